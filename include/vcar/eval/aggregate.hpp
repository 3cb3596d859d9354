#pragma once
// One (object, view) evaluation with every metric of conventions §6, and the two levels of
// aggregation: mean over the views of a scene, then mean over scenes (both are reported).
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "vcar/core/image.hpp"
#include "vcar/eval/boundary_metrics.hpp"
#include "vcar/eval/mask_metrics.hpp"

namespace vcar::eval {

struct ViewMetrics {
  double iou = 0, accuracy = 0, boundary_iou = 0, boundary_f1 = 0, trimap_iou = 0;
};

// All metrics of one predicted mask against its GT; d <= 0 picks the default band width.
inline ViewMetrics evaluate_mask(const Mask& pred, const Mask& gt, int d = 0, const std::string& where = "mask") {
  check_same_size(pred, gt, where);
  if (d <= 0) d = band_width(gt.width, gt.height);
  const Confusion c = confusion(pred, gt, where);
  return {iou(c), pixel_accuracy(c), vcar::eval::boundary_iou(pred, gt, d, where),
          vcar::eval::boundary_f1(pred, gt, d, where).f1, vcar::eval::trimap_iou(pred, gt, d, where)};
}

// The rendered alpha of the selection thresholded at a (conventions §6), then evaluate_mask.
inline ViewMetrics evaluate_alpha(const ImageF& alpha, const Mask& gt, float a = alpha_default, int d = 0,
                                  const std::string& where = "view") {
  return evaluate_mask(predicted_mask(alpha, a), gt, d, where);
}

// Mean of each metric; an empty list gives all zeros.
inline ViewMetrics mean(std::span<const ViewMetrics> v) {
  ViewMetrics m;
  if (v.empty()) return m;
  for (const ViewMetrics& x : v) {
    m.iou += x.iou; m.accuracy += x.accuracy; m.boundary_iou += x.boundary_iou;
    m.boundary_f1 += x.boundary_f1; m.trimap_iou += x.trimap_iou;
  }
  const double n = static_cast<double>(v.size());
  m.iou /= n; m.accuracy /= n; m.boundary_iou /= n; m.boundary_f1 /= n; m.trimap_iou /= n;
  return m;
}

struct Summary {
  std::vector<ViewMetrics> per_scene;  // mean over the views of each scene
  ViewMetrics overall;                 // mean of per_scene (each scene weighs the same)
};

// per_view[s] holds the view metrics of scene s.
inline Summary summarise(const std::vector<std::vector<ViewMetrics>>& per_view) {
  Summary s;
  for (const auto& views : per_view) s.per_scene.push_back(mean(std::span<const ViewMetrics>(views)));
  s.overall = mean(std::span<const ViewMetrics>(s.per_scene));
  return s;
}

}  // namespace vcar::eval
