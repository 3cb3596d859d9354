#pragma once
// Exact squared Euclidean distance transform of a binary image (Felzenszwalb & Huttenlocher 2012):
// for every pixel, the squared distance between pixel centres to the nearest seed pixel. Shared by
// the boundary metrics (eval), the robust vote's mask measures (algo: Eq. R6, R11) and the
// oracle's dilation/erosion (synth).
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
inline std::vector<double> squared_distance_to(const std::vector<std::uint8_t>& seed, int width, int height) {
  if (width <= 0 || height <= 0) return {};
  const std::size_t W = static_cast<std::size_t>(width);
  std::vector<double> f(seed.size()), g(seed.size());
  for (std::size_t k = 0; k < seed.size(); ++k) f[k] = seed[k] ? 0.0 : no_seed;
  parallel_for(width, [&](std::int64_t x) {  // columns, then rows: the transform is separable
    std::vector<int> v; std::vector<double> z;
    detail::distance_1d(f.data() + x, static_cast<std::ptrdiff_t>(W), height, g.data() + x, v, z);
  });
  parallel_for(height, [&](std::int64_t y) {
    std::vector<int> v; std::vector<double> z;
    detail::distance_1d(g.data() + y * W, 1, width, f.data() + y * W, v, z);
  });
  return f;
}

}  // namespace vcar
