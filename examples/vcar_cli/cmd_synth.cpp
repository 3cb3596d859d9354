// `vcar synth`: a synthetic dataset directory (synth/dataset.hpp) from a seed.
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::cli {

int run_synth(const SynthOptions& o, const GlobalOptions& g) {
  ProgressLine progress(g.quiet);
  if ((o.width > 0) != (o.height > 0))
    throw CliError(exit_usage, "give both --width and --height, or neither", "--width/--height");
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
  const std::string kind = o.rig == "360" ? "orbit" : o.rig;  // the CLI's name for the orbit rig
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
              o.rig.c_str(), rig.train.size(), rig.train.front().width, rig.train.front().height,
              rig.eval.size(), rig.train[rig.reference].name.c_str());
  return exit_ok;
}

}  // namespace vcar::cli
