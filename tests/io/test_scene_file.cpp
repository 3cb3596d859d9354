#include <catch2/catch.hpp>

#include <filesystem>

#include "io_test_util.hpp"
#include "vcar/io/scene_file.hpp"

using vcar::io::SceneFormat;
using vcar_test::read_bytes;
using vcar_test::require_error;
using vcar_test::TempDir;
using vcar_test::write_bytes;

namespace {
const std::filesystem::path train = std::filesystem::path(VCAR_TEST_DATA_DIR) / "train-1000.ply";
}

TEST_CASE("read_scene: the format comes from the content, not the name") {
  TempDir tmp;
  const vcar::GaussianScene src = vcar::io::read_ply(train);
  vcar::io::write_spz(tmp / "a.spz", src);
  vcar::io::write_splat(tmp / "a.splat", src);
  // Misnamed copies: an SPZ called .ply, a PLY called .splat, an SPZ called .splat.
  write_bytes(tmp / "spz_named.ply", read_bytes(tmp / "a.spz"));
  write_bytes(tmp / "ply_named.splat", read_bytes(train));
  write_bytes(tmp / "spz_named.splat", read_bytes(tmp / "a.spz"));
  CHECK(vcar::io::detect_scene_format(train) == SceneFormat::ply);
  CHECK(vcar::io::detect_scene_format(tmp / "a.spz") == SceneFormat::spz);
  CHECK(vcar::io::detect_scene_format(tmp / "a.splat") == SceneFormat::splat);
  CHECK(vcar::io::detect_scene_format(tmp / "spz_named.ply") == SceneFormat::spz);
  CHECK(vcar::io::detect_scene_format(tmp / "ply_named.splat") == SceneFormat::ply);
  CHECK(vcar::io::detect_scene_format(tmp / "spz_named.splat") == SceneFormat::spz);
  SceneFormat f;
  const vcar::GaussianScene s = vcar::io::read_scene(tmp / "ply_named.splat", &f);
  CHECK(f == SceneFormat::ply);
  CHECK(s.sh_degree == 3);
  CHECK(s.mean[0] == src.mean[0]);
  CHECK(vcar::io::read_scene(tmp / "spz_named.ply").sh_degree == 3);
  CHECK(vcar::io::read_scene(tmp / "a.splat").sh_degree == 0);
}

TEST_CASE("write_scene picks the format by extension; unknown files are refused by name") {
  TempDir tmp;
  const vcar::GaussianScene src = vcar::io::read_ply(train);
  for (const char* name : {"w.ply", "w.spz", "w.splat", "w.SPLAT"}) {
    vcar::io::write_scene(tmp / name, src);
    CHECK(vcar::io::read_scene(tmp / name).size() == src.size());
  }
  CHECK(vcar::io::detect_scene_format(tmp / "w.spz") == SceneFormat::spz);
  CHECK(vcar::io::detect_scene_format(tmp / "w.SPLAT") == SceneFormat::splat);
  write_bytes(tmp / "noise.bin", std::string(64, 'x'));
  require_error([&] { vcar::io::read_scene(tmp / "noise.bin"); }, {"noise.bin", "unrecognised scene file", "*.splat"});
  write_bytes(tmp / "short.bin", "pl");
  require_error([&] { vcar::io::read_scene(tmp / "short.bin"); }, {"short.bin", "unrecognised"});
  require_error([&] { vcar::io::read_scene(tmp / "missing.ply"); }, {"missing.ply", "cannot open"});
  require_error([&] { vcar::io::read_scene(tmp.path); }, {"cannot open"});
}
