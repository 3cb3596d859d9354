#include "evaluation.hpp"

#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/eval/aggregate.hpp"
#include "vcar/eval/selection_metrics.hpp"

namespace vcar::cli {

nlohmann::json evaluate_selection(const EvalInputs& in, const Selection& sel, float alpha) {
  cpu::TiledRenderer renderer;
  std::vector<eval::ViewMetrics> per_view;
  nlohmann::json views = nlohmann::json::array();
  for (std::size_t k = 0; k < in.views.size(); ++k) {
    const Camera& cam = in.views[k];
    RenderRequest q;
    q.scene = in.scene;
    q.camera = &cam;
    q.subset = &sel.indices;
    q.log_scale = sel.has_log_scales() ? &sel.log_scale : nullptr;
    const Mask gt = in.gt_mask(k);
    const eval::ViewMetrics m = eval::evaluate_alpha(renderer.render(q).alpha, gt, alpha, 0, "view '" + cam.name + "'");
    per_view.push_back(m);
    views.push_back({{"view", cam.name}, {"iou", m.iou}, {"accuracy", m.accuracy},
                     {"boundary_iou", m.boundary_iou}, {"boundary_f1", m.boundary_f1},
                     {"trimap_iou", m.trimap_iou}});
  }
  const eval::ViewMetrics mean = eval::mean(std::span<const eval::ViewMetrics>(per_view));
  const eval::SelectionScores s3 = eval::selection_scores(sel.indices, in.true_ids, in.scene->size());
  const eval::SelectionScores w3 = eval::weighted_selection_scores(sel.indices, in.true_ids, *in.scene);
  return {{"mIoU", mean.iou}, {"mAcc", mean.accuracy}, {"boundary_iou", mean.boundary_iou},
          {"boundary_f1", mean.boundary_f1}, {"trimap_iou", mean.trimap_iou},
          {"precision_3d", s3.precision}, {"recall_3d", s3.recall}, {"f1_3d", s3.f1},
          {"precision_3d_weighted", w3.precision}, {"recall_3d_weighted", w3.recall},
          {"f1_3d_weighted", w3.f1}, {"selected", sel.indices.size()}, {"true", in.true_ids.size()},
          {"alpha", alpha}, {"views", views}};
}

}  // namespace vcar::cli
