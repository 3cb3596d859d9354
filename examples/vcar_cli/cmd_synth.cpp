// `vcar synth`: a synthetic dataset directory (synth/dataset.hpp) from a seed: the generated
// world of primitives, or with --stage, real trained objects on a floor (synth/stage.hpp).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/stage_json.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::cli {

namespace {

// A stage file's world, its rig settings overridden by the command line's.
int run_synth_stage(const SynthOptions& o, ProgressLine& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  progress.message("reading the stage");
  synth::StageFile sf = synth::read_stage_file(o.stage);
  if (!o.target.empty()) {
    bool found = false;
    for (const auto& ob : sf.stage.objects) found = found || ob.name == o.target;
    if (!found) throw CliError(exit_usage, "the stage has no object named '" + o.target + "'", "--target");
    sf.stage.target = o.target;
  }
  progress.message("placing " + std::to_string(sf.stage.objects.size()) + " objects");
  const synth::World world = synth::make_stage(sf.stage, o.seed);

  synth::RigParams rp;
  const int width = o.width > 0 ? o.width : sf.width, height = o.width > 0 ? o.height : sf.height;
  if (width > 0) rp.intrinsics = synth::make_intrinsics(width, height);
  rp.n_train = o.views > 0 ? o.views : sf.views;
  rp.seed = o.seed;
  rp.fill = synth::stage_rig_fill;
  const std::string rig_name = !o.rig.empty() ? o.rig : !sf.rig.empty() ? sf.rig : "forward";
  const synth::Rig rig = synth::make_rig(rig_name == "360" ? "orbit" : rig_name, world, rp);

  synth::ExportOptions opt;
  std::string target_name;
  for (std::size_t k = 0; k < sf.stage.objects.size(); ++k) {
    const int id = world.inserted[k].object_id;
    opt.objects.push_back({sf.stage.objects[k].name, id});
    if (id == world.target_id) target_name = sf.stage.objects[k].name;
  }
  make_output_dir(o.out);
  progress.message("writing " + std::to_string(rig.train.size()) + " training and " +
                   std::to_string(rig.eval.size()) + " held-out views");
  cpu::TiledRenderer renderer;
  std::vector<synth::PromptedObject> prompts;
  try {
    prompts = synth::export_dataset(o.out, world, rig, renderer, opt);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
  progress.done();
  for (const auto& p : prompts)
    if (!p.visible) std::fprintf(stderr, "vcar: warning: no training view shows '%s': it has no prompt\n", p.name.c_str());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("wrote %s: %zu Gaussians (floor %zu", o.out.c_str(), world.scene.size(), world.gaussians_of(0).size());
  for (std::size_t k = 0; k < opt.objects.size(); ++k)
    std::printf(", %s %zu", opt.objects[k].name.c_str(), world.inserted[k].count);
  std::printf("), target '%s', rig %s, %zu training views (%dx%d), %zu held out, prompt on '%s', %.1f s\n",
              target_name.c_str(), rig.kind.c_str(), rig.train.size(), rig.train.front().width,
              rig.train.front().height, rig.eval.size(), rig.train[rig.reference].name.c_str(), seconds);
  return exit_ok;
}

}  // namespace

int run_synth(const SynthOptions& o, const GlobalOptions& g) {
  ProgressLine progress(g.quiet);
  if ((o.width > 0) != (o.height > 0))
    throw CliError(exit_usage, "give both --width and --height, or neither", "--width/--height");
  if (!o.stage.empty()) return run_synth_stage(o, progress);
  make_output_dir(o.out);

  progress.message("generating the world");
  synth::WorldParams wp;
  wp.seed = o.seed;
  wp.n_gaussians = o.gaussians;
  const synth::World world = synth::generate_world(wp);

  synth::RigParams rp;
  if (o.width > 0) rp.intrinsics = synth::make_intrinsics(o.width, o.height);
  rp.n_train = o.views;
  rp.seed = o.seed;
  const std::string rig_name = o.rig.empty() ? "forward" : o.rig;
  const std::string kind = rig_name == "360" ? "orbit" : rig_name;  // the CLI's name for the orbit rig
  const synth::Rig rig = synth::make_rig(kind, world, rp);

  progress.message("writing " + std::to_string(rig.train.size()) + " training and " +
                   std::to_string(rig.eval.size()) + " held-out views");
  cpu::TiledRenderer renderer;
  try {
    synth::export_dataset(o.out, world, rig, renderer);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
  progress.done();
  std::printf("wrote %s: %zu Gaussians (target: %zu), rig %s, %zu training views (%dx%d), %zu held out, "
              "prompt on '%s'\n", o.out.c_str(), world.scene.size(), world.gaussians_of(world.target_id).size(),
              rig_name.c_str(), rig.train.size(), rig.train.front().width, rig.train.front().height,
              rig.eval.size(), rig.train[rig.reference].name.c_str());
  return exit_ok;
}

}  // namespace vcar::cli
