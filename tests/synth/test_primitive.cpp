#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include "vcar/synth/primitive.hpp"

using namespace vcar::synth;

namespace {
Primitive make(PrimitiveType t, const Eigen::Vector3f& params, vcar::synth::Rng& rng) {
  Primitive q;
  q.type = t;
  q.params = params;
  const Eigen::Vector3f axis = Eigen::Vector3f(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
  q.R = Eigen::AngleAxisf(rng.uniform(0.f, 3.f), axis).toRotationMatrix();
  q.t = {rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
  return q;
}
}  // namespace

TEST_CASE("each primitive's ray caster hits a surface point at its distance") {
  vcar::synth::Rng rng(42, 0);
  const std::vector<std::pair<PrimitiveType, Eigen::Vector3f>> shapes = {
      {PrimitiveType::sphere, {0.5f, 0, 0}},   {PrimitiveType::box, {0.3f, 0.5f, 0.2f}},
      {PrimitiveType::cylinder, {0.3f, 0.6f, 0}}, {PrimitiveType::rod, {0.02f, 0.8f, 0}},
      {PrimitiveType::torus, {0.5f, 0.15f, 0}}, {PrimitiveType::plane, {0.7f, 0.4f, 0}}};
  for (const auto& [type, params] : shapes) {
    INFO(to_string(type));
    const Primitive q = make(type, params, rng);
    float small = 1e9f;  // below every size (and the torus hole's half width)
    for (int d = 0; d < 3; ++d) if (params[d] > 0.f) small = std::min(small, 0.4f * params[d]);
    for (int k = 0; k < 300; ++k) {
      const SurfaceSample smp = sample_surface(q, rng);
      CHECK(std::abs(sdf(q, smp.p)) < 1e-4f);
      CHECK(smp.n.norm() == Approx(1.f).epsilon(1e-4));
      // From a point at distance `s` along the normal (sdf = s there: nothing is nearer).
      const float s = small * rng.uniform(0.2f, 1.f);
      float hit = -1;
      REQUIRE(intersect(q, smp.p + s * smp.n, -smp.n, 0.f, 1e9f, hit));
      CHECK(hit == Approx(s).margin(2e-5));
      // Convex shapes: from far away along the normal as well.
      if (type != PrimitiveType::torus) {
        REQUIRE(intersect(q, smp.p + 5.f * smp.n, -smp.n, 0.f, 1e9f, hit));
        CHECK(hit == Approx(5.f).margin(3e-4));  // float round-off at 5 units
      }
      // Pointing away from the surface misses, except for the torus (which may come back).
      if (type != PrimitiveType::torus && type != PrimitiveType::plane)
        CHECK_FALSE(intersect(q, smp.p + s * smp.n, smp.n, 0.f, 1e9f, hit));
    }
  }
}

TEST_CASE("torus: axis ray passes through the hole, a ray along x hits the outer equator") {
  Primitive q;
  q.type = PrimitiveType::torus;
  q.params = {1.f, 0.25f, 0.f};
  float s;
  CHECK_FALSE(intersect(q, {0, 0, 5}, {0, 0, -1}, 0.f, 1e9f, s));
  REQUIRE(intersect(q, {5, 0, 0}, {-1, 0, 0}, 0.f, 1e9f, s));
  CHECK(s == Approx(5.f - 1.25f).margin(1e-5));
  // Starting in the hole, the next surface is the inner equator at x = -0.75.
  REQUIRE(intersect(q, {0, 0, 0}, {-1, 0, 0}, 0.f, 1e9f, s));
  CHECK(s == Approx(0.75f).margin(1e-5));
  // Tangent ray on top (z = r) touches at x = 1 (grazing is a hit within tolerance or a miss,
  // never a wrong distance).
  if (intersect(q, {-5, 0, 0.25f}, {1, 0, 0}, 0.f, 1e9f, s)) CHECK(std::abs(s - 4.f) < 0.3f);
}

TEST_CASE("surface sampling is uniform by area") {
  vcar::synth::Rng rng(3, 1);
  Primitive box;
  box.type = PrimitiveType::box;
  box.params = {1.f, 0.5f, 0.25f};  // face areas per axis: 0.5, 1, 2 (x4)
  int on_z = 0;
  Primitive cyl;
  cyl.type = PrimitiveType::cylinder;
  cyl.params = {0.5f, 1.f, 0.f};  // side 4 pi r h = 2 pi, caps 2 pi r^2 = pi / 2
  int on_side = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    on_z += std::abs(sample_surface(box, rng).n.z()) > 0.5f;
    on_side += std::abs(sample_surface(cyl, rng).n.z()) < 0.5f;
  }
  CHECK(on_z / double(n) == Approx(2.0 / 3.5).margin(0.015));
  CHECK(on_side / double(n) == Approx(2.0 / 2.5).margin(0.015));
  Primitive torus;
  torus.type = PrimitiveType::torus;
  torus.params = {1.f, 0.5f, 0.f};  // outer half (cos theta > 0) holds (R + 2r/pi)/(2R) of the area
  int outer = 0;
  for (int k = 0; k < n; ++k) {
    const auto smp = sample_surface(torus, rng);
    outer += smp.p.head<2>().norm() > 1.f;
  }
  CHECK(outer / double(n) == Approx((1.0 + 1.0 / M_PI) / 2.0).margin(0.015));
}
