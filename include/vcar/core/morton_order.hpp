#pragma once
// Points ordered along a Morton (Z-order) curve: neighbours in the order are neighbours in
// space, so a run of consecutive points has a small bounding box and projects to a small image
// region. Voting and ABR process their candidates in this order.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace vcar {

// The order (positions 0..n-1) of the points (x[k], y[k], z[k]) sorted by the Morton code of
// their position in the points' bounding box, 10 bits per axis; ties keep their position order,
// so the order is deterministic. Non-finite coordinates count as the box's low corner.
inline std::vector<std::uint32_t> morton_order(const float* x, const float* y, const float* z, std::size_t n) {
  const float* c[3] = {x, y, z};
  std::array<float, 3> lo{}, hi{};
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::numeric_limits<float>::max();
    hi[d] = -lo[d];
    for (std::size_t k = 0; k < n; ++k) {
      lo[d] = std::min(lo[d], c[d][k]);  // NaN compares false: ignored
      hi[d] = std::max(hi[d], c[d][k]);
    }
  }
  auto spread = [](std::uint32_t v) {  // 10 bits -> every third bit
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
  };
  // Keys (code << 32 | position): sorting them by their upper 30 bits keeps ties in position order.
  std::vector<std::uint64_t> key(n), tmp(n);
  for (std::size_t k = 0; k < n; ++k) {
    std::uint32_t m = 0;
    for (int d = 0; d < 3; ++d) {
      const float ext = hi[d] - lo[d];
      const float t = ext > 0.f ? (c[d][k] - lo[d]) / ext * 1024.f : 0.f;
      const float q = t >= 0.f ? std::min(1023.f, t) : 0.f;  // NaN -> 0
      m |= spread(static_cast<std::uint32_t>(q)) << d;
    }
    key[k] = (static_cast<std::uint64_t>(m) << 32) | k;
  }
  // LSD radix sort on the code, 3 stable passes of 10 bits.
  for (int pass = 0; pass < 3; ++pass) {
    const int shift = 32 + 10 * pass;
    std::array<std::size_t, 1025> start{};
    for (std::size_t k = 0; k < n; ++k) ++start[((key[k] >> shift) & 1023u) + 1];
    for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    for (std::size_t k = 0; k < n; ++k) tmp[start[(key[k] >> shift) & 1023u]++] = key[k];
    key.swap(tmp);
  }
  std::vector<std::uint32_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = static_cast<std::uint32_t>(key[k]);
  return order;
}

}  // namespace vcar
