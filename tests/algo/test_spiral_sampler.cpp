#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "vcar/algo/spiral_sampler.hpp"

using vcar::Camera;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;

void check_looks_at(const Camera& cam, const Eigen::Vector3f& c) {
  const Eigen::Vector3f t = cam.to_camera(c);
  CHECK(t.x() == Approx(0).margin(1e-4));
  CHECK(t.y() == Approx(0).margin(1e-4));
  CHECK(t.z() > 0.f);
  CHECK((cam.forward() - (c - cam.position()).normalized()).norm() == Approx(0).margin(1e-5));
}
}  // namespace

TEST_CASE("scene up is the normalised mean of the cameras' up") {
  const vcar::Intrinsics k{10, 10, 10, 10, 5, 5};
  const std::vector<Camera> cams = {Camera::look_at({0, 0, -5}, {0, 0, 0}, {0, -1, 0}, k),
                                    Camera::look_at({5, 0, 0}, {0, 0, 0}, {0, 0, 1}, k)};
  REQUIRE((cams[0].up() - Eigen::Vector3f(0, -1, 0)).norm() < 1e-6f);
  const Eigen::Vector3f up = vcar::estimate_scene_up(cams);
  CHECK((up - Eigen::Vector3f(0, -1, 1).normalized()).norm() == Approx(0).margin(1e-6));
  CHECK_THROWS_AS(vcar::estimate_scene_up(std::vector<Camera>{}), vcar::Error);
}

TEST_CASE("Eq. 7-8: S1 = 4, S2 = 8 spiral against hand values") {
  const vcar::ObjectSphere sphere{{1, 2, 3}, 2.f, 10};
  const Eigen::Vector3f up(0, -1, 0);  // COLMAP-style: world y points down
  const vcar::Intrinsics k{64, 48, 50, 50, 32, 24};
  const auto cams = vcar::spiral_cameras(sphere, up, k, 4, 8, -60.f, 60.f);
  REQUIRE(cams.size() == 32);
  CHECK(cams.front().name == "sss_000");
  CHECK(cams.back().name == "sss_031");
  // Frame for up = -y: e3 = -y, e1 = x (least aligned with up, first on ties), e2 = e3 x e1 = z.
  // k = 0: theta 0, phi -60: p = c + r (0.5 e1 - sin 60 e3) = c + 2 (0.5, +0.866, 0).
  const Eigen::Vector3f p0 = sphere.c + 2.f * Eigen::Vector3f(0.5f, std::sqrt(3.f) / 2, 0);
  CHECK((cams[0].position() - p0).norm() == Approx(0).margin(1e-5));
  // k = 31: theta = 2 pi 4 31 / 32 = -pi/4 (mod 2 pi), phi = 60:
  // p = c + 2 (0.5 cos45 e1 - 0.5 sin45 e2 + sin60 e3) = c + 2 (0.3536, -0.866, -0.3536).
  const float h = 0.5f * std::sqrt(0.5f);
  const Eigen::Vector3f p31 = sphere.c + 2.f * Eigen::Vector3f(h, -std::sqrt(3.f) / 2, -h);
  CHECK((cams[31].position() - p31).norm() == Approx(0).margin(1e-5));
  // k = 2: theta = pi/2, phi = -60 + 240/31 degrees.
  const double phi2 = (-60.0 + 120.0 * 2 / 31) * kDeg;
  const Eigen::Vector3f p2 = sphere.c + 2.f * Eigen::Vector3f(0, -std::sin(phi2), std::cos(phi2));
  CHECK((cams[2].position() - p2).norm() == Approx(0).margin(1e-5));
  for (std::size_t j = 0; j < cams.size(); ++j) {
    INFO("camera " << j);
    const Eigen::Vector3f d = cams[j].position() - sphere.c;
    CHECK(d.norm() == Approx(2.0).epsilon(1e-5));  // on the sphere
    const double elevation = std::asin(d.normalized().dot(up)) / kDeg;
    CHECK(elevation == Approx(-60.0 + 120.0 * j / 31).margin(1e-3));  // Eq. 7, from the plane orthogonal to up
    check_looks_at(cams[j], sphere.c);
    CHECK(cams[j].up().dot(up) > 0.f);  // the sampled frames stay upright
    CHECK(cams[j].width == 64);
    CHECK(cams[j].fx == 50.f);
  }
  // S1 revolutions: theta advances 2 pi every S2 = 8 cameras.
  const Eigen::Vector3f a = (cams[1].position() - sphere.c), b = (cams[9].position() - sphere.c);
  CHECK(std::atan2(a.z(), a.x()) == Approx(std::atan2(b.z(), b.x())).margin(1e-5));
}

TEST_CASE("spiral: N_s = 1, reference-code variant and the 45-degree intrinsics") {
  const vcar::ObjectSphere sphere{{0, 0, 0}, 1.f, 1};
  const vcar::Intrinsics k{64, 48, 50, 50, 32, 24};
  const auto one = vcar::spiral_cameras(sphere, {0, 0, 1}, k, 1, 1, 30.f, 60.f);
  REQUIRE(one.size() == 1);
  CHECK(one[0].position().z() == Approx(0.5));  // phi = phi_s when N_s = 1
  // Reference code: world axes frame, elevation +60..-10.
  auto p = vcar::VcarParams::reference_code();
  p.spiral_variant = vcar::SpiralVariant::ReferenceCode;
  Camera ref;
  ref.width = 1280; ref.height = 720; ref.fx = ref.fy = 1000; ref.cx = 600; ref.cy = 300;
  const auto cams = vcar::spiral_cameras(sphere, {0, -1, 0}, ref, p);
  REQUIRE(cams.size() == 32);
  CHECK(cams[0].position().z() == Approx(std::sin(60 * kDeg)));   // world z is the third axis
  CHECK(cams[31].position().z() == Approx(std::sin(-10 * kDeg)));
  const double f = 360.0 / std::tan(22.5 * kDeg);  // 45 degrees on the short side (720)
  CHECK(cams[0].fx == Approx(f));
  CHECK(cams[0].fy == Approx(f));
  CHECK(cams[0].cx == Approx(640));
  CHECK(cams[0].cy == Approx(360));
  for (const auto& c : cams) check_looks_at(c, sphere.c);
  const vcar::Intrinsics same = vcar::sampled_intrinsics(ref, vcar::VcarParams::nvos());  // paper: reference view's
  CHECK(same.fx == 1000.f);
  CHECK(same.cx == 600.f);
  CHECK(same.width == 1280);
}

TEST_CASE("gap-directed cameras sit in a cone around the gap direction") {
  const vcar::ObjectSphere sphere{{1, 0, 0}, 3.f, 1};
  const Eigen::Vector3f g = Eigen::Vector3f(0, -1, 1).normalized();
  const auto cams = vcar::gap_directed_cameras(sphere, {0, 0, 1}, g, {32, 32, 30, 30, 16, 16}, 6, 20.f);
  REQUIRE(cams.size() == 6);
  CHECK((cams[0].position() - (sphere.c + 3.f * g)).norm() == Approx(0).margin(1e-5));
  CHECK(cams[5].name == "sss_gap_005");
  for (std::size_t k = 0; k < cams.size(); ++k) {
    const Eigen::Vector3f d = cams[k].position() - sphere.c;
    CHECK(d.norm() == Approx(3.0).epsilon(1e-5));
    const double angle = std::atan2(d.normalized().cross(g).norm(), d.normalized().dot(g)) / kDeg;
    CHECK(angle == Approx(20.0 * k / 5).margin(1e-3));
    check_looks_at(cams[k], sphere.c);
  }
}
