#include <catch2/catch.hpp>

#include <random>

#include "vcar/algo/mean_projection.hpp"

using vcar::Camera;
using vcar::detail::BoxView;

TEST_CASE("project_box decides a box only when every mean in it agrees with Eq. 1") {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> U(-2.f, 2.f), S(0.01f, 0.6f), T(0.f, 1.f);
  int decided[3] = {0, 0, 0};
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Vector3f eye(U(rng), U(rng), U(rng) - 2.5f);
    const Camera cam = Camera::look_at(eye, {U(rng) * 0.3f, U(rng) * 0.3f, 0.f}, {0, -1, 0}, {64, 48, 50, 55, 31.5f, 24.5f});
    const auto P = vcar::detail::MeanProjection::from(cam);
    const float lo[3] = {U(rng), U(rng), U(rng)};
    const float hi[3] = {lo[0] + S(rng), lo[1] + S(rng), lo[2] + S(rng)};
    const BoxView b = vcar::detail::project_box(P, lo, hi);
    ++decided[b.visibility];
    for (int k = 0; k < 200; ++k) {  // corners and random points of the box
      float p[3];
      for (int d = 0; d < 3; ++d) p[d] = k < 8 ? ((k >> d) & 1 ? hi[d] : lo[d]) : lo[d] + T(rng) * (hi[d] - lo[d]);
      float x[vcar::detail::mean_batch], y[vcar::detail::mean_batch], z[vcar::detail::mean_batch];
      std::fill(x, x + vcar::detail::mean_batch, p[0]);
      std::fill(y, y + vcar::detail::mean_batch, p[1]);
      std::fill(z, z + vcar::detail::mean_batch, p[2]);
      std::int32_t pix[vcar::detail::mean_batch], vis[vcar::detail::mean_batch];
      float depth[vcar::detail::mean_batch];
      vcar::detail::project_batch(P, x, y, z, pix, vis, depth);
      INFO("trial " << trial << " point " << k);
      if (b.visibility == BoxView::none_visible) CHECK(vis[0] == 0);
      if (b.visibility == BoxView::all_visible) CHECK(vis[0] == 1);
      if (vis[0]) {  // every visible mean's pixel lies in the rectangle
        const int px = pix[0] % cam.width, py = pix[0] / cam.width;
        CHECK(px >= b.x0);
        CHECK(px <= b.x1);
        CHECK(py >= b.y0);
        CHECK(py <= b.y1);
      }
    }
  }
  CHECK(decided[BoxView::none_visible] > 20);
  CHECK(decided[BoxView::all_visible] > 20);
  CHECK(decided[BoxView::partial] > 20);
}
