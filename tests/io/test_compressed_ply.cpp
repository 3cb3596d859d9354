#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>

#include "io_test_util.hpp"
#include "vcar/io/compressed_ply.hpp"
#include "vcar/io/scene_file.hpp"

using vcar_test::append_le;
using vcar_test::require_error;
using vcar_test::TempDir;
using vcar_test::write_bytes;

namespace {

const char* chunk_props[18] = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z",
                               "min_scale_x", "min_scale_y", "min_scale_z", "max_scale_x", "max_scale_y", "max_scale_z",
                               "min_r", "min_g", "min_b", "max_r", "max_g", "max_b"};

// A compressed PLY built byte by byte: `chunks` rows of 12 or 18 floats, 4 words per vertex,
// optional SH bytes (sh_rest per vertex).
std::string compressed(std::size_t n, const std::vector<std::vector<float>>& chunks, const std::vector<std::uint32_t>& words,
                       int sh_rest = 0, const std::vector<std::uint8_t>& sh = {}, const std::string& packed_type = "uint") {
  std::string h = "ply\nformat binary_little_endian 1.0\ncomment hand-made\nelement chunk " + std::to_string(chunks.size()) + "\n";
  for (std::size_t k = 0; k < chunks.at(0).size(); ++k) h += std::string("property float ") + chunk_props[k] + "\n";
  h += "element vertex " + std::to_string(n) + "\n";
  for (const char* p : {"packed_position", "packed_rotation", "packed_scale", "packed_color"})
    h += "property " + packed_type + " " + p + "\n";
  if (sh_rest) {
    h += "element sh " + std::to_string(n) + "\n";
    for (int j = 0; j < sh_rest; ++j) h += "property uchar f_rest_" + std::to_string(j) + "\n";
  }
  h += "end_header\n";
  for (const auto& c : chunks) for (float v : c) append_le(h, v);
  for (std::uint32_t w : words) append_le(h, w);
  for (std::uint8_t b : sh) h.push_back(static_cast<char>(b));
  return h;
}

std::uint32_t p111011(std::uint32_t x, std::uint32_t y, std::uint32_t z) { return x << 21 | y << 11 | z; }
std::uint32_t p8888(std::uint32_t r, std::uint32_t g, std::uint32_t b, std::uint32_t a) { return r << 24 | g << 16 | b << 8 | a; }
std::uint32_t prot(std::uint32_t largest, std::uint32_t a, std::uint32_t b, std::uint32_t c) { return largest << 30 | a << 20 | b << 10 | c; }

// Chunk: positions over [0, 2047] x [0, 1023] x [0, 2047] (a unorm step is 1), log-scales over
// [-1, 1], colours over [0, 1].
std::vector<float> unit_chunk() { return {0, 0, 0, 2047, 1023, 2047, -1, -1, -1, 1, 1, 1, 0, 0, 0, 1, 1, 1}; }

}  // namespace

TEST_CASE("compressed PLY: one Gaussian decoded by hand (11-10-11, 8888, smallest three, SH bytes)") {
  TempDir tmp;
  const auto f = tmp / "one.compressed.ply";
  std::vector<std::uint8_t> sh(9, 127);
  sh[0] = 0;    // -> -4
  sh[1] = 255;  // -> 4
  sh[2] = 128;  // -> ((128 + 0.5) / 256 - 0.5) * 8 = 0.015625
  write_bytes(f, compressed(1, {unit_chunk()},
                            {p111011(100, 200, 300), prot(1, 767, 255, 511), p111011(2047, 1023, 0), p8888(255, 0, 51, 204)}, 9, sh));
  const vcar::GaussianScene s = vcar::io::read_compressed_ply(f);
  REQUIRE(s.size() == 1);
  REQUIRE(s.sh_degree == 1);
  CHECK(s.mean[0][0] == Approx(100));
  CHECK(s.mean[1][0] == Approx(200));
  CHECK(s.mean[2][0] == Approx(300));
  CHECK(s.log_scale[0][0] == Approx(1));
  CHECK(s.log_scale[1][0] == Approx(1));
  CHECK(s.log_scale[2][0] == Approx(-1));
  CHECK(s.sh[0] == Approx(1.7724538509));   // colour 1
  CHECK(s.sh[1] == Approx(-1.7724538509));  // colour 0
  CHECK(s.sh[2] == Approx(-1.0634723105));  // colour 51 / 255 = 0.2
  CHECK(s.opacity_logit[0] == Approx(1.3862943611));  // alpha 0.8 -> log 4
  // largest = rot_1 (x); w, y, z from 767, 255, 511: (u / 1023 - 0.5) * sqrt(2).
  CHECK(s.rotation[0][0] == Approx(0.3532077861));
  CHECK(s.rotation[1][0] == Approx(0.8657422072));
  CHECK(s.rotation[2][0] == Approx(-0.3545902041));
  CHECK(s.rotation[3][0] == Approx(-0.0006912090).margin(1e-7));
  // f_rest_j: coefficient j % 3 + 1 of channel j / 3 (channel-major, like the Inria PLY).
  CHECK(s.sh[1 * 3 + 0] == -4.f);
  CHECK(s.sh[2 * 3 + 0] == 4.f);
  CHECK(s.sh[3 * 3 + 0] == Approx(0.015625));
  CHECK(s.sh[1 * 3 + 1] == Approx(-0.015625));
}

TEST_CASE("compressed PLY: Gaussian 256 uses chunk 1; without chunk colours the bytes are the colour") {
  TempDir tmp;
  std::vector<float> c0 = unit_chunk(), c1 = unit_chunk();
  c0.resize(12);
  c1.resize(12);
  c1[0] = 10.f;   // min_x of chunk 1
  c1[3] = 12.f;   // max_x
  std::vector<std::uint32_t> words;
  for (int i = 0; i < 257; ++i) {
    const std::uint32_t x = i == 256 ? 2047u : 5u;
    words.insert(words.end(), {p111011(x, 0, 0), prot(0, 512, 512, 512), p111011(1023, 511, 1023), p8888(51, 102, 153, 255)});
  }
  write_bytes(tmp / "two.ply", compressed(257, {c0, c1}, words));
  const vcar::GaussianScene s = vcar::io::read_compressed_ply(tmp / "two.ply");
  REQUIRE(s.size() == 257);
  CHECK(s.sh_degree == 0);
  CHECK(s.mean[0][255] == Approx(5));
  CHECK(s.mean[0][256] == Approx(12));
  CHECK(s.sh[0] == Approx((0.2 - 0.5) / 0.28209479177));
  CHECK(s.sh[2] == Approx((0.6 - 0.5) / 0.28209479177));
  CHECK(s.opacity_logit[0] == Approx(6.2324480166));  // alpha 1 is clamped half a step below 1
  vcar::io::SceneFormat f;
  CHECK(vcar::io::read_scene(tmp / "two.ply", &f).size() == 257);
  CHECK(f == vcar::io::SceneFormat::compressed_ply);
}

TEST_CASE("compressed PLY: bad input gives one-line errors naming the file") {
  TempDir tmp;
  const std::vector<std::uint32_t> w = {p111011(1, 1, 1), prot(0, 512, 512, 512), p111011(1, 1, 1), p8888(1, 1, 1, 1)};
  // 300 vertices need 2 chunks.
  std::vector<std::uint32_t> w300;
  for (int i = 0; i < 300; ++i) w300.insert(w300.end(), w.begin(), w.end());
  write_bytes(tmp / "chunks.ply", compressed(300, {unit_chunk()}, w300));
  require_error([&] { vcar::io::read_compressed_ply(tmp / "chunks.ply"); }, {"chunks.ply", "chunk has 1 rows", "need 2"});
  // A lying vertex count: more rows than the file holds, before anything is allocated.
  std::string lie = compressed(1, {unit_chunk()}, w);
  lie.replace(lie.find("element vertex 1\n"), 17, "element vertex 4000000000\n");
  write_bytes(tmp / "lie.ply", lie);
  require_error([&] { vcar::io::read_compressed_ply(tmp / "lie.ply"); }, {"lie.ply", "vertex", "4000000000", "truncated?"});
  // Truncated data.
  const std::string good = compressed(1, {unit_chunk()}, w);
  write_bytes(tmp / "cut.ply", good.substr(0, good.size() - 3));
  require_error([&] { vcar::io::read_compressed_ply(tmp / "cut.ply"); }, {"cut.ply", "truncated?"});
  // Wrong property type, and an SH element of the wrong width.
  write_bytes(tmp / "type.ply", compressed(1, {unit_chunk()}, {1, 2, 3, 4}, 0, {}, "int"));
  require_error([&] { vcar::io::read_compressed_ply(tmp / "type.ply"); }, {"type.ply", "packed_position", "must be uint"});
  write_bytes(tmp / "sh.ply", compressed(1, {unit_chunk()}, w, 10, std::vector<std::uint8_t>(10, 0)));
  require_error([&] { vcar::io::read_compressed_ply(tmp / "sh.ply"); }, {"sh.ply", "10 properties", "9, 24 or 45"});
  // Half of the colour bounds.
  std::vector<float> half = unit_chunk();
  half.resize(15);
  write_bytes(tmp / "half.ply", compressed(1, {half}, w));
  require_error([&] { vcar::io::read_compressed_ply(tmp / "half.ply"); }, {"half.ply", "missing", "all six or none"});
  // A NaN chunk bound.
  std::vector<float> nan_chunk = unit_chunk();
  nan_chunk[4] = std::nanf("");
  write_bytes(tmp / "nan.ply", compressed(1, {nan_chunk}, w));
  require_error([&] { vcar::io::read_compressed_ply(tmp / "nan.ply"); }, {"nan.ply", "chunk 0", "max_y", "not finite"});
}
