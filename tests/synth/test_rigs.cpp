#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "vcar/synth/rigs.hpp"

using namespace vcar::synth;

namespace {
World small_world() {
  WorldParams p;
  p.seed = 3;
  p.n_gaussians = 2000;
  return generate_world(p);
}
}  // namespace

TEST_CASE("every rig: valid cameras above the table and outside objects, target in view, eval not in train") {
  const World w = small_world();
  const Eigen::Vector3f c = w.bounds(w.target_id).first;
  for (const char* kind : {"forward", "orbit", "sparse", "hemisphere"}) {
    INFO(kind);
    const Rig rig = make_rig(kind, w);
    CHECK(rig.kind == kind);
    REQUIRE(rig.reference < rig.train.size());
    REQUIRE(!rig.eval.empty());
    std::vector<const vcar::Camera*> all;
    for (auto& cam : rig.train) all.push_back(&cam);
    for (auto& cam : rig.eval) all.push_back(&cam);
    for (const auto* cam : all) {
      CHECK_NOTHROW(cam->validate());
      CHECK(cam->width == 320);
      CHECK(cam->position().z() > 0.3f);
      for (const auto& q : w.primitives) CHECK(sdf(q, cam->position()) > 0.05f);
      const Eigen::Vector3f t = cam->to_camera(c);
      REQUIRE(t.z() > 0.f);
      CHECK(vcar::inside_image(cam->fx * t.x() / t.z() + cam->cx, cam->fy * t.y() / t.z() + cam->cy, 320, 240));
      CHECK(cam->up().dot(w.up) > 0.f);  // upright
    }
    for (const auto& e : rig.eval)
      for (const auto& t : rig.train) CHECK((e.position() - t.position()).norm() > 1e-3f);
    std::vector<std::string> names;
    for (const auto* cam : all) names.push_back(cam->name);
    std::sort(names.begin(), names.end());
    CHECK(std::adjacent_find(names.begin(), names.end()) == names.end());
  }
}

TEST_CASE("rig shapes: forward is parallel and in front, orbit covers 360, hemisphere leaves the back unseen") {
  const World w = small_world();
  const Eigen::Vector3f c = w.bounds(w.target_id).first;
  auto azimuth = [&](const vcar::Camera& cam) {
    const Eigen::Vector3f d = cam.position() - c;
    return std::atan2(d.x(), -d.y()) * 180.0 / M_PI;  // 0 = front (-y)
  };
  auto max_gap = [&](const std::vector<vcar::Camera>& cams) {
    std::vector<double> a;
    for (auto& cam : cams) a.push_back(azimuth(cam));
    std::sort(a.begin(), a.end());
    double gap = 360.0 - (a.back() - a.front());
    for (std::size_t k = 1; k < a.size(); ++k) gap = std::max(gap, a[k] - a[k - 1]);
    return gap;
  };
  const Rig fwd = forward_facing_rig(w);
  CHECK(fwd.train.size() == 20);
  for (auto& cam : fwd.train) CHECK(cam.R_w.isApprox(fwd.train[0].R_w, 1e-6f));
  for (auto& cam : fwd.train) CHECK(std::abs(azimuth(cam)) < 20.0);
  CHECK(max_gap(fwd.train) > 300.0);
  const Rig orb = orbit_rig(w);
  CHECK(orb.train.size() == 40);
  CHECK(max_gap(orb.train) == Approx(9.0).margin(0.01));
  const Rig sp = sparse_rig(w);
  CHECK(sp.train.size() == 6);
  const Rig hemi = hemisphere_rig(w);
  CHECK(max_gap(hemi.train) > 180.0);  // the back half is never seen
  for (auto& cam : hemi.eval) CHECK(std::abs(azimuth(cam)) < 80.0);
  RigParams p;
  p.n_train = 1;
  CHECK_THROWS_AS(orbit_rig(w, p), vcar::Error);
  CHECK_THROWS_AS(make_rig("spiral", w), vcar::Error);
}

TEST_CASE("intrinsics: horizontal field of view and centred principal point") {
  const auto k = make_intrinsics(640, 480, 90.f);
  CHECK(k.fx == Approx(320.f));
  CHECK(k.cx == 320.f);
  CHECK(k.cy == 240.f);
}
