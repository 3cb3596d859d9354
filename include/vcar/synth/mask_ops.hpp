#pragma once
// Mask operations behind the oracle's failure models: exact Euclidean dilation and erosion
// (disc structuring element, via the squared distance transform of Felzenszwalb and
// Huttenlocher 2012), integer shifts and painted discs.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::synth {

namespace detail {
// 1D squared distance transform of f (size n) into d, with scratch v, z (lower envelope).
inline void edt_1d(const float* f, float* d, int n, int* v, float* z) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  int k = 0;
  v[0] = 0; z[0] = -inf; z[1] = inf;
  for (int q = 1; q < n; ++q) {
    if (f[q] == inf) continue;
    if (f[v[k]] == inf) { v[k] = q; continue; }  // envelope so far is empty
    float s;
    while (true) {
      s = ((f[q] + static_cast<float>(q) * q) - (f[v[k]] + static_cast<float>(v[k]) * v[k])) / (2.f * (q - v[k]));
      if (s <= z[k] && k > 0) { --k; continue; }
      break;
    }
    ++k; v[k] = q; z[k] = s; z[k + 1] = inf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < static_cast<float>(q)) ++k;
    const float dq = static_cast<float>(q - v[k]);
    d[q] = f[v[k]] == inf ? inf : dq * dq + f[v[k]];
  }
}
}  // namespace detail

// Squared Euclidean distance (pixel centres) from every pixel to the nearest pixel where
// (mask != 0) == `to_foreground`; infinity when there is none.
inline std::vector<float> squared_distance(const Mask& m, bool to_foreground) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  const int W = m.width, H = m.height;
  std::vector<float> g(static_cast<std::size_t>(W) * H);
  for (std::size_t k = 0; k < g.size(); ++k) g[k] = ((m.data[k] != 0) == to_foreground) ? 0.f : inf;
  parallel_for(W, [&](std::int64_t x) {  // columns
    std::vector<float> f(H), d(H), z(H + 1);
    std::vector<int> v(H);
    for (int y = 0; y < H; ++y) f[y] = g[static_cast<std::size_t>(y) * W + x];
    detail::edt_1d(f.data(), d.data(), H, v.data(), z.data());
    for (int y = 0; y < H; ++y) g[static_cast<std::size_t>(y) * W + x] = d[y];
  });
  parallel_for(H, [&](std::int64_t y) {  // rows
    std::vector<float> f(W), z(W + 1);
    std::vector<int> v(W);
    float* row = g.data() + static_cast<std::size_t>(y) * W;
    std::copy(row, row + W, f.begin());
    detail::edt_1d(f.data(), row, W, v.data(), z.data());
  });
  return g;
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
