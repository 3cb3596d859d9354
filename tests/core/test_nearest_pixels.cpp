#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "vcar/core/nearest_pixels.hpp"

using vcar::NearestPixels;

TEST_CASE("NearestPixels by hand: reach 2 visits 13 pixels, nearest first, clipped to the image") {
  const NearestPixels near(2);
  std::vector<int> d2s;
  near.visit(5, 5, 20, 20, [&](std::size_t, int d2) { return d2s.push_back(d2), true; });
  CHECK(d2s == std::vector<int>{0, 1, 1, 1, 1, 2, 2, 2, 2, 4, 4, 4, 4});
  std::vector<std::size_t> corner;
  near.visit(0, 0, 20, 20, [&](std::size_t q, int) { return corner.push_back(q), true; });
  CHECK(corner == std::vector<std::size_t>{0, 1, 20, 21, 2, 40});  // (0, 0); (1, 0), (0, 1); (1, 1); (2, 0), (0, 2)
  int visited = 0;
  CHECK_FALSE(near.visit(5, 5, 20, 20, [&](std::size_t, int) { return ++visited < 3; }));  // stopped
  CHECK(visited == 3);
}

TEST_CASE("nearest_squared_distance equals brute force within the reach, -1 beyond it") {
  std::mt19937 rng(3);
  const int W = 23, H = 17;
  for (const int seeds : {1, 3, 30}) {
    std::vector<std::uint8_t> kind(static_cast<std::size_t>(W) * H, 0);
    for (int s = 0; s < seeds; ++s) kind[rng() % kind.size()] = 1;
    for (const int reach : {0, 1, 4, 9}) {
      const NearestPixels& near = vcar::nearest_pixels(reach);
      CHECK(&near == &vcar::nearest_pixels(reach));  // built once
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          int best = -1;
          for (int v = 0; v < H; ++v)
            for (int u = 0; u < W; ++u)
              if (kind[static_cast<std::size_t>(v) * W + u]) {
                const int d2 = (u - x) * (u - x) + (v - y) * (v - y);
                if (d2 <= reach * reach && (best < 0 || d2 < best)) best = d2;
              }
          CAPTURE(seeds, reach, x, y);
          REQUIRE(vcar::nearest_squared_distance(near, x, y, W, H, [&](std::size_t q) { return kind[q] != 0; }) == best);
        }
    }
  }
}
