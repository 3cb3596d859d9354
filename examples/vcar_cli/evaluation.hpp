#pragma once
// The evaluation protocol of conventions §6, shared by `vcar eval` and `vcar demo`: render the
// selection (refined scales) from each held-out view, threshold alpha, compare with the GT mask;
// score the selected ids against the true ids.
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar::cli {

struct EvalInputs {
  const GaussianScene* scene = nullptr;
  std::vector<Camera> views;                        // held-out views
  std::function<Mask(std::size_t)> gt_mask;         // GT of view k (the target alone)
  std::vector<Index> true_ids;                      // the target's Gaussians
};

// {"mIoU", "mAcc", "boundary_iou", "boundary_f1", "trimap_iou", "precision_3d", "recall_3d",
//  "f1_3d", "precision_3d_weighted", "recall_3d_weighted", "f1_3d_weighted", "alpha", "views": [...]}
nlohmann::json evaluate_selection(const EvalInputs& in, const Selection& sel, float alpha);

}  // namespace vcar::cli
