#pragma once
// Points ordered along a Morton (Z-order) curve: neighbours in the order are neighbours in
// space, so a run of consecutive points has a small bounding box and projects to a small image
// region. Voting and ABR process their candidates in this order.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/radix_sort.hpp"
#include "vcar/core/scratch_vector.hpp"
#include "vcar/core/simd.hpp"

namespace vcar {

// The order (positions 0..n-1) of the points (x[k], y[k], z[k]) sorted by the Morton code of
// their position in the points' bounding box, 10 bits per axis; ties keep their position order,
// so the order is deterministic. Non-finite coordinates count as the box's low corner.
// `bits` < 30 sorts by the code's top `bits` bits only (one radix pass per 10 bits): the points
// of one cell of that coarser grid keep their position order. Voting, which only needs runs of
// 256 points to be compact, sorts its million means by 20 bits (cells of about 1/100 of the box
// per axis), two passes instead of three.
inline scratch_vector<std::uint32_t> morton_order(const float* x, const float* y, const float* z, std::size_t n,
                                                  int bits = 30) {
  if (bits < 1 || bits > 30) throw Error("bits must be in 1..30, got " + std::to_string(bits), "morton_order");
  // Fixed blocks of points (not of threads): every step below gives the same result for any
  // thread count. Each block finds its bounds and computes its keys; the sort is blocked too.
  constexpr std::size_t block = std::size_t{1} << 16;
  const auto blocks = static_cast<std::int64_t>((n + block - 1) / block);
  auto range = [&](std::int64_t b) {
    return std::pair{static_cast<std::size_t>(b) * block, std::min(n, static_cast<std::size_t>(b + 1) * block)};
  };
  const float* c[3] = {x, y, z};
  std::vector<std::array<float, 6>> bounds(static_cast<std::size_t>(blocks));
  parallel_for(blocks, [&](std::int64_t b) {
    const auto [k0, k1] = range(b);
    for (int d = 0; d < 3; ++d) {
      float lo = std::numeric_limits<float>::max(), hi = -lo;
      for (std::size_t k = k0; k < k1; ++k) {
        lo = std::min(lo, c[d][k]);  // NaN compares false: ignored
        hi = std::max(hi, c[d][k]);
      }
      bounds[static_cast<std::size_t>(b)][d] = lo;
      bounds[static_cast<std::size_t>(b)][3 + d] = hi;
    }
  });
  std::array<float, 3> lo{}, hi{};
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::numeric_limits<float>::max();
    hi[d] = -lo[d];
    for (const auto& bb : bounds) lo[d] = std::min(lo[d], bb[d]), hi[d] = std::max(hi[d], bb[3 + d]);
  }
  auto spread = [](auto v) {  // 10 bits -> every third bit (uint32_t, or int32 SIMD lanes)
    using V = decltype(v);
    v = (v | (v << 16)) & V(0x030000FF);
    v = (v | (v << 8)) & V(0x0300F00F);
    v = (v | (v << 4)) & V(0x030C30C3);
    v = (v | (v << 2)) & V(0x09249249);
    return v;
  };
  // Keys (code's top `bits` << 32 | position): a stable sort by their upper word keeps ties in
  // position order.
  const int drop = 30 - bits;
  scratch_vector<std::uint64_t> key(n), tmp;  // written whole below (not zeroed first)
  parallel_for(blocks, [&](std::int64_t b) {
    const auto [k0, k1] = range(b);
    std::size_t k = k0;
    // simd::width points at a time, each lane with the scalar tail's arithmetic (a correctly
    // rounded division, the same clamp and truncation): the same codes.
    using BF = simd::batch<float>;
    using BI = simd::batch<std::int32_t>;
    constexpr std::size_t L = simd::width;
    alignas(64) std::int32_t codes[L];
    for (; k + L <= k1; k += L) {
      BI m(0);
      for (int d = 0; d < 3; ++d) {
        const float ext = hi[d] - lo[d];
        const BF t = ext > 0.f ? (BF::load_unaligned(c[d] + k) - BF(lo[d])) / BF(ext) * BF(1024.f) : BF(0.f);
        const BF q = simd::select(t >= BF(0.f), simd::min(BF(1023.f), t), BF(0.f));  // NaN -> 0
        m = m | (spread(simd::to_int(q)) << d);
      }
      m.store_aligned(codes);
      for (std::size_t l = 0; l < L; ++l)
        key[k + l] = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(codes[l]) >> drop) << 32) | (k + l);
    }
    for (; k < k1; ++k) {
      std::uint32_t m = 0;
      for (int d = 0; d < 3; ++d) {
        const float ext = hi[d] - lo[d];
        const float t = ext > 0.f ? (c[d][k] - lo[d]) / ext * 1024.f : 0.f;
        const float q = t >= 0.f ? std::min(1023.f, t) : 0.f;  // NaN -> 0
        m |= spread(static_cast<std::uint32_t>(q)) << d;
      }
      key[k] = (static_cast<std::uint64_t>(m >> drop) << 32) | k;
    }
  });
  sort_by_upper_word(key, tmp, (1u << bits) - 1);  // stable by the code's top bits
  scratch_vector<std::uint32_t> order(n);
  parallel_for(blocks, [&](std::int64_t b) {
    const auto [k0, k1] = range(b);
    for (std::size_t k = k0; k < k1; ++k) order[k] = static_cast<std::uint32_t>(key[k]);
  });
  return order;
}

}  // namespace vcar
