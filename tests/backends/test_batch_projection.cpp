#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "vcar/backends/cpu/batch_projection.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace {

// True when ceil(v) could land on either side of an integer under last-bit differences.
bool near_integer(float v) { return std::abs(v - std::round(v)) < 1e-3f + 1e-5f * std::abs(v); }

bool close(float a, float b, float rel) { return std::abs(a - b) <= rel * std::max(1.f, std::abs(b)); }

}  // namespace

TEST_CASE("batch projection matches project_gaussian Gaussian by Gaussian (B.6-B.7, Eq. 10)") {
  const int W = 333, H = 207;  // edge tiles cut
  const vcar::Intrinsics k{W, H, 0.8f * W, 0.85f * W, 0.5f * W + 7.f, 0.5f * H - 4.f};
  const vcar::Camera cam = vcar::Camera::look_at(Eigen::Vector3f(0.4f, -0.5f, -3.f), Eigen::Vector3f(0.1f, 0, 0),
                                                 Eigen::Vector3f(0, -1, 0), k, "batch");
  const vcar::ProjectionParams pp{};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(-1.f, 1.f), LS(-6.f, -0.5f), O(-7.f, 9.f);
  std::normal_distribution<float> N(0, 1);
  // Inside and around the frustum, some behind the camera or past the near plane, some
  // transparent (opacity below 1/255), sizes from sub-pixel to larger than the image.
  const int n = 4003;  // not a multiple of any batch width: a tail batch
  vcar::GaussianScene sc;
  sc.resize(n, 0);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3f mu(2.5f * U(rng), 2.f * U(rng), 3.5f * U(rng));
    if (i % 97 == 3) mu = cam.position() + cam.forward() * (0.0095f + 0.002f * (U(rng) + 1.f));
    sc.set(i, mu, Eigen::Vector3f(LS(rng), LS(rng), LS(rng)), Eigen::Vector4f(N(rng), N(rng), N(rng), N(rng)), O(rng));
  }
  const vcar::cpu::BatchCamera bc(cam, pp);
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  constexpr int L = static_cast<int>(vcar::cpu::Lane::size);
  std::vector<vcar::cpu::PackedSplat> splat(n);
  std::vector<std::uint64_t> rect(n, ~std::uint64_t{0});
  for (int k0 = 0; k0 < n; k0 += L) {
    const int lanes = std::min(L, n - k0);
    const vcar::cpu::GaussianBatch g = vcar::cpu::load_batch(q, static_cast<std::size_t>(k0), lanes);
    vcar::cpu::project_batch(bc, pp, g, static_cast<std::uint32_t>(k0), lanes, splat.data() + k0, rect.data() + k0);
  }
  const int tiles_x = (W + 15) / 16, tiles_y = (H + 15) / 16;
  int kept = 0, culled = 0, borderline = 0;
  for (int i = 0; i < n; ++i) {
    const float op = sc.opacity(i);
    const vcar::ProjectedGaussian p = vcar::project_gaussian(cam, sc.mu(i), sc.R(i), sc.scale(i), op, pp);
    const bool scalar_kept = p.valid && p.on_screen;
    const float ext = std::min(pp.extend_max, std::sqrt(2.f * std::log(op / pp.alpha_min)));
    const bool edge = p.valid && (near_integer(ext * std::sqrt(p.Sigma2D(0, 0))) || near_integer(ext * std::sqrt(p.Sigma2D(1, 1))));
    REQUIRE(rect[i] != ~std::uint64_t{0});  // every lane wrote its rectangle
    if (edge) {  // a radius whose ceil may differ by one: only the culling has to agree or not
      ++borderline;
      continue;
    }
    INFO("Gaussian " << i);
    REQUIRE(!vcar::cpu::rect_empty(rect[i]) == scalar_kept);
    if (!scalar_kept) {
      ++culled;
      continue;
    }
    ++kept;
    const vcar::cpu::PackedSplat& s = splat[i];
    CHECK(s.k == static_cast<std::uint32_t>(i));
    CHECK((s.r == 0.f && s.g == 0.f && s.b == 0.f));  // shading is the renderer's (batch_shading.hpp)
    CHECK(close(s.mx, p.mean.x(), 1e-4f));
    CHECK(close(s.my, p.mean.y(), 1e-4f));
    // Radii equal; past the image's size, within 1e-4 (SSE2's exp, log and sqrt without fused
    // multiply-adds put a 23k-pixel radius of a splat at the near plane one pixel off).
    const auto same_radius = [&](float batch, int scalar) {
      return scalar > 2 * std::max(W, H) ? std::abs(batch - static_cast<float>(scalar)) <= 1.f + 1e-4f * static_cast<float>(scalar)
                                         : batch == static_cast<float>(scalar);
    };
    CHECK(same_radius(s.rx, p.radius_x));
    CHECK(same_radius(s.ry, p.radius_y));
    CHECK(close(s.depth, p.depth, 1e-6f));
    CHECK(close(s.opacity, op, 1e-6f));
    CHECK(close(s.sigma_max, std::log(op / pp.alpha_min), 1e-5f));
    // conic relative to its own size (entries of Sigma2D^-1 can be tiny); det cancels for thin
    // splats, so both float results carry errors of this order
    const float cs = std::max({std::abs(p.conic[0]), std::abs(p.conic[1]), std::abs(p.conic[2])});
    CHECK(std::abs(s.ca - p.conic[0]) <= 2e-3f * cs);
    CHECK(std::abs(s.cb - p.conic[1]) <= 2e-3f * cs);
    CHECK(std::abs(s.cc - p.conic[2]) <= 2e-3f * cs);
    // Exact extents: no dx brings sigma to sigma_max + slack once |dy| > ey (or |dx| > ex), and
    // 2% inside them some point does (brute force over a grid, in double, from the float conic).
    {
      const double a = s.ca, b = s.cb, c = s.cc, bound = static_cast<double>(s.sigma_max) + vcar::cpu::sigma_slack;
      const bool round = a * c - b * b > 0.05 * std::max(a, c) * std::max(a, c);  // no cancellation in the minimum
      const auto min_sigma = [&](double dy, double reach, bool swap) {  // min over dx of sigma(dx, dy)
        double m = 1e300;
        for (int k = -4000; k <= 4000; ++k) {
          const double dx = reach * k / 1000.0;
          const double v = swap ? 0.5 * (c * dx * dx + 2 * b * dx * dy + a * dy * dy) : 0.5 * (a * dx * dx + 2 * b * dx * dy + c * dy * dy);
          m = std::min(m, v);
        }
        return m;
      };
      if (round && s.ex < 1e3f && s.ey < 1e3f) {
        CHECK(min_sigma(s.ey, s.ex, false) >= bound - 1e-3 * bound);
        CHECK(min_sigma(s.ex, s.ey, true) >= bound - 1e-3 * bound);
        CHECK(min_sigma(0.98 * (s.ey - 0.01), s.ex, false) <= bound);
        CHECK(min_sigma(0.98 * (s.ex - 0.01), s.ey, true) <= bound);
      }
    }
    std::int32_t tx0, tx1, ty0, ty1;
    vcar::cpu::tile_rect(p.mean.x(), static_cast<float>(p.radius_x), tiles_x, tx0, tx1);
    vcar::cpu::tile_rect(p.mean.y(), static_cast<float>(p.radius_y), tiles_y, ty0, ty1);
    if (!near_integer((p.mean.x() - p.radius_x) / 16.f) && !near_integer((p.mean.x() + p.radius_x) / 16.f) &&
        !near_integer((p.mean.y() - p.radius_y) / 16.f) && !near_integer((p.mean.y() + p.radius_y) / 16.f))
      CHECK(rect[i] == vcar::cpu::pack_rect(tx0, tx1, ty0, ty1));
  }
  // The scene exercises both branches and few cases sit on a rounding edge.
  CHECK(kept > 1000);
  CHECK(culled > 500);
  INFO("borderline " << borderline);
  CHECK(borderline < n / 100);
}
