#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>

#include "vcar/algo/view_completeness.hpp"

using vcar::Camera;

namespace {
constexpr double kPi = std::numbers::pi;

vcar::Directions from_lattice_where(const vcar::Directions& t, bool (*keep)(const Eigen::Vector3f&)) {
  vcar::Directions out;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (keep(t[i])) out.push_back(t[i]);
  return out;
}
}  // namespace

TEST_CASE("A.3 Fibonacci lattice: the formula for a few i") {
  const int K = 7;
  const auto t = vcar::fibonacci_lattice(K);
  REQUIRE(t.size() == 7);
  for (int i : {0, 1, 3, 6}) {
    const double phi = std::acos(1.0 - 2.0 * (i + 0.5) / K), theta = kPi * (1 + std::sqrt(5.0)) * i;
    CHECK(t.x[i] == Approx(std::sin(phi) * std::cos(theta)).margin(1e-6));
    CHECK(t.y[i] == Approx(std::sin(phi) * std::sin(theta)).margin(1e-6));
    CHECK(t.z[i] == Approx(std::cos(phi)).margin(1e-6));
  }
  CHECK(t.z[0] == Approx(1.0 - 1.0 / 7));  // cos phi_0 = 1 - 2 * 0.5 / K
  CHECK(t.x[0] == Approx(std::sqrt(1 - (6.0 / 7) * (6.0 / 7))));  // theta_0 = 0
  CHECK(t.y[0] == Approx(0).margin(1e-7));
  CHECK_THROWS_AS(vcar::fibonacci_lattice(0), vcar::Error);
}

TEST_CASE("Fibonacci lattice is near-uniform") {
  const int K = 2000;
  const auto t = vcar::fibonacci_lattice(K);
  const double s = std::sqrt(4 * kPi / K);  // side of the equal-area cell
  double nn_min = 10, nn_max = 0;
  for (int i = 0; i < K; ++i) {
    CHECK(t[i].norm() == Approx(1.0).margin(1e-6));
    double nn = 10;
    for (int j = 0; j < K; ++j)
      if (j != i) nn = std::min(nn, static_cast<double>((t[i] - t[j]).norm()));
    nn_min = std::min(nn_min, nn);
    nn_max = std::max(nn_max, nn);
  }
  CHECK(nn_min > 0.5 * s);  // no clumps
  CHECK(nn_max < 1.5 * s);  // no holes
}

TEST_CASE("Eq. 6: cameras all around leave a small gap") {
  const auto t = vcar::fibonacci_lattice(2000);
  const auto h = vcar::fibonacci_lattice(100);  // 100 headings spread over the sphere
  const auto g = vcar::max_angular_gap(t, h);
  CHECK(g.valid_cameras == 100);
  CHECK(g.Delta_max_deg < 20.f);  // 100 cells of 4 pi / 100 sr: radius ~ 11-13 degrees
  CHECK(g.Delta_max_deg > 5.f);
  // Brute force with one acos per pair agrees.
  double worst = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    double best = 1e9;
    for (std::size_t j = 0; j < h.size(); ++j)
      best = std::min(best, std::acos(std::clamp(static_cast<double>(t[i].dot(h[j])), -1.0, 1.0)));
    worst = std::max(worst, best);
  }
  CHECK(g.Delta_max_rad == Approx(worst).margin(1e-4));
  CHECK(g.Delta_max_deg == Approx(worst * 180 / kPi).margin(5e-3));
}

TEST_CASE("Eq. 6: a hemisphere rig leaves ~90 degrees, pointing into the empty half") {
  const auto t = vcar::fibonacci_lattice(2000);
  const auto h = from_lattice_where(vcar::fibonacci_lattice(400), [](const Eigen::Vector3f& d) { return d.z() > 0.f; });
  REQUIRE(h.size() == 200);
  const auto g = vcar::max_angular_gap(t, h);
  // True gap: ~90.1 degrees (lowest camera just above the equator); probes lie within the
  // lattice's covering radius (~2.3 degrees for K = 2000) of the south pole.
  CHECK(g.Delta_max_deg > 87.5f);
  CHECK(g.Delta_max_deg < 91.f);
  CHECK(g.direction.z() < -0.99f);  // the south pole: the uncovered region
  CHECK(g.direction == t[g.probe]);
}

TEST_CASE("Eq. 6: one camera leaves ~180 degrees, none exactly 180") {
  const auto t = vcar::fibonacci_lattice(2000);
  vcar::Directions h;
  h.push_back(Eigen::Vector3f(0, 1, 0));
  const auto g = vcar::max_angular_gap(t, h);
  CHECK(g.Delta_max_deg > 176.f);
  CHECK(g.direction.y() < -0.99f);
  const auto none = vcar::max_angular_gap(t, vcar::Directions{});
  CHECK(none.Delta_max_deg == 180.f);
  CHECK(none.Delta_max_rad == Approx(kPi));
  CHECK(none.valid_cameras == 0);
}

TEST_CASE("A.1-A.2: visible fraction, valid cameras and headings") {
  vcar::GaussianScene scene;
  scene.resize(5);
  for (int i = 0; i < 5; ++i) scene.set(i, Eigen::Vector3f(-1.f + 0.5f * i, 0, 0), Eigen::Vector3f::Zero(), {1, 0, 0, 0}, 0);
  const std::vector<vcar::Index> idx = {0, 1, 2, 3, 4};
  // Camera at (0,0,-5) looking along +z; u = 10 x / 5 + 0 = 2x, visible iff 0 <= x < 5:
  // x = 0, 0.5, 1 -> rho = 3/5 (x = 0 lands on u = 0, inside).
  Camera half;
  half.name = "half";
  half.width = 10; half.height = 10; half.fx = 10; half.fy = 10; half.cx = 0; half.cy = 5;
  half.t_w = Eigen::Vector3f(0, 0, 5);
  Camera away = half;  // half turn about y: looks along -z, everything behind it
  away.name = "away";
  away.R_w = Eigen::Vector3f(-1, 1, -1).asDiagonal();
  away.t_w = Eigen::Vector3f(0, 0, -5);
  Camera wide = vcar::Camera::look_at({0, 3, 0}, {0, 0, 0}, {0, 0, 1}, {100, 100, 20, 20, 50, 50}, "wide");
  Camera centre = vcar::Camera::look_at({0, 0, 0}, {0, 0, 1}, {0, -1, 0}, {100, 100, 20, 20, 50, 50}, "centre");
  const std::vector<Camera> cams = {half, away, wide, centre};

  CHECK(vcar::visible_fraction(scene, idx, half) == Approx(0.6));
  CHECK(vcar::visible_fraction(scene, idx, away) == Approx(0.0));
  CHECK(vcar::visible_fraction(scene, idx, wide) == Approx(1.0));
  CHECK(vcar::visible_fraction(scene, idx, centre) == Approx(0.0));  // all at z = 0: invisible
  CHECK(vcar::valid_cameras(scene, idx, cams, 0.6f) == std::vector<std::size_t>{0, 2});  // >= rho_min
  CHECK(vcar::valid_cameras(scene, idx, cams, 0.61f) == std::vector<std::size_t>{2});
  const std::vector<std::size_t> chosen = {0, 2, 3};
  const auto h = vcar::headings(cams, chosen, Eigen::Vector3f::Zero());  // camera 3 is at c: skipped
  REQUIRE(h.size() == 2);
  CHECK((h[0] - Eigen::Vector3f(0, 0, -1)).norm() == Approx(0).margin(1e-6));  // from c toward the camera
  CHECK((h[1] - Eigen::Vector3f(0, 1, 0)).norm() == Approx(0).margin(1e-6));
  // The same from positions.
  const std::vector<Eigen::Vector3f> pos = {{0, 0, -5}, {0, 3, 0}, {0, 0, 0}};
  const auto hp = vcar::headings(Eigen::Vector3f::Zero(), pos);
  REQUIRE(hp.size() == 2);
  CHECK(hp[0] == h[0]);
  CHECK(hp[1] == h[1]);
}
