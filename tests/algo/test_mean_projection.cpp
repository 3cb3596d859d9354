#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <vector>

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

TEST_CASE("project_boxes answers each lane as project_box does for that lane's box and view") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> U(-2.f, 2.f), S(0.01f, 0.8f);
  constexpr std::size_t L = vcar::simd::width;
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<vcar::detail::MeanProjection> views;
    std::vector<std::array<float, 7>> boxes;
    const std::size_t count = 1 + static_cast<std::size_t>(rng() % L);  // lanes past count repeat the last
    for (std::size_t l = 0; l < count; ++l) {
      const Eigen::Vector3f eye(U(rng), U(rng), U(rng) - 2.5f);
      views.push_back(vcar::detail::MeanProjection::from(
          Camera::look_at(eye, {U(rng) * 0.3f, U(rng) * 0.3f, 0.f}, {0, -1, 0}, {64, 48, 50, 55, 31.5f, 24.5f})));
      std::array<float, 7> b{U(rng), U(rng), U(rng), 0.f, 0.f, 0.f, 0.f};
      for (int d = 0; d < 3; ++d) b[3 + d] = b[d] + S(rng);
      if (l == 1 && trial % 5 == 0) b[4] = INFINITY;  // a non-finite box: partial, per-mean test
      boxes.push_back(b);
    }
    std::vector<const vcar::detail::MeanProjection*> ptr;
    for (const auto& v : views) ptr.push_back(&v);
    vcar::detail::BoxViewLanes lanes;
    vcar::detail::project_boxes(vcar::detail::ViewLanes::of(ptr.data(), count),
                                vcar::detail::BoxLanes::of(boxes.data(), count), lanes);
    for (std::size_t l = 0; l < L; ++l) {
      const std::size_t k = std::min(l, count - 1);
      const BoxView want = vcar::detail::project_box(views[k], boxes[k].data(), boxes[k].data() + 3);
      const BoxView got = lanes[l];
      INFO("trial " << trial << " lane " << l);
      CHECK(got.visibility == want.visibility);
      CHECK(got.x0 == want.x0);
      CHECK(got.y0 == want.y0);
      CHECK(got.x1 == want.x1);
      CHECK(got.y1 == want.y1);
      CHECK(got.zmin == want.zmin);
      if (!std::isfinite(boxes[k][4])) CHECK(got.visibility == BoxView::partial);
    }
  }
}

TEST_CASE("mean_box: the least and greatest means per axis; a non-finite mean makes lo NaN, NaN is left out of hi") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> U(-50.f, 50.f);
  // Brute force, one mean at a time.
  auto brute = [](const std::vector<float>* c, std::size_t b, std::size_t e) {
    std::array<float, 6> want{};
    for (int d = 0; d < 3; ++d) {
      bool finite = true;
      float lo = INFINITY, hi = -INFINITY;
      for (std::size_t j = b; j < e; ++j) {
        const float v = c[d][j];
        finite = finite && std::isfinite(v);
        if (!std::isnan(v)) lo = std::min(lo, v), hi = std::max(hi, v);
      }
      want[d] = finite ? lo : NAN;
      want[3 + d] = hi;
    }
    return want;
  };
  int nonfinite_boxes = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t n = 1 + rng() % 300;
    std::vector<float> c[3];
    for (auto& col : c) {
      col.resize(n);
      for (float& v : col) v = U(rng);
    }
    if (trial % 3 == 1) c[rng() % 3][rng() % n] = NAN;
    if (trial % 5 == 2) c[rng() % 3][rng() % n] = trial % 2 ? INFINITY : -INFINITY;
    if (trial % 7 == 3) std::fill(c[1].begin(), c[1].end(), NAN);  // no mean is a number on y
    const std::size_t b = rng() % n, e = b + rng() % (n - b + 1);
    const auto got = vcar::detail::mean_box(c[0].data(), c[1].data(), c[2].data(), b, e);
    const auto want = brute(c, b, e);
    INFO("trial " << trial << " [" << b << ", " << e << ")");
    for (int k = 0; k < 6; ++k) {
      if (std::isnan(want[k])) CHECK(std::isnan(got[k]));
      else CHECK(got[k] == want[k]);
    }
    nonfinite_boxes += std::isnan(want[0]) || std::isnan(want[1]) || std::isnan(want[2]);
  }
  CHECK(nonfinite_boxes > 20);
}
