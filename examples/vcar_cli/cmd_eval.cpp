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
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/ground_truth.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

int run_eval(const EvalOptions& o, const GlobalOptions& g) {
  ProgressLine progress(g.quiet);
  const fs::path dir = o.dataset;
  if (!fs::exists(o.selection)) throw CliError(exit_bad_input, "no such file", o.selection + " (--selection)");
  progress.message("reading the dataset");
  const OracleDataset ds = load_oracle_dataset(dir);
  const synth::Rig rig = synth::load_rig(dir);
  const std::vector<ObjectSelection> objs = read_object_selections(o.selection, &ds.world.scene);
  if (rig.eval.empty()) throw CliError(exit_bad_input, "no held-out views", (dir / "gt" / "eval_cameras.json").string());

  // Each object against its own ground truth: the world's target has its silhouettes on disk,
  // another object's are ray-cast (synth/ground_truth.hpp).
  cpu::TiledRenderer renderer;
  auto score = [&](const Selection& sel, int id) {
    EvalInputs in;
    in.scene = &ds.world.scene;
    in.views = rig.eval;
    in.true_ids = ds.world.gaussians_of(id);
    in.gt_mask = [&](std::size_t k) {
      const Camera& c = rig.eval[k];
      progress.message("evaluating view " + std::to_string(k + 1) + "/" + std::to_string(rig.eval.size()));
      if (id == ds.world.target_id) return io::read_mask(dir / "gt" / "silhouettes" / (c.name + ".png"), c.width, c.height);
      return synth::silhouette_mask(ds.world, c, id, renderer);
    };
    nlohmann::json m = evaluate_selection(in, sel, o.alpha);
    m["true"] = in.true_ids.size();
    return m;
  };
  auto print = [&](const nlohmann::json& m, std::size_t selected) {
    std::printf("  mIoU %.4f  mAcc %.4f  boundary IoU %.4f  boundary F1 %.4f  trimap IoU %.4f\n",
                m["mIoU"].get<double>(), m["mAcc"].get<double>(), m["boundary_iou"].get<double>(),
                m["boundary_f1"].get<double>(), m["trimap_iou"].get<double>());
    std::printf("  3D ids: precision %.4f  recall %.4f  F1 %.4f  (%zu selected, %zu true)\n",
                m["precision_3d"].get<double>(), m["recall_3d"].get<double>(), m["f1_3d"].get<double>(),
                selected, m["true"].get<std::size_t>());
  };
  if (objs.size() == 1 && objs[0].name.empty()) {  // one selection: the dataset's target
    const nlohmann::json m = score(objs[0].selection, ds.world.target_id);
    progress.done();
    if (o.json) {
      std::cout << m.dump() << '\n';
      return exit_ok;
    }
    std::printf("%zu held-out views, alpha > %.2f\n", rig.eval.size(), static_cast<double>(o.alpha));
    print(m, objs[0].selection.indices.size());
    return exit_ok;
  }
  nlohmann::json all = nlohmann::json::array();
  for (const ObjectSelection& ob : objs) {
    if (ob.object_id < 0)
      throw CliError(exit_bad_input, "object '" + ob.name + "' has no \"object_id\": it cannot be scored against the dataset", o.selection);
    nlohmann::json m = score(ob.selection, ob.object_id);
    m["name"] = ob.name;
    m["object_id"] = ob.object_id;
    all.push_back(std::move(m));
  }
  progress.done();
  if (o.json) {
    std::cout << nlohmann::json{{"objects", all}}.dump() << '\n';
    return exit_ok;
  }
  std::printf("%zu held-out views, alpha > %.2f, %zu objects\n", rig.eval.size(), static_cast<double>(o.alpha), objs.size());
  for (std::size_t k = 0; k < objs.size(); ++k) {
    std::printf("%s (object %d)\n", objs[k].name.c_str(), objs[k].object_id);
    print(all[k], objs[k].selection.indices.size());
  }
  return exit_ok;
}

}  // namespace vcar::cli
