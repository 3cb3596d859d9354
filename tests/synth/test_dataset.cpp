#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>

#include <unistd.h>

#include "reference_renderer.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "synth_test_util.hpp"

using namespace vcar::synth;
namespace fs = std::filesystem;

namespace {
using vcar_test::fresh_dir;
RigParams small_rig() {
  RigParams p;
  p.intrinsics = make_intrinsics(96, 72);
  p.n_train = 5;
  p.n_eval = 2;
  return p;
}
}  // namespace

TEST_CASE("export a dataset, read the world back, rebuild the oracle from disk") {
  WorldParams wp;
  wp.seed = 9;
  wp.n_gaussians = 6000;
  const World w = generate_world(wp);
  const Rig rig = sparse_rig(w, small_rig());
  synth_test::ReferenceRenderer renderer;
  const fs::path dir = fresh_dir("export");
  export_dataset(dir, w, rig, renderer);

  for (const char* f : {"scene.ply", "cameras.json", "sparse/0/cameras.txt", "sparse/0/images.txt", "transforms.json",
                        "prompt.json", "gt/eval_cameras.json", "gt/gaussian_ids.bin", "gt/scene.json"})
    CHECK(fs::exists(dir / f));
  for (const auto& c : rig.train) {
    CHECK(fs::exists(dir / "images" / (c.name + ".png")));
    CHECK(fs::exists(dir / "gt" / "silhouettes" / (c.name + ".png")));
  }
  for (const auto& c : rig.eval) CHECK(fs::exists(dir / "gt" / "visible" / (c.name + ".png")));

  const World back = load_world(dir);
  CHECK(back.object_id == w.object_id);
  CHECK(back.target_id == w.target_id);
  CHECK(back.neighbour_id == w.neighbour_id);
  REQUIRE(back.primitives.size() == w.primitives.size());
  for (std::size_t k = 0; k < w.primitives.size(); ++k) {
    CHECK(back.primitives[k].type == w.primitives[k].type);
    CHECK(back.primitives[k].R == w.primitives[k].R);  // exact float round trip
    CHECK(back.primitives[k].t == w.primitives[k].t);
    CHECK(back.primitives[k].params == w.primitives[k].params);
  }
  CHECK(std::memcmp(back.scene.mean[0].data(), w.scene.mean[0].data(), w.scene.size() * 4) == 0);

  const Rig rig2 = load_rig(dir);
  REQUIRE(rig2.train.size() == rig.train.size());
  REQUIRE(rig2.eval.size() == rig.eval.size());
  CHECK(rig2.reference == rig.reference);
  CHECK(rig2.kind == "sparse");
  // The oracle rebuilt from disk reproduces the exported masks.
  OracleSegmenter oracle(back);
  for (std::size_t k = 0; k < rig2.train.size(); ++k) {
    CHECK((rig2.train[k].position() - rig.train[k].position()).norm() < 1e-5f);
    const vcar::Mask disk = vcar::io::read_mask(dir / "masks" / (rig2.train[k].name + ".png"), 96, 72);
    CHECK(disk.data == oracle.mask(rig.train[k], k)->data);
  }
  // Prompt points lie inside the reference view's visible mask.
  const auto pj = vcar::io::read_json_file(dir / "prompt.json");
  const vcar::Mask ref = vcar::io::read_mask(dir / "masks" / (rig.train[rig.reference].name + ".png"));
  REQUIRE(pj.at("points").size() == 3);
  for (const auto& p : pj.at("points")) CHECK(vcar::mask_at(ref, p[0].get<float>(), p[1].get<float>()));
  fs::remove_all(dir);
}

TEST_CASE("a trained object (donut.ply) inserted as the target: ground truth from its rendering") {
  const fs::path donut_path = fs::path(VCAR_TEST_DATA_DIR) / "donut.ply";
  if (!fs::exists(donut_path)) { WARN("tests/data/donut.ply missing"); return; }
  const vcar::GaussianScene donut = vcar::io::read_ply(donut_path);
  WorldParams wp;
  wp.seed = 4;
  wp.n_gaussians = 5000;
  World w = generate_world(wp);
  // Scale the donut's means to a radius of 0.15 and stand it on a free spot of the table.
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  for (std::size_t i = 0; i < donut.size(); ++i) { lo = lo.cwiseMin(donut.mu(i)); hi = hi.cwiseMax(donut.mu(i)); }
  const float s = 0.15f / (0.5f * (hi - lo).maxCoeff());
  const Eigen::Vector3f c = 0.5f * (lo + hi);
  insert_gaussians(w, donut, Eigen::Matrix3f::Identity(), Eigen::Vector3f(-0.2f, -0.45f, 0.2f) - s * c, s, 9);
  w.target_id = 9;
  RigParams rp = small_rig();
  const Rig rig = orbit_rig(w, rp);
  synth_test::ReferenceRenderer renderer;
  OracleParams op;
  op.mode = OracleMode::silhouette;
  OracleSegmenter oracle(w, op, renderer);
  const auto ids = w.gaussians_of(9);
  for (const auto& cam : rig.eval) {
    const vcar::Mask sil = silhouette_mask(w, cam, 9, renderer);
    CHECK(count(sil) > 200);
    CHECK(oracle.mask(cam, 0)->data == sil.data);
    vcar::RenderRequest q;
    q.scene = &w.scene;
    q.camera = &cam;
    q.subset = &ids;
    CHECK(vcar::threshold(renderer.render(q).alpha, 0.5f).data == sil.data);
    CHECK(count(visible_mask(w, cam, 9, renderer)) <= count(sil));
  }
}
