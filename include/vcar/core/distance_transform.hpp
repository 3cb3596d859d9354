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
// Lower envelope of the parabolas (x - q)^2 + f[q] over the q with f[q] >= 0 (f[q] < 0: no
// parabola); writes d[0..n), no_seed where there is none. Exact in integers: parabolas p < q
// meet at s = ((f[q] + q^2) - (f[p] + p^2)) / (2 (q - p)), kept as that fraction.
struct Crossing {
  std::int64_t num = 0, den = 0;  // den > 0; den 0: -inf (num < 0) or +inf (num > 0)
  bool below(std::int64_t x) const { return den == 0 ? num < 0 : num < x * den; }  // s < x
};
inline void distance_1d(const std::int64_t* f, int n, double* d, std::vector<int>& v, std::vector<Crossing>& z) {
  v.resize(static_cast<std::size_t>(n));
  z.resize(static_cast<std::size_t>(n) + 1);
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const std::int64_t fq = f[q];
    if (fq < 0) continue;
    Crossing s{-1, 0};
    while (k >= 0) {
      const int p = v[static_cast<std::size_t>(k)];
      s = {(fq + std::int64_t{q} * q) - (f[p] + std::int64_t{p} * p), 2 * std::int64_t{q - p}};
      const Crossing& zk = z[static_cast<std::size_t>(k)];
      if (zk.den == 0 || s.num * zk.den > zk.num * s.den) break;  // s > z[k] (z[k] = -inf: always)
      --k;
    }
    if (k < 0) s = {-1, 0};
    ++k;
    v[static_cast<std::size_t>(k)] = q;
    z[static_cast<std::size_t>(k)] = s;
    z[static_cast<std::size_t>(k) + 1] = {1, 0};
  }
  if (k < 0) {
    for (int q = 0; q < n; ++q) d[q] = no_seed;
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[static_cast<std::size_t>(j) + 1].below(q)) ++j;
    const int p = v[static_cast<std::size_t>(j)];
    d[q] = static_cast<double>(std::int64_t{q - p} * (q - p) + f[p]);
  }
}
}  // namespace detail

// seed[y * width + x] != 0 marks a seed; returns squared distances (no_seed when there is none).
// An image without pixels (width or height 0) gives an empty result.
// Columns first: with 0/1 seeds a column's lower envelope is the squared distance to the
// column's nearest seed, two scans down and up the rows (whole rows at a time); then each row's
// envelope (distance_1d, in integers) over those values.
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
  std::vector<double> out(seed.size());
  constexpr std::int64_t rows_per_task = 16;
  parallel_chunks(height, rows_per_task, [&](std::int64_t, std::int64_t y0, std::int64_t y1) {
    std::vector<std::int64_t> f(W);
    std::vector<int> v;
    std::vector<detail::Crossing> z;
    for (std::int64_t y = y0; y < y1; ++y) {
      const std::int32_t* column = up.data() + static_cast<std::size_t>(y) * W;
      for (std::size_t x = 0; x < W; ++x) f[x] = column[x] == none ? -1 : std::int64_t{column[x]} * column[x];
      detail::distance_1d(f.data(), width, out.data() + static_cast<std::size_t>(y) * W, v, z);
    }
  });
  return out;
}

}  // namespace vcar
