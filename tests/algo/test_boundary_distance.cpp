#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "vcar/algo/boundary_distance.hpp"

namespace {
// Foreground where col < edge_col (a straight vertical edge at u = edge_col).
vcar::Mask left_of(int w, int h, int edge_col) {
  vcar::Mask m(w, h, 1, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < edge_col && x < w; ++x) m(x, y) = 255;
  return m;
}
}  // namespace

TEST_CASE("boundary distance is halfway between the last foreground and the first exit sample") {
  const vcar::Mask mask = left_of(200, 100, 110);
  const Eigen::Vector2f m(100.3f, 50.3f), u(1.f, 0.f);
  const float L = 15.f;  // samples t_k = 15 k / 128
  // First sample with 100.3 + t_k >= 110: k = ceil(9.7 * 128 / 15) = 83.
  const int k = static_cast<int>(std::ceil(9.7 * 128.0 / 15.0));
  REQUIRE(k == 83);
  const double expected = 0.5 * ((k - 1) + k) * 15.0 / 128.0;
  CHECK(vcar::boundary_distance(mask, m, u, L, 129) == Approx(expected).epsilon(1e-6));
  // Opposite direction never leaves the foreground before the endpoint: endpoint distance.
  CHECK(vcar::boundary_distance(mask, m, -u, L, 129) == L);
}

TEST_CASE("boundary distance counts leaving the image as an exit") {
  const vcar::Mask mask(112, 100, 1, 255);  // all foreground, image ends at u = 112
  const Eigen::Vector2f m(100.3f, 50.3f), u(1.f, 0.f);
  const float L = 20.f;
  const int k = static_cast<int>(std::ceil((112.0 - 100.3) * 128.0 / 20.0));  // 74.88 -> 75
  CHECK(vcar::boundary_distance(mask, m, u, L, 129) == Approx((k - 0.5) * 20.0 / 128.0).epsilon(1e-6));
}

TEST_CASE("boundary distance matches a fine brute-force march on a random disk mask") {
  const int W = 64, H = 48;
  vcar::Mask mask(W, H, 1, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      mask(x, y) = (x + 0.5 - 30.0) * (x + 0.5 - 30.0) + (y + 0.5 - 24.0) * (y + 0.5 - 24.0) < 15.0 * 15.0 ? 255 : 0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> ang(0.f, 6.2831853f), off(-5.f, 5.f);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector2f m(30.f + off(rng), 24.f + off(rng));
    const float a = ang(rng);
    const Eigen::Vector2f u(std::cos(a), std::sin(a));
    const float L = 40.f, step = L / 128.f;
    // Brute force: the first exit along the ray; the sampled answer is within half a step of it.
    double exit = L;
    for (int j = 0; j <= 128000; ++j) {
      const double t = L * j / 128000.0;
      if (!vcar::mask_at(mask, static_cast<float>(m.x() + t * u.x()), static_cast<float>(m.y() + t * u.y()))) { exit = t; break; }
    }
    const float l = vcar::boundary_distance(mask, m, u, L, 129);
    CHECK(std::abs(l - exit) <= 0.5 * step + 1e-3);
  }
}

TEST_CASE("boundary distance of a centre outside the foreground is zero") {
  const vcar::Mask mask = left_of(50, 50, 10);
  CHECK(vcar::boundary_distance(mask, {20.5f, 5.5f}, {-1.f, 0.f}, 15.f, 129) == 0.f);
}

TEST_CASE("a march cut short finds the same exit when the exit is within reach, none otherwise") {
  const vcar::Mask mask = left_of(200, 100, 110);
  const Eigen::Vector2f m(100.3f, 50.3f), u(1.f, 0.f);
  const float step = 15.f / 128.f;
  // The exit is sample 83 (first test case).
  CHECK(vcar::first_exit_sample(mask, m, u, step, 128) == 83);
  CHECK(vcar::first_exit_sample(mask, m, u, step, 83) == 83);
  CHECK(vcar::first_exit_sample(mask, m, u, step, 82) == 83);  // none up to 82: last + 1
  CHECK(vcar::first_exit_sample(mask, m, u, step, 40) == 41);
  CHECK(vcar::exit_distance(83, step) == Approx(82.5 * 15.0 / 128.0).epsilon(1e-6));
  CHECK(vcar::exit_distance(0, step) == 0.f);
}
