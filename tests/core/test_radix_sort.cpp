#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <vector>

#include "vcar/core/radix_sort.hpp"

TEST_CASE("sort_by_upper_word equals a stable sort by the upper 32 bits") {
  std::mt19937_64 rng(3);
  for (std::uint32_t largest : {0u, 1u, 2047u, 2048u, 4194303u, 4194304u, 0xffffffffu}) {
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{5000}, std::size_t{150000}}) {  // 150000: three blocks
      std::vector<std::uint64_t> v(n);
      for (std::size_t k = 0; k < n; ++k) {  // keys in [0, largest] with repeats; payload = position
        const std::uint64_t key = largest ? rng() % (std::uint64_t{largest} + 1) : 0;
        v[k] = (k % 7 == 0 ? std::uint64_t{largest} : key) << 32 | k;
      }
      std::vector<std::uint64_t> want = v, tmp;
      std::stable_sort(want.begin(), want.end(), [](std::uint64_t a, std::uint64_t b) { return (a >> 32) < (b >> 32); });
      vcar::sort_by_upper_word(v, tmp, largest);
      CHECK(v == want);
    }
  }
}
