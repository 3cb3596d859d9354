#pragma once
// Exact squared Euclidean distance transform of a binary image (Felzenszwalb & Huttenlocher 2012):
// for every pixel, the squared distance between pixel centres to the nearest seed pixel. Shared by
// the boundary metrics (eval), the robust vote's mask measures (algo: Eq. R6, R11) and the
// oracle's dilation/erosion (synth).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "vcar/core/parallel.hpp"

namespace vcar {

inline constexpr double no_seed = std::numeric_limits<double>::infinity();

namespace detail {  // vcar::detail
// Lower envelope of the parabolas (x - q)^2 + f[q] over the finite f[q]; writes d[0..n).
// Infinite samples add no parabola, so rows or columns without seeds stay infinite.
inline void distance_1d(const double* f, std::ptrdiff_t stride, int n, double* d, std::vector<int>& v,
                        std::vector<double>& z) {
  v.resize(static_cast<std::size_t>(n));
  z.resize(static_cast<std::size_t>(n) + 1);
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const double fq = f[q * stride];
    if (fq == no_seed) continue;
    double s = -no_seed;
    while (k >= 0) {
      const int p = v[static_cast<std::size_t>(k)];
      const double fp = f[p * stride];
      s = ((fq + double(q) * q) - (fp + double(p) * p)) / (2.0 * (q - p));
      if (s > z[static_cast<std::size_t>(k)]) break;
      --k;
    }
    if (k < 0) s = -no_seed;
    ++k;
    v[static_cast<std::size_t>(k)] = q;
    z[static_cast<std::size_t>(k)] = s;
    z[static_cast<std::size_t>(k) + 1] = no_seed;
  }
  if (k < 0) {
    for (int q = 0; q < n; ++q) d[q * stride] = no_seed;
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[static_cast<std::size_t>(j) + 1] < q) ++j;
    const int p = v[static_cast<std::size_t>(j)];
    d[q * stride] = double(q - p) * (q - p) + f[p * stride];
  }
}
}  // namespace detail

// seed[y * width + x] != 0 marks a seed; returns squared distances (no_seed when there is none).
// An image without pixels (width or height 0) gives an empty result.
// Columns first: with 0/1 seeds a column's lower envelope is the squared distance to the
// column's nearest seed, two scans down and up the rows (whole rows at a time); then each row's
// envelope (distance_1d) over those values.
inline std::vector<double> squared_distance_to(const std::vector<std::uint8_t>& seed, int width, int height) {
  if (width <= 0 || height <= 0) return {};
  const std::size_t W = static_cast<std::size_t>(width), H = static_cast<std::size_t>(height);
  constexpr std::int32_t none = std::numeric_limits<std::int32_t>::max();  // no seed in the column (yet)
  std::vector<std::int32_t> up(seed.size());  // rows to the nearest seed above, then either way
  for (std::size_t x = 0; x < W; ++x) up[x] = seed[x] ? 0 : none;
  for (std::size_t y = 1; y < H; ++y) {
    const std::uint8_t* s = seed.data() + y * W;
    const std::int32_t* above = up.data() + (y - 1) * W;
    std::int32_t* row = up.data() + y * W;
    for (std::size_t x = 0; x < W; ++x) row[x] = s[x] ? 0 : (above[x] == none ? none : above[x] + 1);
  }
  for (std::size_t y = H - 1; y-- > 0;) {
    const std::int32_t* below = up.data() + (y + 1) * W;
    std::int32_t* row = up.data() + y * W;
    for (std::size_t x = 0; x < W; ++x)
      if (below[x] != none) row[x] = std::min(row[x], below[x] + 1);
  }
  std::vector<double> g(seed.size()), f(seed.size());
  for (std::size_t k = 0; k < seed.size(); ++k)
    g[k] = up[k] == none ? no_seed : static_cast<double>(up[k]) * static_cast<double>(up[k]);
  constexpr std::int64_t rows_per_task = 16;
  parallel_chunks(height, rows_per_task, [&](std::int64_t, std::int64_t y0, std::int64_t y1) {
    std::vector<int> v;
    std::vector<double> z;
    for (std::int64_t y = y0; y < y1; ++y)
      detail::distance_1d(g.data() + static_cast<std::size_t>(y) * W, 1, width, f.data() + static_cast<std::size_t>(y) * W, v, z);
  });
  return f;
}

}  // namespace vcar
