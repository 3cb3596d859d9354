#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "vcar/core/distance_transform.hpp"

namespace {

// O((W H)^2): the squared distance from every pixel to every seed.
std::vector<double> brute_force(const std::vector<std::uint8_t>& seed, int W, int H) {
  std::vector<double> d(seed.size(), vcar::no_seed);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int yy = 0; yy < H; ++yy)
        for (int xx = 0; xx < W; ++xx)
          if (seed[yy * W + xx]) d[y * W + x] = std::min(d[y * W + x], double((x - xx) * (x - xx) + (y - yy) * (y - yy)));
  return d;
}

}  // namespace

TEST_CASE("distance transform matches brute force") {
  std::mt19937 rng(7);
  // Shapes: tiny, one row, one column, wider than a column strip (256), and square; seed
  // densities from a single seed to most pixels (columns and rows without any seed included).
  const int shapes[][2] = {{1, 1}, {23, 17}, {40, 1}, {1, 33}, {300, 5}, {64, 64}};
  for (const auto& s : shapes) {
    const int W = s[0], H = s[1];
    for (const double density : {0.0, 0.002, 0.03, 0.3, 0.9, 1.0}) {
      std::vector<std::uint8_t> seed(static_cast<std::size_t>(W) * H, 0);
      std::bernoulli_distribution on(density);
      for (auto& v : seed) v = on(rng) ? 1 : 0;
      if (density > 0.0 && density < 0.01) seed[rng() % seed.size()] = 1;  // at least one seed
      INFO(W << "x" << H << ", density " << density);
      const std::vector<double> d2 = vcar::squared_distance_to(seed, W, H);
      REQUIRE(d2 == brute_force(seed, W, H));
    }
  }
}

TEST_CASE("distance transform: no seed gives no_seed everywhere, an empty image nothing") {
  const auto none = vcar::squared_distance_to(std::vector<std::uint8_t>(12 * 7, 0), 12, 7);
  CHECK(std::all_of(none.begin(), none.end(), [](double v) { return v == vcar::no_seed; }));
  CHECK(vcar::squared_distance_to({}, 0, 0).empty());
  CHECK(vcar::squared_distance_to({}, 5, 0).empty());
}

TEST_CASE("distance transform: hand values around one seed") {
  std::vector<std::uint8_t> seed(5 * 4, 0);
  seed[1 * 5 + 3] = 1;  // (3, 1)
  const auto d2 = vcar::squared_distance_to(seed, 5, 4);
  CHECK(d2[1 * 5 + 3] == 0.0);
  CHECK(d2[0 * 5 + 0] == 9.0 + 1.0);  // (0, 0): dx 3, dy 1
  CHECK(d2[3 * 5 + 4] == 1.0 + 4.0);  // (4, 3): dx 1, dy 2
  CHECK(d2[3 * 5 + 0] == 9.0 + 4.0);
}
