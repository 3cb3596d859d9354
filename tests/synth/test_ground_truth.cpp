#include <catch2/catch.hpp>

#include <cstring>

#include "reference_renderer.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/rigs.hpp"

using namespace vcar::synth;

namespace {
double iou(const vcar::Mask& a, const vcar::Mask& b) {
  std::size_t i = 0, u = 0;
  for (std::size_t k = 0; k < a.data.size(); ++k) {
    i += a.data[k] && b.data[k];
    u += a.data[k] || b.data[k];
  }
  return u ? double(i) / double(u) : 1.0;
}
World one_sphere(float r) {
  World w;
  Primitive s;
  s.type = PrimitiveType::sphere;
  s.params = {r, 0, 0};
  s.object_id = 1;
  w.primitives.push_back(s);
  return w;
}
}  // namespace

TEST_CASE("a centred sphere's mask is the disc of radius f r / sqrt(d^2 - r^2)") {
  for (float d : {2.f, 3.5f}) {
    const float r = 0.6f;
    const World w = one_sphere(r);
    const vcar::Intrinsics k{400, 300, 250.f, 250.f, 200.f, 150.f};
    const auto cam = vcar::Camera::look_at({0, -d, 0}, {0, 0, 0}, {0, 0, 1}, k, "c");
    const double rho = k.fx * r / std::sqrt(d * d - r * r);
    const vcar::Mask m = visible_mask(w, cam, 1);
    CHECK(double(count(m)) == Approx(M_PI * rho * rho).epsilon(0.01));
    CHECK(m(200, 150) == 255);
    CHECK(m(200 + static_cast<int>(rho) + 2, 150) == 0);
    CHECK(m(200 + static_cast<int>(rho) - 2, 150) == 255);
    // Depth at the centre pixel is d - r (camera z).
    const IdImage img = raycast(w, cam);
    CHECK(img.depth[150 * 400 + 200] == Approx(d - r).epsilon(1e-3));
  }
}

TEST_CASE("visible mask is the silhouette minus occluders") {
  World w = one_sphere(0.5f);
  Primitive box;
  box.type = PrimitiveType::box;
  box.params = {0.2f, 0.2f, 0.2f};
  box.t = {0.3f, -1.f, 0.f};  // between the camera and the sphere, to the right
  box.object_id = 2;
  w.primitives.push_back(box);
  const auto cam = vcar::Camera::look_at({0, -3, 0}, {0, 0, 0}, {0, 0, 1}, make_intrinsics(320, 240), "c");
  const vcar::Mask vis = visible_mask(w, cam, 1), sil = silhouette_mask(w, cam, 1), occ = visible_mask(w, cam, 2);
  std::size_t vis_outside_sil = 0, sil_minus_vis = 0, explained = 0;
  for (std::size_t k = 0; k < vis.data.size(); ++k) {
    vis_outside_sil += vis.data[k] && !sil.data[k];
    if (sil.data[k] && !vis.data[k]) { ++sil_minus_vis; explained += occ.data[k] != 0; }
  }
  CHECK(vis_outside_sil == 0);
  CHECK(sil_minus_vis > 500);
  CHECK(explained == sil_minus_vis);  // every hidden pixel is covered by the box
}

TEST_CASE("default world: the target touches the neighbour in the reference views") {
  WorldParams p;
  p.seed = 7;
  p.n_gaussians = 10000;
  const World w = generate_world(p);
  const Rig rig = forward_facing_rig(w);
  const IdImage img = raycast(w, rig.train[rig.reference]);
  std::size_t target = 0, adjacent = 0;
  for (int y = 0; y + 1 < img.height; ++y)
    for (int x = 0; x + 1 < img.width; ++x) {
      target += img.at(x, y) == w.target_id;
      const int a = img.at(x, y), b = img.at(x + 1, y), c = img.at(x, y + 1);
      adjacent += (a == w.target_id && (b == w.neighbour_id || c == w.neighbour_id)) ||
                  (a == w.neighbour_id && (b == w.target_id || c == w.target_id));
    }
  CHECK(target > 3000);
  CHECK(adjacent > 10);
}

// Realism: the GT silhouette and the rendering of the GT Gaussians alone agree (IoU >= 0.9).
template <class R>
void check_realism(R& renderer) {
  WorldParams p;
  p.seed = 7;
  p.n_gaussians = 60000;
  const World w = generate_world(p);
  const auto ids = w.gaussians_of(w.target_id);
  for (const char* kind : {"forward", "orbit", "sparse", "hemisphere"}) {
    const Rig rig = make_rig(kind, w);
    std::vector<vcar::Camera> cams = rig.eval;
    cams.push_back(rig.train[rig.reference]);
    for (const auto& cam : cams) {
      INFO(kind << " " << cam.name);
      vcar::RenderRequest q;
      q.scene = &w.scene;
      q.camera = &cam;
      q.subset = &ids;
      const vcar::Mask rendered = vcar::threshold(renderer.render(q).alpha, 0.5f);
      const double v = iou(rendered, silhouette_mask(w, cam, w.target_id));
      CHECK(v >= 0.9);
    }
  }
}

TEST_CASE("realism: GT silhouette vs the GT Gaussians rendered alone (test-local renderer)") {
  synth_test::ReferenceRenderer renderer;
  check_realism(renderer);
}

#if __has_include("vcar/backends/cpu/tiled_renderer.hpp")
#include "vcar/backends/cpu/tiled_renderer.hpp"
TEST_CASE("realism: GT silhouette vs the GT Gaussians rendered alone (CPU backend)") {
  vcar::cpu::TiledRenderer renderer;
  check_realism(renderer);
}
#endif

TEST_CASE("inserted Gaussian objects: ground truth from their rendering, occlusion by depth") {
  WorldParams p;
  p.seed = 7;
  p.n_gaussians = 10000;
  World w = generate_world(p);
  const Rig rig = forward_facing_rig(w);
  const vcar::Camera& cam = rig.train[rig.reference];
  // A blob of small Gaussians halfway between the camera and the target.
  vcar::GaussianScene blob;
  blob.resize(400);
  Rng rng(1, 2);
  for (std::size_t i = 0; i < 400; ++i) {
    Eigen::Vector3f x(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    x *= 0.05f / std::max(1.f, x.norm());
    blob.set(i, x, Eigen::Vector3f::Constant(std::log(0.015f)), {1, 0, 0, 0}, 4.f);
  }
  const Eigen::Vector3f c = w.bounds(w.target_id).first;
  insert_gaussians(w, blob, Eigen::Matrix3f::Identity(), 0.5f * (c + cam.position()), 1.f, 8);
  synth_test::ReferenceRenderer renderer;
  const vcar::Mask before = visible_mask(w, cam, w.target_id);  // primitives only
  const vcar::Mask after = visible_mask(w, cam, w.target_id, renderer);
  const vcar::Mask inserted = visible_mask(w, cam, 8, renderer);
  const vcar::Mask inserted_alone = silhouette_mask(w, cam, 8, renderer);
  CHECK(count(inserted) > 200);
  CHECK(count(inserted) == count(inserted_alone));  // nothing is in front of it
  CHECK(count(after) + 200 < count(before));        // it hides part of the target
  for (std::size_t k = 0; k < after.data.size(); ++k) {
    if (after.data[k] && inserted.data[k]) FAIL("a pixel has two owners");
  }
  // The target's own silhouette ignores the occluder.
  CHECK(silhouette_mask(w, cam, w.target_id, renderer).data == silhouette_mask(w, cam, w.target_id).data);
}

TEST_CASE("ground truth masks are the same bytes for any thread count and repeated calls") {
  WorldParams p;
  p.seed = 21;
  p.n_gaussians = 2000;
  const World w = generate_world(p);
  const Rig rig = orbit_rig(w);
  const auto& cam = rig.train[5];
  const IdImage a = raycast(w, cam);
  const int threads = vcar::max_threads();
  vcar::set_num_threads(1);
  const IdImage b = raycast(w, cam);
  vcar::set_num_threads(threads);
  CHECK(a.id == b.id);
  CHECK(std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)) == 0);
  CHECK(visible_mask(w, cam, w.target_id).data == visible_mask(w, cam, w.target_id).data);
}
