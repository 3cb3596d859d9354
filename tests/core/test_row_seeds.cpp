#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "vcar/core/distance_transform.hpp"
#include "vcar/core/row_seeds.hpp"

using vcar::RowSeeds;

TEST_CASE("RowSeeds by hand: two seeds, the nearest by rows outwards, none at all") {
  // 7 x 5: seeds at (1, 0) and (6, 4).
  auto seed = [](int x, int y) { return (x == 1 && y == 0) || (x == 6 && y == 4); };
  const RowSeeds s(7, 5, seed);
  CHECK(s.nearest_squared(1, 0) == 0.0);
  CHECK(s.nearest_squared(3, 2) == 8.0);   // (1, 0): 4 + 4; (6, 4): 9 + 4
  CHECK(s.nearest_squared(0, 4) == 17.0);  // (1, 0): 1 + 16; (6, 4): 36
  CHECK(s.nearest_squared(5, 3) == 2.0);
  const RowSeeds none(7, 5, [](int, int) { return false; });
  CHECK(none.empty());
  CHECK(none.nearest_squared(3, 2) == vcar::no_seed);
}

TEST_CASE("RowSeeds equals the exact distance transform at every pixel (random seeds, sizes, densities)") {
  std::mt19937 rng(11);
  for (const int W : {1, 2, 9, 31})
    for (const int H : {1, 3, 17, 40})
      for (const int seeds : {1, 2, 5, 60}) {
        std::vector<std::uint8_t> kind(static_cast<std::size_t>(W) * H, 0);
        for (int k = 0; k < seeds; ++k) kind[rng() % kind.size()] = 1;
        const RowSeeds s(W, H, [&](int x, int y) { return kind[static_cast<std::size_t>(y) * W + x] != 0; });
        const std::vector<double> want = vcar::squared_distance_to(kind, W, H);
        for (int y = 0; y < H; ++y)
          for (int x = 0; x < W; ++x) {
            CAPTURE(W, H, seeds, x, y);
            REQUIRE(s.nearest_squared(x, y) == want[static_cast<std::size_t>(y) * W + x]);
          }
      }
}
