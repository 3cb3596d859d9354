#include <catch2/catch.hpp>

#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/random.hpp"

using namespace vcar::synth;

TEST_CASE("squared distance transform equals brute force") {
  Rng rng(8, 0);
  for (int trial = 0; trial < 5; ++trial) {
    vcar::Mask m(37, 23, 1);
    const float p = trial == 0 ? 0.002f : 0.05f * trial;
    for (auto& v : m.data) v = rng.uniform() < p ? 255 : 0;
    for (bool fg : {true, false}) {
      const auto d2 = squared_distance(m, fg);
      for (int y = 0; y < m.height; ++y)
        for (int x = 0; x < m.width; ++x) {
          float best = INFINITY;
          for (int yy = 0; yy < m.height; ++yy)
            for (int xx = 0; xx < m.width; ++xx)
              if ((m(xx, yy) != 0) == fg) best = std::min(best, float((x - xx) * (x - xx) + (y - yy) * (y - yy)));
          CHECK(d2[static_cast<std::size_t>(y) * m.width + x] == best);
        }
    }
  }
}

TEST_CASE("dilation and erosion by k px change a disc's radius by k") {
  vcar::Mask m(200, 200, 1);
  const float R = 40.f;
  paint_disc(m, 100.f, 100.f, R);
  auto radius = [](const vcar::Mask& x) { return std::sqrt(count(x) / 3.14159265); };
  CHECK(radius(m) == Approx(R).margin(0.5));
  for (int k : {1, 3, 7, -3, -10}) {
    INFO("k = " << k);
    CHECK(radius(dilate_erode(m, k)) == Approx(R + k).margin(1.0));
  }
  // A single pixel dilated by 2 is the Euclidean disc of radius 2: 13 pixels.
  vcar::Mask dot(9, 9, 1);
  dot(4, 4) = 255;
  CHECK(count(dilate_erode(dot, 2)) == 13);
}

TEST_CASE("shift moves the mask, disc paints pixel centres within r") {
  vcar::Mask m(10, 8, 1);
  m(2, 3) = 255;
  const vcar::Mask s = shift(m, 3, -2);
  CHECK(count(s) == 1);
  CHECK(s(5, 1) == 255);
  CHECK(count(shift(m, -3, 0)) == 0);
  vcar::Mask d(10, 10, 1);
  paint_disc(d, 5.f, 5.f, 1.f);  // centres (4.5|5.5, 4.5|5.5) at distance 0.707
  CHECK(count(d) == 4);
}
