#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>

#include "io_test_util.hpp"
#include "vcar/io/ply.hpp"

using vcar_test::TempDir;
using vcar_test::read_bytes;
using vcar_test::require_error;
using vcar_test::write_bytes;
using vcar_test::append_le;

namespace {

const std::filesystem::path data_dir = VCAR_TEST_DATA_DIR;

// Independent tiny parser: float j of vertex i in an all-float binary PLY.
float raw_float(const std::string& file, std::size_t props, std::size_t i, std::size_t j) {
  const std::size_t body = file.find("end_header\n") + 11;
  float v;
  std::memcpy(&v, file.data() + body + (i * props + j) * 4, 4);
  return v;
}

std::string header(const std::string& format, std::size_t n, const std::vector<std::string>& props,
                   const std::string& type = "float") {
  std::string h = "ply\nformat " + format + " 1.0\nelement vertex " + std::to_string(n) + "\n";
  for (const auto& p : props) h += "property " + type + " " + p + "\n";
  return h + "end_header\n";
}

const std::vector<std::string> deg0 = {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity",
                                       "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"};

std::string binary_rows(const std::vector<std::vector<float>>& rows) {
  std::string s;
  for (const auto& r : rows) for (float v : r) append_le(s, v);
  return s;
}

std::vector<float> good_row(float x) { return {x, 2, 3, 0.1f, 0.2f, 0.3f, 0.5f, -1, -2, -3, 1, 0, 0, 0}; }

void check_same(const vcar::GaussianScene& a, const vcar::GaussianScene& b) {
  REQUIRE(a.size() == b.size());
  CHECK(a.sh_degree == b.sh_degree);
  for (int d = 0; d < 3; ++d) { CHECK(a.mean[d] == b.mean[d]); CHECK(a.log_scale[d] == b.log_scale[d]); }
  for (int k = 0; k < 4; ++k) CHECK(a.rotation[k] == b.rotation[k]);
  CHECK(a.opacity_logit == b.opacity_logit);
  CHECK(a.sh == b.sh);
  CHECK(a.extra_names == b.extra_names);
  CHECK(a.extra == b.extra);
}

}  // namespace

TEST_CASE("train-1000.ply: counts, SH degree 3, normals kept, values at known offsets") {
  const auto file = data_dir / "train-1000.ply";
  const auto s = vcar::io::read_ply(file);
  REQUIRE(s.size() == 1000);
  CHECK(s.sh_degree == 3);
  CHECK(s.extra_names == std::vector<std::string>{"nx", "ny", "nz"});
  const std::string raw = read_bytes(file);
  constexpr std::size_t P = 62;  // x y z nx ny nz f_dc(3) f_rest(45) opacity scale(3) rot(4)
  for (std::size_t i : {std::size_t{0}, std::size_t{1}, std::size_t{517}, std::size_t{999}}) {
    for (int d = 0; d < 3; ++d) CHECK(s.mean[d][i] == raw_float(raw, P, i, d));
    for (int e = 0; e < 3; ++e) CHECK(s.extra[i * 3 + e] == raw_float(raw, P, i, 3 + e));
    for (int c = 0; c < 3; ++c) CHECK(s.sh[i * 16 * 3 + c] == raw_float(raw, P, i, 6 + c));
    // f_rest_j is coefficient j % 15 + 1 of channel j / 15 (channel-major, conventions §1).
    for (std::size_t j = 0; j < 45; ++j)
      CHECK(s.sh[(i * 16 + j % 15 + 1) * 3 + j / 15] == raw_float(raw, P, i, 9 + j));
    CHECK(s.opacity_logit[i] == raw_float(raw, P, i, 54));
    for (int d = 0; d < 3; ++d) CHECK(s.log_scale[d][i] == raw_float(raw, P, i, 55 + d));
    for (int k = 0; k < 4; ++k) CHECK(s.rotation[k][i] == raw_float(raw, P, i, 58 + k));
  }
  CHECK(s.mean[0][0] == Approx(2.0958523750305176));  // read by hand (python struct)
}

TEST_CASE("donut.ply: SH degree 0, no extras, values at known offsets") {
  const auto file = data_dir / "donut.ply";
  const auto s = vcar::io::read_ply(file);
  REQUIRE(s.size() == 45624);
  CHECK(s.sh_degree == 0);
  CHECK(s.extra_names.empty());
  CHECK(s.sh.size() == 45624u * 3);
  const std::string raw = read_bytes(file);
  for (std::size_t i : {std::size_t{0}, std::size_t{12345}, std::size_t{45623}}) {
    for (int d = 0; d < 3; ++d) CHECK(s.mean[d][i] == raw_float(raw, 14, i, d));
    for (int c = 0; c < 3; ++c) CHECK(s.sh[i * 3 + c] == raw_float(raw, 14, i, 3 + c));
    CHECK(s.opacity_logit[i] == raw_float(raw, 14, i, 6));
    for (int d = 0; d < 3; ++d) CHECK(s.log_scale[d][i] == raw_float(raw, 14, i, 7 + d));
    for (int k = 0; k < 4; ++k) CHECK(s.rotation[k][i] == raw_float(raw, 14, i, 10 + k));
  }
}

TEST_CASE("write -> read -> write is bit-identical, and reproduces the Inria files") {
  TempDir tmp;
  for (const char* name : {"train-1000.ply", "donut.ply"}) {
    const auto s1 = vcar::io::read_ply(data_dir / name);
    vcar::io::write_ply(tmp / "a.ply", s1);
    const auto s2 = vcar::io::read_ply(tmp / "a.ply");
    check_same(s1, s2);
    vcar::io::write_ply(tmp / "b.ply", s2);
    CHECK(read_bytes(tmp / "a.ply") == read_bytes(tmp / "b.ply"));
    // Our header and property order are the Inria writer's, so the bytes match the original.
    CHECK(read_bytes(tmp / "a.ply") == read_bytes(data_dir / name));
  }
  // No temporary files are left behind.
  std::size_t files = 0;
  for (auto& e : std::filesystem::directory_iterator(tmp.path)) { (void)e; ++files; }
  CHECK(files == 2);
}

TEST_CASE("ASCII write and read are lossless") {
  TempDir tmp;
  const auto s1 = vcar::io::read_ply(data_dir / "train-1000.ply");
  vcar::io::write_ply(tmp / "a.ply", s1, /*binary=*/false);
  CHECK(read_bytes(tmp / "a.ply").find("format ascii 1.0") != std::string::npos);
  const auto s2 = vcar::io::read_ply(tmp / "a.ply");
  check_same(s1, s2);
}

TEST_CASE("properties matched by name, in any order, of any numeric type") {
  TempDir tmp;
  // ASCII, shuffled order, one custom extra, f_rest for degree 1 (9 values).
  std::vector<std::string> props = {"rot_3", "opacity", "f_dc_2", "label", "x", "scale_1", "rot_0",
                                    "z", "f_dc_0", "scale_0", "y", "rot_1", "f_dc_1", "scale_2", "rot_2"};
  for (int j = 8; j >= 0; --j) props.push_back("f_rest_" + std::to_string(j));
  std::string h = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 1\n";
  for (const auto& p : props) h += std::string("property ") + (p == "label" ? "uchar " : p == "x" ? "double " : "float ") + p + "\n";
  h += "end_header\n";
  // values: rot_3=.4 opacity=.5 f_dc_2=3 label=7 x=1.5 scale_1=-2 rot_0=.1 z=3.5 f_dc_0=1 scale_0=-1
  //         y=2.5 rot_1=.2 f_dc_1=2 scale_2=-3 rot_2=.3, then f_rest_8 .. f_rest_0 = 18 .. 10
  h += "0.4 0.5 3 7 1.5 -2 0.1 3.5 1 -1 2.5 0.2 2 -3 0.3 18 17 16 15 14 13 12 11 10\r\n";
  write_bytes(tmp / "a.ply", h);
  const auto s = vcar::io::read_ply(tmp / "a.ply");
  REQUIRE(s.size() == 1);
  CHECK(s.sh_degree == 1);
  CHECK(s.mu(0) == Eigen::Vector3f(1.5f, 2.5f, 3.5f));
  CHECK(s.log_scale[0][0] == -1.f); CHECK(s.log_scale[1][0] == -2.f); CHECK(s.log_scale[2][0] == -3.f);
  CHECK(s.rotation[0][0] == 0.1f); CHECK(s.rotation[3][0] == 0.4f);
  CHECK(s.opacity_logit[0] == 0.5f);
  REQUIRE(s.extra_names == std::vector<std::string>{"label"});
  CHECK(s.extra[0] == 7.f);
  // sh[k][c]: DC = f_dc; f_rest_j (j = 3c + k - 1 for B = 4) = 10 + j.
  for (int c = 0; c < 3; ++c) {
    CHECK(s.sh[c] == float(c + 1));
    for (int k = 1; k < 4; ++k) CHECK(s.sh[k * 3 + c] == float(10 + 3 * c + k - 1));
  }

  // Binary with doubles and ints.
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n";
  const std::vector<std::string> p2 = {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity",
                                       "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3", "id"};
  for (const auto& p : p2) b += (p == "id" ? "property int " : "property double ") + p + "\n";
  b += "end_header\n";
  for (int i = 0; i < 2; ++i) {
    for (int q = 0; q < 14; ++q) append_le(b, 0.25 * q + i);
    append_le(b, std::int32_t(-5 - i));
  }
  write_bytes(tmp / "b.ply", b);
  const auto t = vcar::io::read_ply(tmp / "b.ply");
  REQUIRE(t.size() == 2);
  CHECK(t.mean[1][1] == 1.25f);
  CHECK(t.rotation[3][0] == 0.25f * 13);
  CHECK(t.extra == std::vector<float>{-5.f, -6.f});
}

TEST_CASE("subset write with replacement log-scales") {
  TempDir tmp;
  const auto s = vcar::io::read_ply(data_dir / "train-1000.ply");
  const std::vector<vcar::Index> idx = {7, 3, 999};
  vcar::LogScales ls;
  for (int d = 0; d < 3; ++d) ls[d] = {-1.f - d, -2.f - d, -3.f - d};
  vcar::io::write_ply(tmp / "sub.ply", s, idx, &ls);
  const auto t = vcar::io::read_ply(tmp / "sub.ply");
  REQUIRE(t.size() == 3);
  CHECK(t.extra_names == s.extra_names);
  for (std::size_t r = 0; r < 3; ++r) {
    const std::size_t i = idx[r];
    CHECK(t.mu(r) == s.mu(i));
    for (int d = 0; d < 3; ++d) CHECK(t.log_scale[d][r] == ls[d][r]);
    for (int k = 0; k < 4; ++k) CHECK(t.rotation[k][r] == s.rotation[k][i]);
    for (int b = 0; b < 48; ++b) CHECK(t.sh[r * 48 + b] == s.sh[i * 48 + b]);
    for (int e = 0; e < 3; ++e) CHECK(t.extra[r * 3 + e] == s.extra[i * 3 + e]);
  }
  vcar::io::write_ply(tmp / "sub2.ply", s, idx);  // own scales
  const auto u = vcar::io::read_ply(tmp / "sub2.ply");
  CHECK(u.log_scale[0][1] == s.log_scale[0][3]);
  const std::vector<vcar::Index> bad = {1, 1000};
  require_error([&] { vcar::io::write_ply(tmp / "bad.ply", s, bad); }, {"1000", "out of range"});
  vcar::LogScales short_ls;
  require_error([&] { vcar::io::write_ply(tmp / "bad.ply", s, idx, &short_ls); }, {"log_scale", "expected 3"});
  CHECK(!std::filesystem::exists(tmp / "bad.ply"));
}

TEST_CASE("bad PLY input gives a clear error and writes nothing") {
  TempDir tmp;
  const auto path = tmp / "bad.ply";
  SECTION("truncated binary data") {
    std::string f = header("binary_little_endian", 3, deg0) + binary_rows({good_row(1), good_row(2)});
    f += binary_rows({good_row(3)}).substr(0, 20);
    write_bytes(path, f);
    require_error([&] { vcar::io::read_ply(path); }, {"bad.ply", "3 vertices", "truncated"});
  }
  SECTION("huge element count in a tiny file fails before allocating") {
    write_bytes(path, header("binary_little_endian", 4000000000ull, deg0) + binary_rows({good_row(1)}));
    require_error([&] { vcar::io::read_ply(path); }, {"4000000000", "truncated"});
    write_bytes(path, header("ascii", 4000000000ull, deg0) + "1 2 3\n");
    require_error([&] { vcar::io::read_ply(path); }, {"4000000000", "truncated"});
  }
  SECTION("header ending at the end of the file") {
    std::string h = header("ascii", 1, deg0);
    h.pop_back();  // no newline after end_header
    write_bytes(path, h);
    require_error([&] { vcar::io::read_ply(path); }, {"truncated"});
    std::string h0 = header("binary_little_endian", 0, deg0);
    h0.pop_back();
    write_bytes(path, h0);
    CHECK(vcar::io::read_ply(path).empty());
  }
  SECTION("truncated ASCII data") {
    // long tokens so that the size pre-check passes and the parser meets the end of data
    write_bytes(path, header("ascii", 2, deg0) + "1.000 2.000 3.000 0.000 0.000 0.000 0.000 0.000 0.000 0.000 1.000 0.000 0.000 0.000\n"
                                                 "1.000 2.000 3.000 0.000 0.000 0.000 0.000 0.000 0.000 0.000 1.000 0.000\n");
    require_error([&] { vcar::io::read_ply(path); }, {"vertex 1", "rot_2"});
  }
  SECTION("not a number in ASCII") {
    write_bytes(path, header("ascii", 1, deg0) + "1 2 3 0 0 0 0 0 0 0 1 0 0 abc\n");
    require_error([&] { vcar::io::read_ply(path); }, {"vertex 0", "rot_3", "abc"});
  }
  SECTION("missing properties are all named") {
    std::vector<std::string> p = deg0;
    p.erase(p.begin() + 10);  // rot_0
    p.erase(p.begin() + 6);   // opacity
    p.erase(p.begin() + 1);   // y
    write_bytes(path, header("binary_little_endian", 0, p));
    require_error([&] { vcar::io::read_ply(path); }, {"missing", "y", "opacity", "rot_0"});
  }
  SECTION("incomplete f_rest set") {
    std::vector<std::string> p = deg0;
    for (int j = 0; j < 8; ++j) p.push_back("f_rest_" + std::to_string(j));
    write_bytes(path, header("binary_little_endian", 0, p));
    require_error([&] { vcar::io::read_ply(path); }, {"8 f_rest_"});
  }
  SECTION("big-endian and unknown formats") {
    write_bytes(path, header("binary_big_endian", 1, deg0) + binary_rows({good_row(1)}));
    require_error([&] { vcar::io::read_ply(path); }, {"big-endian"});
    write_bytes(path, header("binary_middle_endian", 1, deg0) + binary_rows({good_row(1)}));
    require_error([&] { vcar::io::read_ply(path); }, {"unknown PLY format", "binary_middle_endian"});
  }
  SECTION("not a PLY / no end_header / bad property type / missing file") {
    write_bytes(path, "solid cube\n");
    require_error([&] { vcar::io::read_ply(path); }, {"not a PLY"});
    write_bytes(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
    require_error([&] { vcar::io::read_ply(path); }, {"end_header"});
    write_bytes(path, header("ascii", 1, deg0, "float128"));
    require_error([&] { vcar::io::read_ply(path); }, {"float128"});
    require_error([&] { vcar::io::read_ply(tmp / "nope.ply"); }, {"nope.ply"});
  }
  SECTION("NaN / Inf name the first bad Gaussian") {
    auto r3 = good_row(3);
    r3[8] = std::numeric_limits<float>::quiet_NaN();
    auto r4 = good_row(4);
    r4[0] = std::numeric_limits<float>::infinity();
    write_bytes(path, header("binary_little_endian", 5, deg0) +
                          binary_rows({good_row(0), good_row(1), good_row(2), r3, r4}));
    require_error([&] { vcar::io::read_ply(path); }, {"bad.ply", "Gaussian 3", "NaN"});
    write_bytes(path, header("ascii", 2, deg0) + "1 2 3 0 0 0 0 0 0 0 1 0 0 0\ninf 2 3 0 0 0 0 0 0 0 1 0 0 0\n");
    require_error([&] { vcar::io::read_ply(path); }, {"Gaussian 1"});
  }
  SECTION("zero quaternion") {
    auto r = good_row(1);
    r[10] = 0;
    write_bytes(path, header("binary_little_endian", 2, deg0) + binary_rows({good_row(0), r}));
    require_error([&] { vcar::io::read_ply(path); }, {"Gaussian 1", "zero quaternion"});
  }
  SECTION("a failed write leaves the old file intact and no temporary") {
    const auto s = vcar::io::read_ply(data_dir / "donut.ply");
    vcar::io::write_ply(path, s.subset({0, 1}));
    const std::string before = read_bytes(path);
    auto broken = s.subset({0, 1, 2});
    broken.rotation[0][2] = broken.rotation[1][2] = broken.rotation[2][2] = broken.rotation[3][2] = 0;
    require_error([&] { vcar::io::write_ply(path, broken); }, {"Gaussian 2"});
    CHECK(read_bytes(path) == before);
    require_error([&] { vcar::io::write_ply(tmp / "no_dir" / "x.ply", s); }, {"x.ply"});
    std::size_t files = 0;
    for (auto& e : std::filesystem::directory_iterator(tmp.path)) { (void)e; ++files; }
    CHECK(files == 1);
  }
}

TEST_CASE("other elements are skipped; duplicate properties are rejected") {
  TempDir tmp;
  const auto path = tmp / "e.ply";
  // Binary: a fixed-size element before `vertex`, a list element after it.
  std::string f = "ply\nformat binary_little_endian 1.0\ncomment x\nelement camera 2\nproperty double f\n"
                  "property uchar k\nelement vertex 2\n";
  for (const auto& p : deg0) f += "property float " + p + "\n";
  f += "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (int k = 0; k < 2; ++k) { append_le(f, 1.0); append_le(f, std::uint8_t(9)); }
  f += binary_rows({good_row(10), good_row(20)});
  append_le(f, std::uint8_t(3));
  for (int k = 0; k < 3; ++k) append_le(f, std::int32_t(k));
  write_bytes(path, f);
  auto s = vcar::io::read_ply(path);
  REQUIRE(s.size() == 2);
  CHECK(s.mean[0][0] == 10.f);
  CHECK(s.mean[0][1] == 20.f);
  CHECK(s.extra_names.empty());
  // ASCII: the rows of the earlier element are skipped line by line.
  std::string a = "ply\r\nformat ascii 1.0\r\nelement camera 1\r\nproperty float f\r\nelement vertex 1\r\n";
  for (const auto& p : deg0) a += "property float " + p + "\r\n";
  a += "end_header\r\n42\r\n7 2 3 0 0 0 0 0 0 0 1 0 0 0\r\n";
  write_bytes(path, a);
  s = vcar::io::read_ply(path);
  REQUIRE(s.size() == 1);
  CHECK(s.mean[0][0] == 7.f);
  std::vector<std::string> dup = deg0;
  dup.push_back("x");
  write_bytes(path, header("binary_little_endian", 0, dup));
  require_error([&] { vcar::io::read_ply(path); }, {"duplicate property 'x'"});
}

TEST_CASE("opacity logits of +-inf read as fully opaque / transparent, counted; other infinities refused") {
  TempDir tmp;
  const auto path = tmp / "inf.ply";
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> opaque = good_row(1), clear = good_row(2), opaque2 = good_row(3);
  opaque[6] = inf;
  clear[6] = -inf;
  opaque2[6] = inf;
  write_bytes(path, header("binary_little_endian", 4, deg0) + binary_rows({opaque, good_row(4), clear, opaque2}));
  vcar::InfiniteOpacities infinite;
  const vcar::GaussianScene g = vcar::io::read_ply(path, &infinite);
  CHECK(infinite.opaque == 2);
  CHECK(infinite.transparent == 1);
  CHECK(infinite.message() == "3 Gaussians had infinite opacity logits: read as fully opaque (2) or transparent (1)");
  CHECK(g.opacity(0) == 1.f);  // exactly, in float
  CHECK(g.opacity(2) == 0.f);
  CHECK(g.opacity(3) == 1.f);
  CHECK(g.opacity_logit[1] == 0.5f);  // finite logits untouched
  CHECK(std::isfinite(g.opacity_logit[0]));
  // Read the same without asking for the count: the same scene.
  check_same(vcar::io::read_ply(path), g);
  // ASCII files spell them "inf" / "-inf".
  write_bytes(path, header("ascii", 2, deg0) + "1 2 3 0 0 0 inf 0 0 0 1 0 0 0\n1 2 3 0 0 0 -inf 0 0 0 1 0 0 0\n");
  vcar::io::read_ply(path, &infinite);
  CHECK(infinite.opaque == 1);
  CHECK(infinite.transparent == 1);
  // A file without them reports zero and no message.
  write_bytes(path, header("binary_little_endian", 1, deg0) + binary_rows({good_row(1)}));
  vcar::io::read_ply(path, &infinite);
  CHECK(infinite.total() == 0);
  CHECK(infinite.message().empty());
  // NaN opacity, infinite positions, scales, rotations and colours stay refused.
  for (std::size_t col : {0u, 3u, 7u, 10u}) {
    std::vector<float> bad = good_row(1);
    bad[col] = inf;
    write_bytes(path, header("binary_little_endian", 1, deg0) + binary_rows({bad}));
    require_error([&] { vcar::io::read_ply(path); }, {"inf.ply", "Gaussian 0", "NaN or infinite"});
  }
  std::vector<float> nan_opacity = good_row(1);
  nan_opacity[6] = std::numeric_limits<float>::quiet_NaN();
  write_bytes(path, header("binary_little_endian", 1, deg0) + binary_rows({nan_opacity}));
  require_error([&] { vcar::io::read_ply(path); }, {"Gaussian 0", "NaN or infinite"});
}
