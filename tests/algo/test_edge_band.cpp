#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "vcar/algo/edge_band.hpp"

#include "square_mask.hpp"

using vcar::Mask;


TEST_CASE("Eq. R1a: band half-width from the mask's equivalent radius") {
  // A = pi r^2 with r = 50: w = round(0.1 * 50) = 5.
  const std::size_t A = static_cast<std::size_t>(std::lround(3.14159265358979 * 2500.0));
  CHECK(vcar::edge_band_width(A, 0.1f) == 5);
  CHECK(vcar::edge_band_width(A, 0.2f) == 10);
  // At least one pixel, also for an empty mask.
  CHECK(vcar::edge_band_width(0, 0.2f) == 1);
  CHECK(vcar::edge_band_width(30, 0.05f) == 1);
  // 400 px: r_eq = sqrt(400 / pi) = 11.28; 0.3 * 11.28 = 3.38 -> 3.
  CHECK(vcar::edge_band_width(400, 0.3f) == 3);
}

TEST_CASE("Eq. R1b by hand: a 4x4 square in a 10x8 image, w = 1") {
  const Mask m = square_mask(10, 8, 3, 2, 7, 6);
  vcar::EdgeBandMasks b;
  std::vector<std::uint32_t> scratch;
  vcar::edge_band(m, 1, b, scratch);
  auto fg = [&](int x, int y) { return b.sure_foreground.data[static_cast<std::size_t>(y) * 10 + x] != 0; };
  auto sure = [&](int x, int y) { return b.sure.data[static_cast<std::size_t>(y) * 10 + x] != 0; };
  // Interior 2x2 (x 4..5, y 3..4): its 3x3 box lies inside the square.
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 10; ++x) {
      const bool interior = x >= 4 && x <= 5 && y >= 3 && y <= 4;
      const bool far_out = x <= 1 || x >= 8 || y <= 0 || y >= 7;  // box touches no foreground
      CHECK(fg(x, y) == interior);
      CHECK(sure(x, y) == (interior || far_out));
    }
}

TEST_CASE("Eq. R1b against brute force (random masks, w = 0..3, clipped boxes at the border)") {
  std::mt19937 rng(5);
  std::vector<std::uint32_t> scratch;
  for (int trial = 0; trial < 20; ++trial) {
    const int W = 5 + static_cast<int>(rng() % 20), H = 3 + static_cast<int>(rng() % 15), w = static_cast<int>(rng() % 4);
    Mask m(W, H, 1);
    for (auto& v : m.data) v = static_cast<std::uint8_t>(rng() % 3 ? 0 : 1 + rng() % 255);
    vcar::EdgeBandMasks b;
    vcar::edge_band(m, w, b, scratch);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        int n = 0, f = 0;
        for (int yy = std::max(0, y - w); yy <= std::min(H - 1, y + w); ++yy)
          for (int xx = std::max(0, x - w); xx <= std::min(W - 1, x + w); ++xx) {
            ++n;
            f += m.data[static_cast<std::size_t>(yy) * W + xx] != 0;
          }
        const std::size_t p = static_cast<std::size_t>(y) * W + x;
        REQUIRE((b.sure_foreground.data[p] != 0) == (f == n));
        REQUIRE((b.sure.data[p] != 0) == (f == n || f == 0));
      }
    // w = 0: every pixel sure, sure foreground = the mask.
    vcar::edge_band(m, 0, b, scratch);
    for (std::size_t p = 0; p < m.data.size(); ++p) {
      REQUIRE(b.sure.data[p] != 0);
      REQUIRE((b.sure_foreground.data[p] != 0) == (m.data[p] != 0));
    }
  }
}
