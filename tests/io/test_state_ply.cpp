#include <catch2/catch.hpp>

#include <cstring>

#include "io_test_util.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/state_ply.hpp"

using vcar_test::read_bytes;
using vcar_test::require_error;
using vcar_test::TempDir;

namespace {

vcar::GaussianScene three() {
  vcar::GaussianScene s;
  s.resize(3, 0);
  for (std::size_t i = 0; i < 3; ++i) s.set(i, {float(i), 0, 0}, {-1, -1, -1}, {1, 0, 0, 0}, 0.5f);
  return s;
}

}  // namespace

TEST_CASE("state PLY: a last uchar property with SuperSplat's flags, one byte per row") {
  TempDir tmp;
  const vcar::GaussianScene s = three();
  const std::vector<std::uint8_t> state = vcar::io::selection_state(3, {0, 2});
  CHECK(state == std::vector<std::uint8_t>{1, 0, 1});
  vcar::io::write_state_ply(tmp / "s.ply", s, state);
  const std::string raw = read_bytes(tmp / "s.ply");
  const std::size_t body = raw.find("end_header\n") + 11;
  CHECK(raw.find("property float rot_3\nproperty uchar state\nend_header\n") != std::string::npos);
  // 14 floats + 1 byte per row; row 2's state byte is the last byte of the file.
  REQUIRE(raw.size() == body + 3 * (14 * 4 + 1));
  CHECK(raw[body + 56] == 1);
  CHECK(raw[body + 57 + 56] == 0);
  CHECK(raw.back() == 1);
  float x2;
  std::memcpy(&x2, raw.data() + body + 2 * 57, 4);
  CHECK(x2 == 2.f);

  const vcar::GaussianScene back = vcar::io::read_ply(tmp / "s.ply");
  CHECK(back.extra_names == std::vector<std::string>{"state"});
  CHECK(vcar::io::state_of(back) == state);
  CHECK(back.mean[0] == s.mean[0]);
  // Writing a scene that already has a state column replaces it (no duplicate property).
  vcar::io::write_state_ply(tmp / "s2.ply", back, {4, 4, 0});
  const vcar::GaussianScene again = vcar::io::read_ply(tmp / "s2.ply");
  CHECK(again.extra_names == std::vector<std::string>{"state"});
  CHECK(vcar::io::state_of(again) == std::vector<std::uint8_t>{4, 4, 0});
  // ASCII too.
  vcar::io::write_state_ply(tmp / "a.ply", s, state, false);
  CHECK(read_bytes(tmp / "a.ply").find(" 1\n") != std::string::npos);
  CHECK(vcar::io::state_of(vcar::io::read_ply(tmp / "a.ply")) == state);
}

TEST_CASE("state PLY: sizes and values are checked") {
  TempDir tmp;
  const vcar::GaussianScene s = three();
  require_error([&] { vcar::io::write_state_ply(tmp / "bad.ply", s, {1, 0}); }, {"bad.ply", "2 bytes", "3 Gaussians"});
  require_error([&] { vcar::io::selection_state(3, {5}); }, {"index 5"});
  CHECK(vcar::io::state_of(s).empty());
  vcar::GaussianScene odd = s;
  odd.extra_names = {"state"};
  odd.extra = {1.f, 2.5f, 0.f};
  require_error([&] { vcar::io::state_of(odd, "odd.ply"); }, {"odd.ply", "Gaussian 1", "integer 0..255"});
}
