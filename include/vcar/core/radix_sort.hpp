#pragma once
// A stable LSD radix sort of 64-bit records by their upper 32 bits (a key there, a payload in the
// lower 32), 10 bits a pass and only as many passes as the largest key needs: the Morton order of
// means (core/morton_order.hpp) and the selections that voting returns in scene-index order.
#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vcar/core/parallel.hpp"

namespace vcar {

// Sorts `v` by v >> 32, stably; every key must be <= `largest`. `tmp` is scratch. In fixed
// blocks of records (not of threads), so the result is the same for any thread count: each
// block counts its digits and scatters its records at offsets taken digit-major, then in block
// order.
// `Vector`: a std::vector of std::uint64_t with any allocator (a scratch_vector's `tmp` is not
// zeroed first).
template <class Vector>
  requires std::same_as<typename Vector::value_type, std::uint64_t>
void sort_by_upper_word(Vector& v, Vector& tmp, std::uint32_t largest) {
  constexpr std::size_t block = std::size_t{1} << 16, digits = 1024;
  const std::size_t n = v.size();
  const auto blocks = static_cast<std::int64_t>((n + block - 1) / block);
  tmp.resize(n);
  std::vector<std::array<std::size_t, digits>> start(static_cast<std::size_t>(blocks));
  for (int shift = 32; shift < 64 && (static_cast<std::uint64_t>(largest) << 32) >> shift; shift += 10) {
    const std::uint64_t* src = v.data();
    std::uint64_t* dst = tmp.data();
    parallel_for(blocks, [&](std::int64_t b) {  // each block's digit counts
      const std::size_t k0 = static_cast<std::size_t>(b) * block, k1 = std::min(n, k0 + block);
      auto& s = start[static_cast<std::size_t>(b)];
      s.fill(0);
      for (std::size_t k = k0; k < k1; ++k) ++s[(src[k] >> shift) & (digits - 1)];
    });
    std::size_t at = 0;
    for (std::size_t digit = 0; digit < digits; ++digit)
      for (auto& s : start) {
        const std::size_t count = s[digit];
        s[digit] = at;
        at += count;
      }
    parallel_for(blocks, [&](std::int64_t b) {
      const std::size_t k0 = static_cast<std::size_t>(b) * block, k1 = std::min(n, k0 + block);
      std::size_t* s = start[static_cast<std::size_t>(b)].data();
      for (std::size_t k = k0; k < k1; ++k) dst[s[(src[k] >> shift) & (digits - 1)]++] = src[k];
    });
    v.swap(tmp);
  }
}

}  // namespace vcar
