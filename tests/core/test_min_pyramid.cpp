#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "vcar/core/min_pyramid.hpp"

using vcar::MinPyramid;

namespace {

// Brute force over the rectangle's pixels (clipped); NaN reads -inf.
float brute(const std::vector<float>& v, int W, int H, int x0, int y0, int x1, int y1) {
  float m = std::numeric_limits<float>::infinity();
  for (int y = std::max(0, y0); y <= std::min(H - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(W - 1, x1); ++x) {
      const float a = v[static_cast<std::size_t>(y) * W + x];
      m = a == a ? std::min(m, a) : -std::numeric_limits<float>::infinity();
    }
  return m;
}

}  // namespace

TEST_CASE("MinPyramid: a lower bound of the rectangle's least value, exact on the cells it reads") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0.f, 10.f);
  for (auto [W, H] : {std::pair{64, 48}, std::pair{37, 29}, std::pair{300, 7}}) {  // whole and partial tiles
    CAPTURE(W, H);
    std::vector<float> v(static_cast<std::size_t>(W) * H);
    for (auto& a : v) a = U(rng);
    v[static_cast<std::size_t>(H / 2) * W + W / 3] = -1.f;  // one low pixel
    MinPyramid p;
    p.build(W, H, [&](std::size_t i) { return v[i]; });
    std::uniform_int_distribution<int> X(-3, W + 2), Y(-3, H + 2);
    int exact = 0;
    for (int t = 0; t < 3000; ++t) {
      int x0 = X(rng), x1 = X(rng), y0 = Y(rng), y1 = Y(rng);
      if (x0 > x1) std::swap(x0, x1);
      if (y0 > y1) std::swap(y0, y1);
      const float b = brute(v, W, H, x0, y0, x1, y1), q = p.min_over(x0, y0, x1, y1);
      CAPTURE(x0, y0, x1, y1);
      REQUIRE(q <= b);
      exact += q == b;
    }
    CHECK(exact > 0);
    // Tile-aligned rectangles of at most 4 x 4 tiles read exactly their own cells.
    for (int ty = 0; ty * 8 < H; ++ty)
      for (int tx = 0; tx * 8 < W; ++tx) {
        const int x1 = std::min(W, (tx + 2) * 8) - 1, y1 = std::min(H, (ty + 3) * 8) - 1;
        CHECK(p.min_over(tx * 8, ty * 8, x1, y1) == brute(v, W, H, tx * 8, ty * 8, x1, y1));
      }
  }
}

TEST_CASE("MinPyramid by hand: NaN has no lower bound, an empty rectangle none above, rebuilt in place") {
  std::vector<float> v(16 * 16, 2.f);
  v[5] = std::nanf("");
  MinPyramid p;
  p.build(16, 16, [&](std::size_t i) { return v[i]; });
  CHECK(p.min_over(0, 0, 7, 7) == -std::numeric_limits<float>::infinity());  // tile 0 holds the NaN
  CHECK(p.min_over(8, 8, 15, 15) == 2.f);
  CHECK(p.min_over(20, 20, 30, 30) == std::numeric_limits<float>::infinity());  // outside
  CHECK(p.min_over(0, 0, 1000, 1000) == -std::numeric_limits<float>::infinity());
  v[5] = 3.f;
  v[16 * 15 + 15] = 1.f;
  p.build(16, 16, [&](std::size_t i) { return v[i]; });
  CHECK(p.min_over(0, 0, 7, 7) == 2.f);
  CHECK(p.min_over(8, 8, 15, 15) == 1.f);
  CHECK(p.min_over(15, 15, 15, 15) == 1.f);
}
