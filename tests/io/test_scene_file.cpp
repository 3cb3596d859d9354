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

TEST_CASE("read_scene from bytes reads every format as from the file; errors name the given name") {
  TempDir tmp;
  const vcar::GaussianScene src = vcar::io::read_ply(train);
  vcar::io::write_ply(tmp / "ascii.ply", src, false);
  vcar::io::write_spz(tmp / "a.spz", src);
  vcar::io::write_splat(tmp / "a.splat", src);
  auto bytes_of = [](const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); };
  auto same = [](const vcar::GaussianScene& a, const vcar::GaussianScene& b) {
    REQUIRE(a.size() == b.size());
    CHECK(a.sh_degree == b.sh_degree);
    for (int d = 0; d < 3; ++d) CHECK(a.mean[d] == b.mean[d]);
    for (int d = 0; d < 3; ++d) CHECK(a.log_scale[d] == b.log_scale[d]);
    for (int k = 0; k < 4; ++k) CHECK(a.rotation[k] == b.rotation[k]);
    CHECK(a.opacity_logit == b.opacity_logit);
    CHECK(a.sh == b.sh);
    CHECK(a.extra_names == b.extra_names);
    CHECK(a.extra == b.extra);
  };
  struct Case { std::filesystem::path file; std::string name; SceneFormat format; };
  for (const Case& c : {Case{train, "t.ply", SceneFormat::ply}, Case{tmp / "ascii.ply", "a.ply", SceneFormat::ply},
                        Case{tmp / "a.spz", "a.spz", SceneFormat::spz}, Case{tmp / "a.splat", "a.splat", SceneFormat::splat}}) {
    INFO(c.file.string());
    const auto bytes = bytes_of(read_bytes(c.file));
    SceneFormat f_file, f_bytes;
    const vcar::GaussianScene from_file = vcar::io::read_scene(c.file, &f_file);
    const vcar::GaussianScene from_bytes = vcar::io::read_scene(bytes, c.name, &f_bytes);
    CHECK(f_file == c.format);
    CHECK(f_bytes == c.format);
    same(from_bytes, from_file);
  }
  // SPZ v3 already inflated (a browser's DecompressionStream): the payload alone reads the same.
  const std::string payload = vcar::io::encode_spz_payload(src, "payload");
  same(vcar::io::read_scene(bytes_of(payload), "inflated.spz"), vcar::io::read_scene(tmp / "a.spz"));
  require_error([&] { vcar::io::read_scene(bytes_of(payload.substr(0, payload.size() / 2)), "cut.spz"); },
                {"cut.spz", "truncated?"});
  // Truncated PLY bytes and unrecognised bytes: the given name in the error.
  const std::string ply = read_bytes(train);
  require_error([&] { vcar::io::read_scene(bytes_of(ply.substr(0, ply.size() / 2)), "half.ply"); }, {"half.ply", "truncated"});
  require_error([&] { vcar::io::read_scene(bytes_of(std::string(64, 'x')), "noise.bin"); }, {"noise.bin", "unrecognised"});
  require_error([&] { vcar::io::read_scene(std::vector<std::uint8_t>{}, "empty.bin"); }, {"empty.bin", "unrecognised"});
  // A .splat has no signature: the name decides, for bytes as for files.
  CHECK(vcar::io::detect_scene_format(bytes_of(read_bytes(tmp / "a.splat")), "x.splat") == SceneFormat::splat);
}

TEST_CASE("ByteStream seeks within its bytes and fails outside them, as a file stream") {
  const std::vector<std::uint8_t> b = {'a', 'b', 'c', 'd', 'e'};
  vcar::io::detail::ByteStream in(b);
  char c = 0;
  in.seekg(3);
  in.get(c);
  CHECK(c == 'd');
  in.seekg(-4, std::ios::end);
  in.get(c);
  CHECK(c == 'b');
  in.seekg(1, std::ios::cur);
  in.get(c);
  CHECK(c == 'd');
  in.seekg(9);
  CHECK(in.fail());
  in.clear();
  in.get(c);
  CHECK(c == 'e');  // the failed seek left the position where it was
  CHECK(!in.get(c));
}
