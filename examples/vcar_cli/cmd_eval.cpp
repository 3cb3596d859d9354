// `vcar eval`: a selection against a synthetic dataset's ground truth (conventions §6).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "evaluation.hpp"
#include "scene_inputs.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/synth/dataset.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

int run_eval(const EvalOptions& o, const GlobalOptions& g) {
  ProgressLine progress(g.quiet);
  const fs::path dir = o.dataset;
  if (!fs::exists(o.selection)) throw CliError(exit_bad_input, "no such file", o.selection + " (--selection)");
  progress.message("reading the dataset");
  const OracleDataset ds = load_oracle_dataset(dir);
  const synth::Rig rig = synth::load_rig(dir);
  const Selection sel = read_selection(o.selection, &ds.world.scene);

  EvalInputs in;
  in.scene = &ds.world.scene;
  in.views = rig.eval;
  in.true_ids = ds.world.gaussians_of(ds.world.target_id);
  in.gt_mask = [&](std::size_t k) {
    const Camera& c = rig.eval[k];
    progress.message("evaluating view " + std::to_string(k + 1) + "/" + std::to_string(rig.eval.size()));
    return io::read_mask(dir / "gt" / "silhouettes" / (c.name + ".png"), c.width, c.height);
  };
  if (in.views.empty()) throw CliError(exit_bad_input, "no held-out views", (dir / "gt" / "eval_cameras.json").string());
  nlohmann::json m = evaluate_selection(in, sel, o.alpha);
  progress.done();
  if (o.json) {
    std::cout << m.dump() << '\n';
    return exit_ok;
  }
  std::printf("%zu held-out views, alpha > %.2f\n", in.views.size(), static_cast<double>(o.alpha));
  std::printf("  mIoU %.4f  mAcc %.4f  boundary IoU %.4f  boundary F1 %.4f  trimap IoU %.4f\n",
              m["mIoU"].get<double>(), m["mAcc"].get<double>(), m["boundary_iou"].get<double>(),
              m["boundary_f1"].get<double>(), m["trimap_iou"].get<double>());
  std::printf("  3D ids: precision %.4f  recall %.4f  F1 %.4f  (%zu selected, %zu true)\n",
              m["precision_3d"].get<double>(), m["recall_3d"].get<double>(), m["f1_3d"].get<double>(),
              sel.indices.size(), in.true_ids.size());
  return exit_ok;
}

}  // namespace vcar::cli
