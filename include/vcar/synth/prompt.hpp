#pragma once
// Positive prompt points deep inside a mask (what a user would click): the pixel farthest from
// the background, then points spread out (farthest-point sampling) among pixels at least half
// as deep. Deterministic; points are pixel centres (j + 0.5, i + 0.5).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"
#include "vcar/synth/mask_ops.hpp"

namespace vcar::synth {

inline Prompt prompt_points(const Mask& visible, std::size_t reference_view, int n_points = 3,
                            const std::string& where = "reference view") {
  const std::vector<float> depth2 = squared_distance(visible, false);  // to the nearest background
  float best = 0.f;
  for (std::size_t k = 0; k < depth2.size(); ++k)
    if (visible.data[k] && depth2[k] > best && std::isfinite(depth2[k])) best = depth2[k];
  if (best == 0.f) {  // a mask with no background: any foreground pixel is deep
    for (std::size_t k = 0; k < depth2.size(); ++k) if (visible.data[k]) { best = 1.f; break; }
  }
  if (best == 0.f) throw Error("the target is not visible: no prompt points", where);
  std::vector<std::size_t> candidates;
  for (std::size_t k = 0; k < depth2.size(); ++k)
    if (visible.data[k] && depth2[k] >= 0.25f * best) candidates.push_back(k);  // depth >= half
  Prompt p;
  p.reference_view = reference_view;
  std::vector<float> dmin(candidates.size(), INFINITY);
  std::size_t pick = 0;
  for (std::size_t c = 0; c < candidates.size(); ++c)
    if (depth2[candidates[c]] > depth2[candidates[pick]]) pick = c;
  for (int n = 0; n < n_points && n < static_cast<int>(candidates.size()); ++n) {
    const std::size_t k = candidates[pick];
    const float x = static_cast<float>(k % visible.width) + 0.5f, y = static_cast<float>(k / visible.width) + 0.5f;
    p.points.emplace_back(x, y);
    p.point_labels.push_back(1);
    std::size_t next = 0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const float dx = static_cast<float>(candidates[c] % visible.width) + 0.5f - x;
      const float dy = static_cast<float>(candidates[c] / visible.width) + 0.5f - y;
      dmin[c] = std::min(dmin[c], dx * dx + dy * dy);
      if (dmin[c] > dmin[next]) next = c;
    }
    pick = next;
  }
  return p;
}

// The box around a mask's foreground, [x0, y0, x1, y1] in pixel edges (the pixels j0..j1 span
// [j0, j1 + 1)): what a user would drag around the visible object. Throws when the mask is empty.
inline Eigen::Vector4f mask_box(const Mask& m, const std::string& where = "mask") {
  int x0 = m.width, y0 = m.height, x1 = -1, y1 = -1;
  for (int i = 0; i < m.height; ++i)
    for (int j = 0; j < m.width; ++j)
      if (m.data[static_cast<std::size_t>(i) * m.width + j]) {
        x0 = std::min(x0, j); x1 = std::max(x1, j);
        y0 = std::min(y0, i); y1 = std::max(y1, i);
      }
  if (x1 < 0) throw Error("the mask is empty: no box", where);
  return {static_cast<float>(x0), static_cast<float>(y0), static_cast<float>(x1 + 1), static_cast<float>(y1 + 1)};
}

}  // namespace vcar::synth
