#include <catch2/catch.hpp>

#include <filesystem>

#include "io_test_util.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/selection_file.hpp"
#include "vcar/io/state_ply.hpp"

using vcar_test::require_error;
using vcar_test::TempDir;
using vcar_test::write_bytes;

namespace {
const std::filesystem::path selection_train = std::filesystem::path(VCAR_TEST_DATA_DIR) / "train-1000.ply";

// Selection {3, 10, 700} of `scene` with scores, scales and identity.
vcar::io::Selection three_selected(const vcar::GaussianScene& scene) {
  vcar::io::Selection s;
  s.indices = {3, 10, 700};
  s.scores = {0.9f, 0.8f, 0.7f};
  for (int d = 0; d < 3; ++d) s.log_scale[d] = {-1.f - d, -2.f - d, -3.f - d};
  s.scene_gaussians = scene.size();
  s.identity = vcar::io::selection_identity(vcar::io::gaussian_identities(scene), s.indices);
  return s;
}
}  // namespace

TEST_CASE("selection.json: written and read back; applied by identity to a re-ordered copy of its scene") {
  TempDir tmp;
  const vcar::GaussianScene scene = vcar::io::read_ply(selection_train);
  const vcar::io::Selection s = three_selected(scene);
  vcar::io::write_json_file(tmp / "selection.json", vcar::io::selection_json(s));
  const vcar::io::Selection r = vcar::io::read_selection(tmp / "selection.json", &scene);
  CHECK(r.indices == s.indices);
  CHECK(r.scores == s.scores);
  for (int d = 0; d < 3; ++d) CHECK(r.log_scale[d] == s.log_scale[d]);
  REQUIRE(r.identity);
  CHECK(r.identity->gaussians == s.identity->gaussians);

  // The scene reversed: Gaussian i is now n-1-i. The same three Gaussians, ascending again,
  // their scores and scales following them.
  std::vector<vcar::Index> rev(scene.size());
  for (std::size_t i = 0; i < rev.size(); ++i) rev[i] = static_cast<vcar::Index>(scene.size() - 1 - i);
  const vcar::GaussianScene reversed = scene.subset(rev);
  const vcar::io::Selection m = vcar::io::read_selection(tmp / "selection.json", &reversed);
  const std::size_t n = scene.size();
  CHECK(m.indices == std::vector<vcar::Index>{static_cast<vcar::Index>(n - 701), static_cast<vcar::Index>(n - 11),
                                              static_cast<vcar::Index>(n - 4)});
  CHECK(m.scores == std::vector<float>{0.7f, 0.8f, 0.9f});
  CHECK(m.log_scale[0] == std::vector<float>{-3.f, -2.f, -1.f});

  // Another scene (one Gaussian moved) is refused, naming the file.
  vcar::GaussianScene edited = scene;
  edited.mean[0][10] += 1.f;
  CHECK_THROWS_AS(vcar::io::read_selection(tmp / "selection.json", &edited), vcar::Error);
}

TEST_CASE("selection.json: several objects read as their union and one by one; bad files are named") {
  TempDir tmp;
  const vcar::GaussianScene scene = vcar::io::read_ply(selection_train);
  vcar::io::Selection a = three_selected(scene), b;
  b.indices = {10, 20};
  b.scores = {0.5f, 0.6f};
  b.scene_gaussians = scene.size();
  nlohmann::json ja = vcar::io::selection_json(a), jb = vcar::io::selection_json(b);
  ja["name"] = "a";
  jb["name"] = "b";
  jb["object_id"] = 4;
  vcar::io::write_json_file(tmp / "objects.json", {{"objects", {ja, jb}}});
  const auto objs = vcar::io::read_object_selections(tmp / "objects.json", &scene);
  REQUIRE(objs.size() == 2);
  CHECK(objs[0].name == "a");
  CHECK(objs[1].object_id == 4);
  CHECK(objs[1].selection.indices == b.indices);
  const vcar::io::Selection u = vcar::io::read_selection(tmp / "objects.json", &scene);
  CHECK(u.indices == std::vector<vcar::Index>{3, 10, 20, 700});
  CHECK(u.scores == std::vector<float>{0.9f, 0.8f, 0.6f, 0.7f});  // 10: the first object's entry
  CHECK(!u.has_log_scales());  // b has no refined scales

  write_bytes(tmp / "desc.json", R"({"indices": [5, 3]})");
  require_error([&] { vcar::io::read_selection(tmp / "desc.json"); }, {"desc.json", "strictly ascending"});
  write_bytes(tmp / "scales.json", R"({"indices": [1, 2], "log_scales": [[0, 0, 0]]})");
  require_error([&] { vcar::io::read_selection(tmp / "scales.json"); }, {"scales.json", "\"log_scales\" has 1"});
  write_bytes(tmp / "big.json", R"({"indices": [1, 5000]})");
  require_error([&] { vcar::io::read_selection(tmp / "big.json", &scene); }, {"big.json", "out of range"});
  write_bytes(tmp / "none.json", R"({"objects": []})");
  require_error([&] { vcar::io::read_object_selections(tmp / "none.json"); }, {"none.json", "non-empty array"});
}

TEST_CASE("a state PLY reads as a selection: selected and not deleted") {
  TempDir tmp;
  const vcar::GaussianScene scene = vcar::io::read_ply(selection_train);
  std::vector<std::uint8_t> state(scene.size(), 0);
  state[2] = vcar::io::splat_state::selected;
  state[9] = vcar::io::splat_state::selected | vcar::io::splat_state::deleted;
  state[40] = vcar::io::splat_state::selected;
  vcar::io::write_state_ply(tmp / "state.ply", scene, state);
  const vcar::io::Selection s = vcar::io::read_selection(tmp / "state.ply", &scene);
  CHECK(s.indices == std::vector<vcar::Index>{2, 40});
  require_error([&] { vcar::io::read_selection(selection_train); }, {"train-1000.ply", "without a 'state' property"});
}
