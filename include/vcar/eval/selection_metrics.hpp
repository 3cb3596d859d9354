#pragma once
// 3D metrics of a selection of Gaussians against the true set (the target's ids): precision,
// recall and F1 per Gaussian, and an opacity-weighted variant where Gaussian i weighs
//   w_i = opacity_i * s_a * s_b,   s_a >= s_b the two largest of its three scales,
// i.e. opacity times the area of its largest cross-section: what a viewer can actually see of
// it (a flat splat counts by its disc, a needle by little, a transparent one by little).
// Conventions for empty sets: precision = 1 when nothing is selected, recall = 1 when nothing is
// true; F1 = 2PR/(P+R), 0 when P+R = 0. Both empty -> 1, 1, 1.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace vcar::eval {

struct SelectionScores {
  double tp = 0, fp = 0, fn = 0;  // counts, or weight sums for the weighted variant
  double precision = 1, recall = 1, f1 = 1;
};

namespace detail {
inline std::vector<std::uint8_t> membership(const std::vector<Index>& ids, std::size_t n, const char* what) {
  std::vector<std::uint8_t> in(n, 0);
  for (Index i : ids) {
    if (i >= n) throw Error("index " + std::to_string(i) + " out of range (" + std::to_string(n) + " Gaussians)", what);
    in[i] = 1;
  }
  return in;
}
inline SelectionScores finish(SelectionScores s) {
  s.precision = s.tp + s.fp > 0 ? s.tp / (s.tp + s.fp) : 1.0;
  s.recall = s.tp + s.fn > 0 ? s.tp / (s.tp + s.fn) : 1.0;
  s.f1 = s.precision + s.recall > 0 ? 2 * s.precision * s.recall / (s.precision + s.recall) : 0.0;
  return s;
}
}  // namespace detail

// Weighted scores over a scene of n Gaussians; weight empty = every Gaussian weighs 1.
// Duplicate indices count once. Throws vcar::Error for an index >= n.
inline SelectionScores selection_scores(const std::vector<Index>& selected, const std::vector<Index>& truth,
                                        std::size_t n, const std::vector<double>& weight = {}) {
  if (!weight.empty() && weight.size() != n) throw Error("weight count differs from the scene", "selection_scores");
  const std::vector<std::uint8_t> s = detail::membership(selected, n, "selection"),
                                  t = detail::membership(truth, n, "true ids");
  SelectionScores r;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weight.empty() ? 1.0 : weight[i];
    if (s[i] && t[i]) r.tp += w;
    else if (s[i]) r.fp += w;
    else if (t[i]) r.fn += w;
  }
  return detail::finish(r);
}

// w_i = opacity_i * s_a * s_b (the two largest scales), see the header comment.
inline std::vector<double> visible_area_weight(const GaussianScene& scene) {
  std::vector<double> w(scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    float l[3] = {scene.log_scale[0][i], scene.log_scale[1][i], scene.log_scale[2][i]};
    std::sort(l, l + 3);
    w[i] = double(scene.opacity(i)) * std::exp(double(l[1]) + double(l[2]));
  }
  return w;
}

inline SelectionScores weighted_selection_scores(const std::vector<Index>& selected, const std::vector<Index>& truth,
                                                 const GaussianScene& scene) {
  return selection_scores(selected, truth, scene.size(), visible_area_weight(scene));
}

}  // namespace vcar::eval
