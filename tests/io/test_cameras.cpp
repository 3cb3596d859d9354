#include <catch2/catch.hpp>

#include "io_test_util.hpp"
#include "vcar/io/cameras.hpp"

using vcar_test::TempDir;
using vcar_test::require_error;
using vcar_test::write_bytes;

namespace {
std::vector<vcar::Camera> two() {
  const vcar::Intrinsics k{64, 48, 50.f, 50.f, 32.f, 24.f};
  return {vcar::Camera::look_at({1, 2, 3}, {0, 0, 0}, {0, 0, 1}, k, "v1"),
          vcar::Camera::look_at({-2, 1, 1}, {0, 0, 0}, {0, 0, 1}, k, "v2")};
}
void same(const std::vector<vcar::Camera>& a, const std::vector<vcar::Camera>& b) {
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].name == b[i].name);
    CHECK((a[i].t_w - b[i].t_w).norm() < 1e-5f);
  }
}
}  // namespace

TEST_CASE("read_cameras detects the format from the path") {
  TempDir tmp;
  const auto cams = two();
  // COLMAP: the scene folder (sparse/0), the sparse folder itself, and a file inside it.
  vcar::io::write_colmap_text(tmp / "colmap" / "sparse" / "0", cams);
  same(vcar::io::read_cameras(tmp / "colmap"), cams);
  same(vcar::io::read_cameras(tmp / "colmap" / "sparse" / "0"), cams);
  same(vcar::io::read_cameras(tmp / "colmap" / "sparse" / "0" / "images.txt"), cams);
  // transforms.json and cameras.json, by folder and by file (any file name: by content).
  std::filesystem::create_directories(tmp / "ns");
  vcar::io::write_transforms_json(tmp / "ns" / "transforms.json", cams);
  same(vcar::io::read_cameras(tmp / "ns"), cams);
  vcar::io::write_transforms_json(tmp / "ns" / "other.json", cams);
  same(vcar::io::read_cameras(tmp / "ns" / "other.json"), cams);
  std::filesystem::create_directories(tmp / "inria");
  vcar::io::write_cameras_json(tmp / "inria" / "cameras.json", cams);
  same(vcar::io::read_cameras(tmp / "inria"), cams);
  same(vcar::io::read_cameras(tmp / "inria" / "cameras.json"), cams);
}

TEST_CASE("read_cameras: unknown formats are named") {
  TempDir tmp;
  require_error([&] { vcar::io::read_cameras(tmp.path); }, {tmp.path.string(), "no cameras found"});
  require_error([&] { vcar::io::read_cameras(tmp / "nothing"); }, {"nothing", "no such"});
  write_bytes(tmp / "x.json", R"({"a": 1})");
  require_error([&] { vcar::io::read_cameras(tmp / "x.json"); }, {"x.json", "neither"});
  write_bytes(tmp / "x.yaml", "a: 1");
  require_error([&] { vcar::io::read_cameras(tmp / "x.yaml"); }, {"x.yaml", "unknown camera format"});
}

TEST_CASE("read_cameras from bytes: both JSON formats by content, errors name the given name") {
  TempDir tmp;
  const auto cams = two();
  auto bytes_of = [](const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); };
  vcar::io::write_transforms_json(tmp / "t.json", cams);
  vcar::io::write_cameras_json(tmp / "c.json", cams);
  same(vcar::io::read_cameras(bytes_of(vcar_test::read_bytes(tmp / "t.json")), "upload.json"), cams);
  same(vcar::io::read_cameras(bytes_of(vcar_test::read_bytes(tmp / "c.json")), "upload.json"), cams);
  require_error([&] { vcar::io::read_cameras(bytes_of(R"({"a": 1})"), "up.json"); }, {"up.json", "neither"});
  require_error([&] { vcar::io::read_cameras(bytes_of("[{"), "bad.json"); }, {"bad.json", "malformed JSON"});
}
