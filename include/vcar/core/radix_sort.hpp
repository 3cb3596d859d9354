#pragma once
// A stable LSD radix sort of 64-bit records by their upper 32 bits (a key there, a payload in the
// lower 32), 11 bits a pass and only as many passes as the largest key needs: O(n) for the
// selections that voting returns in scene-index order.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vcar {

// Sorts `v` by v >> 32, stably; every key must be <= `largest`. `tmp` is scratch.
inline void sort_by_upper_word(std::vector<std::uint64_t>& v, std::vector<std::uint64_t>& tmp, std::uint32_t largest) {
  tmp.resize(v.size());
  for (int shift = 32; shift < 64 && (static_cast<std::uint64_t>(largest) << 32) >> shift; shift += 11) {
    std::array<std::size_t, 2049> start{};
    for (std::uint64_t x : v) ++start[((x >> shift) & 2047u) + 1];
    for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    for (std::uint64_t x : v) tmp[start[(x >> shift) & 2047u]++] = x;
    v.swap(tmp);
  }
}

}  // namespace vcar
