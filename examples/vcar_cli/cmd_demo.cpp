// `vcar demo`: the built-in synthetic scene, segmented with the oracle, evaluated, rendered.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "evaluation.hpp"
#include "mask_tally.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

namespace {
// The demo scene: small enough for seconds on two cores, large enough to show every stage.
constexpr std::uint64_t demo_seed = 1;
constexpr std::size_t demo_gaussians = 30000;
}  // namespace

int run_demo(const DemoOptions& o, const GlobalOptions& g) {
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine progress(g.quiet);
  const fs::path out = o.out;
  make_output_dir(out);

  progress.message("generating the synthetic scene");
  synth::WorldParams wp;
  wp.seed = demo_seed;
  wp.n_gaussians = demo_gaussians;
  const synth::World world = synth::generate_world(wp);
  // Forward-facing capture: the back of the target is never seen, so SSS has work to do.
  const synth::Rig rig = synth::make_rig("forward", world);

  Prompt prompt;
  prompt.reference_view = rig.reference;
  const VcarParams params = VcarParams::robust();  // the library's default preset (docs/robust.md)
  cpu::TiledRenderer renderer;
  synth::OracleSegmenter oracle(world, {}, renderer);
  TallySegmenter tally(oracle, rig.train);
  const SegmentationResult result =
      segment(world.scene, rig.train, prompt, renderer, tally, params, progress.callback());
  MaskCounts counts;
  if (const RoundTally* t = tally.used()) counts = {t->training, t->training_missing, t->sampled, t->sampled_missing};

  progress.message("writing results");
  nlohmann::json inputs = {{"scene", "built-in synthetic world"}, {"seed", demo_seed},
                           {"gaussians", demo_gaussians}, {"rig", rig.kind},
                           {"training_views", rig.train.size()}, {"heldout_views", rig.eval.size()},
                           {"prompt_view", rig.train[rig.reference].name}, {"segmenter", "oracle"},
                           {"preset", "robust"}};
  nlohmann::json report = write_segmentation(out, world.scene, result, params, inputs);

  progress.message("evaluating on the held-out views");
  Selection sel;
  sel.indices = result.indices;
  sel.scores = result.scores;
  sel.log_scale = result.log_scale;
  EvalInputs ev;
  ev.scene = &world.scene;
  ev.views = rig.eval;
  ev.gt_mask = [&](std::size_t k) { return synth::silhouette_mask(world, rig.eval[k], world.target_id, renderer); };
  ev.true_ids = world.gaussians_of(world.target_id);
  const nlohmann::json metrics = evaluate_selection(ev, sel, 0.5f);
  report["metrics"] = metrics;
  report["metrics_alpha_0.1"] = evaluate_selection(ev, sel, 0.1f);

  // Before / after renders from the first held-out view.
  progress.message("rendering before/after");
  const Camera& view = rig.eval.front();
  std::vector<Index> rest;
  for (std::size_t i = 0, k = 0; i < world.scene.size(); ++i) {
    if (k < sel.indices.size() && sel.indices[k] == i) { ++k; continue; }
    rest.push_back(static_cast<Index>(i));
  }
  auto render_to = [&](const fs::path& file, const std::vector<Index>* subset, const LogScales* ls) {
    RenderRequest q;
    q.scene = &world.scene;
    q.camera = &view;
    q.subset = subset;
    q.log_scale = ls;
    try {
      io::write_png(file, renderer.render(q).rgb);
    } catch (const Error& e) {
      throw CliError(exit_output, e.what());
    }
  };
  render_to(out / "before.png", nullptr, nullptr);
  render_to(out / "after_object.png", &sel.indices, sel.has_log_scales() ? &sel.log_scale : nullptr);
  render_to(out / "after_removed.png", &rest, nullptr);
  // The scene as an ordinary dataset, so `segment --oracle` and `eval` can be tried on it.
  progress.message("writing the dataset");
  try {
    synth::export_dataset(out / "dataset", world, rig, renderer);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report["demo_seconds"] = total_s;
  report["peak_rss_mib"] = peak_rss_mib();
  report["outputs"]["before"] = "before.png";
  report["outputs"]["after_object"] = "after_object.png";
  report["outputs"]["after_removed"] = "after_removed.png";
  report["outputs"]["dataset"] = "dataset";
  report["masks"] = mask_counts_json(counts);
  write_json(out / "report.json", report);
  progress.done();

  std::printf("vcar demo: synthetic scene (seed %llu), %zu Gaussians, %s capture: %zu training views, "
              "%zu held out\n", static_cast<unsigned long long>(demo_seed), world.scene.size(),
              rig.kind.c_str(), rig.train.size(), rig.eval.size());
  std::printf("prompt    view '%s'; masks from the oracle (exact ground truth); target: %zu Gaussians in truth\n",
              rig.train[rig.reference].name.c_str(), ev.true_ids.size());
  std::fputs(summary_text(result.diagnostics, params, world.scene.size(), &counts, total_s, false).c_str(), stdout);
  std::printf("held out  alpha > 0.5: mIoU %.3f  mAcc %.3f  boundary IoU %.3f  boundary F1 %.3f\n",
              metrics["mIoU"].get<double>(), metrics["mAcc"].get<double>(),
              metrics["boundary_iou"].get<double>(), metrics["boundary_f1"].get<double>());
  std::printf("3D ids    precision %.3f  recall %.3f  F1 %.3f\n", metrics["precision_3d"].get<double>(),
              metrics["recall_3d"].get<double>(), metrics["f1_3d"].get<double>());
  std::printf("wrote     %s/{object.ply, removed.ply, selection.json, report.json, before.png, "
              "after_object.png, after_removed.png, dataset/}\n", out.string().c_str());
  return exit_ok;
}

}  // namespace vcar::cli
