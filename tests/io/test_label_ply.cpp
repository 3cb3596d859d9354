#include <catch2/catch.hpp>

#include <cstring>

#include "io_test_util.hpp"
#include "vcar/io/label_ply.hpp"
#include "vcar/io/ply.hpp"

using vcar_test::read_bytes;
using vcar_test::require_error;
using vcar_test::TempDir;

TEST_CASE("labels PLY: the whole scene and a last int property, -1 for none") {
  TempDir tmp;
  vcar::GaussianScene s;
  s.resize(3, 0);
  for (std::size_t i = 0; i < 3; ++i) s.set(i, {float(i), 0, 0}, {-1, -1, -1}, {1, 0, 0, 0}, 0.5f);
  const std::vector<std::int32_t> label{1, -1, 0};
  SECTION("binary: 14 floats and 4 little-endian bytes per row") {
    vcar::io::write_label_ply(tmp / "l.ply", s, label);
    const std::string raw = read_bytes(tmp / "l.ply");
    CHECK(raw.find("property float rot_3\nproperty int label\nend_header\n") != std::string::npos);
    const std::size_t body = raw.find("end_header\n") + 11;
    REQUIRE(raw.size() == body + 3 * (14 * 4 + 4));
    std::int32_t l1;
    std::memcpy(&l1, raw.data() + body + 60 + 56, 4);
    CHECK(l1 == -1);
    CHECK(static_cast<unsigned char>(raw[body + 56]) == 1);  // row 0: 1, least significant byte first
    const vcar::GaussianScene back = vcar::io::read_ply(tmp / "l.ply");
    REQUIRE(back.extra_names == std::vector<std::string>{"label"});
    CHECK(back.extra == std::vector<float>{1.f, -1.f, 0.f});
    CHECK(back.mean[0] == s.mean[0]);
  }
  SECTION("ASCII, and a scene that already has a label column gets the new one") {
    s.extra_names = {"label"};
    s.extra = {7.f, 7.f, 7.f};
    vcar::io::write_label_ply(tmp / "a.ply", s, label, false);
    const vcar::GaussianScene back = vcar::io::read_ply(tmp / "a.ply");
    CHECK(back.extra == std::vector<float>{1.f, -1.f, 0.f});
  }
  require_error([&] { vcar::io::write_label_ply(tmp / "bad.ply", s, {1, 2}); }, {"bad.ply", "2 entries", "3 Gaussians"});
}
