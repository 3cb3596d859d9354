#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "vcar/core/image.hpp"

TEST_CASE("mask_at and mask_at_branchless: the pixel containing the point (floor), false outside the image, NaN or an empty mask") {
  vcar::Mask m(4, 3, 1, 0);
  m(2, 1) = 7;    // any nonzero value is foreground
  m(0, 0) = 255;  // pixel 0: what an outside point must not report
  CHECK(vcar::mask_at(m, 2.f, 1.f));
  CHECK(vcar::mask_at(m, 2.999f, 1.999f));  // same pixel
  CHECK_FALSE(vcar::mask_at(m, 3.f, 1.f));  // the next one
  CHECK_FALSE(vcar::mask_at(m, 1.999f, 1.f));
  CHECK(vcar::mask_at(m, 0.f, 0.f));
  for (auto [u, v] : {std::pair{-0.001f, 0.f}, std::pair{0.f, -0.5f}, std::pair{4.f, 0.f}, std::pair{0.f, 3.f},
                      std::pair{NAN, 0.f}, std::pair{0.f, NAN}, std::pair{-INFINITY, 0.f}, std::pair{1e30f, 1.f}}) {
    INFO(u << ", " << v);
    CHECK_FALSE(vcar::mask_at(m, u, v));
    CHECK_FALSE(vcar::mask_at_branchless(m, u, v));
  }
  CHECK_FALSE(vcar::mask_at(vcar::Mask(), 0.f, 0.f));
  CHECK_FALSE(vcar::mask_at_branchless(vcar::Mask(), 0.f, 0.f));
  CHECK_FALSE(vcar::mask_at_branchless(vcar::Mask(0, 5, 1, 0), 0.f, 0.f));
  // The two agree on a grid of points in and around the image (every 0.25 px).
  std::size_t differ = 0, fg = 0;
  for (float v = -1.f; v <= 4.f; v += 0.25f)
    for (float u = -1.f; u <= 5.f; u += 0.25f) {
      differ += vcar::mask_at(m, u, v) != vcar::mask_at_branchless(m, u, v);
      fg += vcar::mask_at(m, u, v);
    }
  CHECK(differ == 0);
  CHECK(fg == 32);  // pixels (2, 1) and (0, 0), 16 grid points each
}

TEST_CASE("to_8bit rounds 255 v half away from zero (std::lround), clamped, NaN to 0: every value near a step or a half") {
  std::vector<float> values = {0.f, 1.f, -0.f, -1e-30f, 1e-30f, 2.f, -3.f, std::numeric_limits<float>::infinity(),
                               -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()};
  for (int k = 0; k <= 255; ++k)
    for (const float c : {static_cast<float>(k) / 255.f, (static_cast<float>(k) + 0.5f) / 255.f}) {
      float lo = c, hi = c;
      for (int step = 0; step < 4; ++step) {  // the value and its float neighbours on either side
        values.push_back(lo), values.push_back(hi);
        lo = std::nextafter(lo, -1.f), hi = std::nextafter(hi, 2.f);
      }
    }
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(-0.25f, 1.25f);
  for (int k = 0; k < 20000; ++k) values.push_back(U(rng));
  vcar::ImageF img(static_cast<int>(values.size()), 1, 1);
  img.data = values;
  const vcar::Image<std::uint8_t> out = vcar::to_8bit(img);
  for (std::size_t k = 0; k < values.size(); ++k) {
    const float v = values[k];
    const long want = std::isnan(v) ? 0 : std::lround(std::clamp(v, 0.f, 1.f) * 255.f);
    CAPTURE(k, v);
    REQUIRE(static_cast<long>(out.data[k]) == want);
  }
}
