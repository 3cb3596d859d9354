#pragma once
// Mask operations behind the oracle's failure models: exact Euclidean dilation and erosion
// (disc structuring element, via core/distance_transform.hpp), integer shifts and painted discs.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "vcar/core/distance_transform.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::synth {

// Squared Euclidean distance (pixel centres) from every pixel to the nearest pixel where
// (mask != 0) == `to_foreground`; infinity when there is none.
inline std::vector<float> squared_distance(const Mask& m, bool to_foreground) {
  std::vector<std::uint8_t> seed(m.data.size());
  for (std::size_t k = 0; k < seed.size(); ++k) seed[k] = (m.data[k] != 0) == to_foreground;
  const std::vector<double> d2 = squared_distance_to(seed, m.width, m.height);  // core
  return std::vector<float>(d2.begin(), d2.end());  // integers (or infinity): exact in float
}

// Dilation (k > 0) or erosion (k < 0) by a Euclidean disc of radius |k| px: a pixel joins when
// a foreground pixel lies within |k|; it leaves when a background pixel lies within |k|.
// Outside the image counts as neither (objects cut by the border do not erode from it).
inline Mask dilate_erode(const Mask& m, int k) {
  if (k == 0) return m;
  const float k2 = static_cast<float>(k) * static_cast<float>(k);
  const std::vector<float> d2 = squared_distance(m, k > 0);
  Mask out(m.width, m.height, 1);
  for (std::size_t i = 0; i < d2.size(); ++i)
    out.data[i] = (k > 0 ? d2[i] <= k2 : (m.data[i] != 0 && d2[i] > k2)) ? 255 : 0;
  return out;
}

// out(x, y) = m(x - dx, y - dy); pixels shifted in from outside are background.
inline Mask shift(const Mask& m, int dx, int dy) {
  Mask out(m.width, m.height, 1);
  for (int y = 0; y < m.height; ++y) {
    const int sy = y - dy;
    if (sy < 0 || sy >= m.height) continue;
    for (int x = 0; x < m.width; ++x) {
      const int sx = x - dx;
      if (sx >= 0 && sx < m.width) out(x, y) = m(sx, sy);
    }
  }
  return out;
}

// Paints the disc of pixels whose centres lie within r of (cx, cy).
inline void paint_disc(Mask& m, float cx, float cy, float r) {
  const int y0 = std::max(0, static_cast<int>(std::floor(cy - r))), y1 = std::min(m.height - 1, static_cast<int>(std::ceil(cy + r)));
  const int x0 = std::max(0, static_cast<int>(std::floor(cx - r))), x1 = std::min(m.width - 1, static_cast<int>(std::ceil(cx + r)));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const float dx = x + 0.5f - cx, dy = y + 0.5f - cy;
      if (dx * dx + dy * dy <= r * r) m(x, y) = 255;
    }
}

inline std::size_t count(const Mask& m) {
  std::size_t n = 0;
  for (auto v : m.data) n += v != 0;
  return n;
}

}  // namespace vcar::synth
