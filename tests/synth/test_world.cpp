#include <catch2/catch.hpp>

#include <cstring>
#include <set>

#include "vcar/core/parallel.hpp"
#include "vcar/synth/world.hpp"
#include "synth_test_util.hpp"

using namespace vcar::synth;

namespace {
using vcar_test::same_bytes;
bool same_scene(const World& a, const World& b) {
  bool ok = a.object_id == b.object_id && same_bytes(a.scene.opacity_logit, b.scene.opacity_logit) &&
            same_bytes(a.scene.sh, b.scene.sh);
  for (int d = 0; d < 3; ++d) ok = ok && same_bytes(a.scene.mean[d], b.scene.mean[d]) && same_bytes(a.scene.log_scale[d], b.scene.log_scale[d]);
  for (int c = 0; c < 4; ++c) ok = ok && same_bytes(a.scene.rotation[c], b.scene.rotation[c]);
  return ok;
}
const Primitive& prim_of(const World& w, int id) {
  for (const auto& q : w.primitives) if (q.object_id == id) return q;
  throw std::runtime_error("no primitive");
}
}  // namespace

TEST_CASE("same seed gives the same bytes, for any thread count; another seed differs") {
  WorldParams p;
  p.seed = 11;
  p.n_gaussians = 20000;
  const World a = generate_world(p);
  const int threads = vcar::max_threads();
  vcar::set_num_threads(1);
  const World b = generate_world(p);
  vcar::set_num_threads(threads);
  CHECK(same_scene(a, b));
  p.seed = 12;
  CHECK_FALSE(same_scene(a, generate_world(p)));
  CHECK_NOTHROW(a.scene.validate());
  CHECK(a.scene.size() == 20000);
  CHECK(a.object_id.size() == 20000);
}

TEST_CASE("the layout: target touches the neighbour, the rod leans on it, objects rest on the table") {
  std::set<PrimitiveType> target_types;
  for (std::uint64_t seed = 1; seed <= 24; ++seed) {
    WorldParams p;
    p.seed = seed;
    p.n_gaussians = 2000;
    const World w = generate_world(p);
    INFO("seed " << seed);
    const Primitive& target = prim_of(w, w.target_id);
    const Primitive& nb = prim_of(w, w.neighbour_id);
    const Primitive& rod = prim_of(w, 3);
    target_types.insert(target.type);
    // Contact: the closest target surface point is on the neighbour's surface (brute force).
    vcar::synth::Rng rng(seed, 99);
    float closest = INFINITY;
    for (int k = 0; k < 20000; ++k) closest = std::min(closest, sdf(nb, sample_surface(target, rng).p));
    CHECK(closest > -1e-3f);  // no interpenetration
    CHECK(closest < 5e-3f);   // touching (sampling resolution)
    // The rod's axis passes the neighbour's top edge at one rod radius.
    const Eigen::Vector3f E(nb.t.x() + nb.params[0], 0.f, 2.f * nb.params[2]);
    const Eigen::Vector3f axis = rod.R.col(2);
    float edge_dist = INFINITY;  // distance from the edge line (along y) to the rod surface
    for (int k = -100; k <= 100; ++k) {
      const Eigen::Vector3f q = E + Eigen::Vector3f(0, nb.params[1] * k / 100.f, 0);
      edge_dist = std::min(edge_dist, sdf(rod, q));
    }
    CHECK(std::abs(edge_dist) < 2e-3f);
    CHECK(axis.z() != 0.f);
    // Everything rests on the table: lowest point of each solid at z = 0 (rod: foot at z ~ 0).
    for (const auto& q : w.primitives) {
      if (q.type == PrimitiveType::plane || q.type == PrimitiveType::rod) continue;
      float zmin = INFINITY;
      for (int k = 0; k < 4000; ++k) zmin = std::min(zmin, sample_surface(q, rng).p.z());
      CHECK(zmin == Approx(0.f).margin(3e-3));
      CHECK(zmin > -1e-4f);
    }
  }
  CHECK(target_types.size() == 4);  // sphere, torus, cylinder, box all occur
}

TEST_CASE("Gaussians: surface discs on their object, defects and floaters as asked") {
  WorldParams p;
  p.seed = 5;
  p.n_gaussians = 50000;
  p.floater_fraction = 0.02f;
  const World w = generate_world(p);
  const std::size_t n_float = static_cast<std::size_t>(0.02f * 50000);
  const std::size_t n_strad = static_cast<std::size_t>(p.straddler_fraction * 50000);
  const std::size_t n_needle = static_cast<std::size_t>(p.needle_fraction * 50000);
  REQUIRE(n_strad > 50);
  std::size_t background = 0, low_opacity_bg = 0;
  for (std::size_t i = 0; i < w.scene.size(); ++i)
    if (w.object_id[i] == -1) { ++background; low_opacity_bg += w.scene.opacity(i) < 0.3f; }
  CHECK(background == n_float);
  CHECK(low_opacity_bg == n_float);
  // Surface discs: mean on their primitive's surface, smallest axis along its normal, not buried.
  const std::size_t n_surf = 50000 - n_float - n_strad - n_needle;
  std::size_t off_surface = 0, buried_count = 0, not_flat = 0;
  std::vector<std::size_t> per_prim(w.primitives.size(), 0);
  for (std::size_t i = 0; i < n_surf; ++i) {
    const Eigen::Vector3f mu = w.scene.mu(i);
    std::size_t k = 0;
    while (w.primitives[k].object_id != w.object_id[i]) ++k;
    ++per_prim[k];
    off_surface += std::abs(sdf(w.primitives[k], mu)) > 1e-4f;
    buried_count += detail::buried(w.primitives, k, mu);
    const Eigen::Vector3f s = w.scene.scale(i);
    not_flat += !(s.z() < 0.1f * s.x() && s.z() < 0.1f * s.y());
  }
  CHECK(off_surface == 0);
  CHECK(buried_count < n_surf / 1000);  // only where 64 redraws all failed
  CHECK(not_flat == 0);
  // Density proportional to area: Gaussians per unit area equal across primitives (+-15%).
  const double ref = per_prim[0] / area(w.primitives[0]);
  for (std::size_t k = 1; k < w.primitives.size(); ++k) {
    INFO("primitive " << k);
    CHECK(per_prim[k] / area(w.primitives[k]) == Approx(ref).epsilon(0.15));
  }
  // Straddlers lie near a contact and are much larger than surface discs.
  for (std::size_t i = n_surf; i < n_surf + n_strad; ++i) {
    float near = INFINITY;
    std::size_t own = 0;
    while (w.primitives[own].object_id != w.object_id[i]) ++own;
    for (std::size_t m = 0; m < w.primitives.size(); ++m)
      if (m != own) near = std::min(near, std::abs(sdf(w.primitives[m], w.scene.mu(i))));
    CHECK(near < 0.1f);
    CHECK(w.scene.scale(i).x() > 1.5f * w.scene.scale(0).x());  // >= 2 h vs <= h
  }
  const auto target = w.gaussians_of(w.target_id);
  CHECK(target.size() > 1000);
}

TEST_CASE("default world and inserted Gaussians") {
  const World w = default_world();
  CHECK(w.scene.size() == 100000);
  CHECK(w.target_id != w.neighbour_id);
  World v = w;
  vcar::GaussianScene obj;
  obj.resize(3);
  obj.set(0, {0, 0, 0}, {-3, -3, -3}, {1, 0, 0, 0}, 2.f);
  obj.set(1, {1, 0, 0}, {-3, -3, -3}, {0, 0, 0, 1}, 2.f);
  obj.set(2, {0, 1, 0}, {-3, -2, -3}, {1, 0, 0, 0}, 2.f);
  obj.set_rgb(2, {0.2f, 0.4f, 0.6f});
  const Eigen::Matrix3f R = Eigen::AngleAxisf(0.5f * 3.14159265f, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  insert_gaussians(v, obj, R, {0.5f, 0.5f, 0.1f}, 2.f, 9);
  REQUIRE(v.scene.size() == 100003);
  CHECK(v.object_id.back() == 9);
  CHECK((v.scene.mu(100001) - Eigen::Vector3f(0.5f, 2.5f, 0.1f)).norm() < 1e-5f);  // R (2 x) + t
  CHECK((v.scene.mu(100002) - Eigen::Vector3f(-1.5f, 0.5f, 0.1f)).norm() < 1e-5f);
  CHECK(v.scene.scale(100002).y() == Approx(2.f * std::exp(-2.f)));
  // Rotation composes: Gaussian 1's local x axis (rotated 180 deg about z) then 90 deg about z.
  CHECK((v.scene.R(100001).col(0) - Eigen::Vector3f(0, -1, 0)).norm() < 1e-5f);
  CHECK(v.scene.opacity(100002) == Approx(obj.opacity(2)));
  CHECK(v.scene.sh[100002 * 3 + 2] == Approx(obj.sh[2 * 3 + 2]));
  CHECK(v.has_inserted(9));
  CHECK(v.gaussians_of(9).size() == 3);
  CHECK_THROWS_AS(insert_gaussians(v, obj, R, {0, 0, 0}, -1.f, 9), vcar::Error);
}
