#include <catch2/catch.hpp>

#include <zlib.h>
#include <zstd.h>

#include <cmath>
#include <cstdint>

#include "io_test_util.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/spz.hpp"

using vcar_test::append_le;
using vcar_test::read_bytes;
using vcar_test::require_error;
using vcar_test::TempDir;
using vcar_test::write_bytes;

namespace {

std::string gzip(const std::string& raw) {
  z_stream z{};
  REQUIRE(deflateInit2(&z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) == Z_OK);
  std::string out(deflateBound(&z, static_cast<uLong>(raw.size())) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
  z.avail_in = static_cast<uInt>(raw.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  REQUIRE(deflate(&z, Z_FINISH) == Z_STREAM_END);
  out.resize(out.size() - z.avail_out);
  deflateEnd(&z);
  return out;
}

std::string header16(std::uint32_t version, std::uint32_t n, int degree, int flags = 0) {
  std::string h;
  append_le(h, std::uint32_t{0x5053474e});
  append_le(h, version);
  append_le(h, n);
  h.push_back(static_cast<char>(degree));
  h.push_back(12);  // fractional bits
  h.push_back(static_cast<char>(flags));
  h.push_back(0);
  return h;
}

std::string bytes(std::initializer_list<int> v) {
  std::string s;
  for (int b : v) s.push_back(static_cast<char>(b));
  return s;
}

// One Gaussian, SH degree 1, in RUB as SPZ stores it:
//   position (1, -0.5, 2) -> RDF (1, 0.5, -2); alpha 204 (0.8); colour bytes 128, 255, 0;
//   log-scales 0, -1, 1 (bytes 160, 144, 176); quaternion xyzw (0.5, 0.5, 0.5, 0.5) as smallest
//   three (largest x, magnitudes 361 / 511 / sqrt 2); SH [k][c] with k = 1 (y), 2 (z), 3 (x).
std::string arrays_v3() {
  std::string a = bytes({0x00, 0x10, 0x00, 0x00, 0xf8, 0xff, 0x00, 0x20, 0x00});  // 4096, -2048, 8192
  a += bytes({204, 128, 255, 0, 160, 144, 176});
  std::uint32_t comp = 0;
  for (int k = 0; k < 3; ++k) comp = comp << 10 | 361u;
  append_le(a, comp);
  a += bytes({192, 64, 128, 0, 128, 128, 255, 128, 128});
  return a;
}

void check_hand_gaussian(const vcar::GaussianScene& s) {
  REQUIRE(s.size() == 1);
  REQUIRE(s.sh_degree == 1);
  CHECK(s.mean[0][0] == 1.f);
  CHECK(s.mean[1][0] == 0.5f);   // y flipped
  CHECK(s.mean[2][0] == -2.f);   // z flipped
  CHECK(s.opacity_logit[0] == Approx(1.3862943611));  // logit 0.8
  CHECK(s.sh[0] == Approx(0.0130718954).margin(1e-6));   // (128 / 255 - 0.5) / 0.15
  CHECK(s.sh[1] == Approx(3.3333333333));
  CHECK(s.sh[2] == Approx(-3.3333333333));
  CHECK(s.log_scale[0][0] == 0.f);
  CHECK(s.log_scale[1][0] == -1.f);
  CHECK(s.log_scale[2][0] == 1.f);
  // w = 361 / 511 / sqrt(2) = 0.4995412, x = sqrt(1 - 3 w^2) = 0.5013739; y, z flipped.
  CHECK(s.rotation[0][0] == Approx(0.4995411890));
  CHECK(s.rotation[1][0] == Approx(0.5013739138));
  CHECK(s.rotation[2][0] == Approx(-0.4995411890));
  CHECK(s.rotation[3][0] == Approx(-0.4995411890));
  // SH: (v - 128) / 128 times the RUB -> RDF sign of the basis (y: -1, z: -1, x: +1).
  CHECK(s.sh[3 + 0] == -0.5f);
  CHECK(s.sh[3 + 1] == 0.5f);
  CHECK(s.sh[3 + 2] == 0.f);
  CHECK(s.sh[6 + 0] == 1.f);
  CHECK(s.sh[9 + 0] == Approx(0.9921875));
}

std::string ngsp_v4(const std::string& arrays, std::uint32_t n, const std::string& extension = {}) {
  // Split the arrays of one Gaussian (9, 1, 3, 3, 4, 9 bytes) into six zstd frames.
  const std::size_t sizes[6] = {9 * n, n, 3 * n, 3 * n, 4 * n, 9 * n};
  std::string h;
  append_le(h, std::uint32_t{0x5053474e});
  append_le(h, std::uint32_t{4});
  append_le(h, n);
  h += bytes({1, 12, extension.empty() ? 0 : 2, 6});
  append_le(h, static_cast<std::uint32_t>(32 + extension.size()));
  h += std::string(12, '\0');
  h += extension;
  std::string frames;
  std::size_t at = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    std::string f(ZSTD_compressBound(sizes[k]), '\0');
    const std::size_t c = ZSTD_compress(f.data(), f.size(), arrays.data() + at, sizes[k], 3);
    REQUIRE_FALSE(ZSTD_isError(c));
    f.resize(c);
    append_le(h, static_cast<std::uint64_t>(c));
    append_le(h, static_cast<std::uint64_t>(sizes[k]));
    frames += f;
    at += sizes[k];
  }
  return h + frames;
}

}  // namespace

TEST_CASE("SPZ v3 (gzip): one Gaussian decoded by hand, RUB -> RDF") {
  TempDir tmp;
  write_bytes(tmp / "one.spz", gzip(header16(3, 1, 1) + arrays_v3()));
  check_hand_gaussian(vcar::io::read_spz(tmp / "one.spz"));
}

TEST_CASE("SPZ v4 (NGSP + zstd streams): the same Gaussian, extension records skipped") {
  TempDir tmp;
  write_bytes(tmp / "v4.spz", ngsp_v4(arrays_v3(), 1));
  check_hand_gaussian(vcar::io::read_spz(tmp / "v4.spz"));
  std::string ext;  // an unknown vendor record: skipped by its length
  append_le(ext, std::uint32_t{0x12340001});
  append_le(ext, std::uint32_t{4});
  append_le(ext, std::uint32_t{7});
  write_bytes(tmp / "ext.spz", ngsp_v4(arrays_v3(), 1, ext));
  check_hand_gaussian(vcar::io::read_spz(tmp / "ext.spz"));
}

TEST_CASE("SPZ v2: rotation as x y z bytes, w derived non-negative") {
  TempDir tmp;
  std::string a = arrays_v3();
  a.replace(16, 4, bytes({255, 128, 128}));  // x = 255 / 127.5 - 1 = 1, y = z = 0.0039
  write_bytes(tmp / "v2.spz", gzip(header16(2, 1, 1) + a));
  const vcar::GaussianScene s = vcar::io::read_spz(tmp / "v2.spz");
  CHECK(s.rotation[1][0] == 1.f);
  CHECK(s.rotation[2][0] == Approx(-0.0039215686).margin(1e-6));
  CHECK(s.rotation[0][0] == 0.f);  // sqrt(max(0, 1 - 1 - ...))
}

TEST_CASE("SPZ: re-encoding a decoded file reproduces its bytes; write -> read within the quantisation") {
  TempDir tmp;
  const std::string raw = header16(3, 1, 1) + arrays_v3();
  write_bytes(tmp / "one.spz", gzip(raw));
  const vcar::GaussianScene s = vcar::io::read_spz(tmp / "one.spz");
  CHECK(vcar::io::encode_spz_payload(s, "test") == raw);

  const vcar::GaussianScene src = vcar::io::read_ply(std::filesystem::path(VCAR_TEST_DATA_DIR) / "train-1000.ply");
  vcar::io::write_spz(tmp / "t.spz", src);
  const vcar::GaussianScene back = vcar::io::read_spz(tmp / "t.spz");
  REQUIRE(back.size() == src.size());
  REQUIRE(back.sh_degree == 3);
  for (std::size_t i = 0; i < src.size(); ++i) {
    for (int d = 0; d < 3; ++d) {
      CHECK(std::abs(back.mean[d][i] - src.mean[d][i]) <= 0.5f / 4096.f + 1e-6f);
      CHECK(std::abs(back.log_scale[d][i] - std::clamp(src.log_scale[d][i], -10.f, 5.9375f)) <= 1.f / 32.f + 1e-6f);
    }
    for (std::size_t b = 0; b < 48; ++b) {
      const float v = src.sh[i * 48 + b];
      if (b < 3) CHECK(std::abs(back.sh[i * 48 + b] - std::clamp(v, -127.5f / 38.25f, 127.5f / 38.25f)) <= 0.5f / 38.25f + 1e-5f);
      else CHECK(std::abs(back.sh[i * 48 + b] - std::clamp(v, -1.f, 127.f / 128.f)) <= 0.5f / 128.f + 1e-6f);
    }
  }
}

TEST_CASE("SPZ: bad input gives one-line errors naming the file") {
  TempDir tmp;
  const std::string good = gzip(header16(3, 1, 1) + arrays_v3());
  write_bytes(tmp / "cut.spz", good.substr(0, good.size() / 2));
  require_error([&] { vcar::io::read_spz(tmp / "cut.spz"); }, {"cut.spz", "gzip"});
  write_bytes(tmp / "short.spz", gzip(header16(3, 2, 1) + arrays_v3()));  // header says 2
  require_error([&] { vcar::io::read_spz(tmp / "short.spz"); }, {"short.spz", "truncated?"});
  write_bytes(tmp / "lie.spz", gzip(header16(3, 1000000000, 3) + arrays_v3()));
  require_error([&] { vcar::io::read_spz(tmp / "lie.spz"); }, {"lie.spz", "1000000000", "lying header?"});
  write_bytes(tmp / "magic.spz", gzip("XXXX" + header16(3, 1, 1).substr(4) + arrays_v3()));
  require_error([&] { vcar::io::read_spz(tmp / "magic.spz"); }, {"magic.spz", "NGSP"});
  write_bytes(tmp / "v9.spz", gzip(header16(9, 1, 1) + arrays_v3()));
  require_error([&] { vcar::io::read_spz(tmp / "v9.spz"); }, {"v9.spz", "version 9"});
  write_bytes(tmp / "deg4.spz", gzip(header16(3, 1, 4) + arrays_v3()));
  require_error([&] { vcar::io::read_spz(tmp / "deg4.spz"); }, {"deg4.spz", "degree 4", "-H 3"});
  write_bytes(tmp / "ext3.spz", gzip(header16(3, 1, 1, 2) + arrays_v3()));
  require_error([&] { vcar::io::read_spz(tmp / "ext3.spz"); }, {"ext3.spz", "extension"});
  // v4: a table of contents past the end, a stream larger than the rest of the file.
  std::string v4 = ngsp_v4(arrays_v3(), 1);
  std::string toc = v4;
  toc[19] = 0x10;  // offset >= 2^28
  write_bytes(tmp / "toc.spz", toc);
  require_error([&] { vcar::io::read_spz(tmp / "toc.spz"); }, {"toc.spz", "table of contents"});
  write_bytes(tmp / "cut4.spz", v4.substr(0, v4.size() - 4));
  require_error([&] { vcar::io::read_spz(tmp / "cut4.spz"); }, {"cut4.spz", "stream 5", "truncated?"});
  std::string n4 = v4;
  n4[8] = 2;  // two Gaussians: the streams' sizes no longer match
  write_bytes(tmp / "n4.spz", n4);
  require_error([&] { vcar::io::read_spz(tmp / "n4.spz"); }, {"n4.spz", "stream 0", "declares 9 bytes", "need 18"});
  // Writing refuses positions the 24-bit fixed point cannot hold.
  vcar::GaussianScene far;
  far.resize(1);
  far.mean[0][0] = 5000.f;
  require_error([&] { vcar::io::write_spz(tmp / "far.spz", far); }, {"far.spz", "Gaussian 0", "2048"});
}
