#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

#include "io_test_util.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/splat_file.hpp"

using vcar_test::append_le;
using vcar_test::read_bytes;
using vcar_test::require_error;
using vcar_test::TempDir;
using vcar_test::write_bytes;

namespace {

std::string record(float x, float y, float z, float s0, float s1, float s2, std::uint8_t r, std::uint8_t g,
                   std::uint8_t b, std::uint8_t a, std::uint8_t q0, std::uint8_t q1, std::uint8_t q2, std::uint8_t q3) {
  std::string s;
  for (float v : {x, y, z, s0, s1, s2}) append_le(s, v);
  for (std::uint8_t v : {r, g, b, a, q0, q1, q2, q3}) s.push_back(static_cast<char>(v));
  return s;
}

}  // namespace

TEST_CASE(".splat: one record decoded by hand (linear scales, colour and alpha after activation)") {
  TempDir tmp;
  const auto f = tmp / "one.splat";
  write_bytes(f, record(1.5f, -2.f, 0.25f, 0.5f, 1.f, 2.f, 255, 128, 0, 191, 255, 128, 128, 128) +
                     record(0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 128, 0, 128, 255));
  const vcar::GaussianScene s = vcar::io::read_splat(f);
  REQUIRE(s.size() == 2);
  CHECK(s.sh_degree == 0);
  CHECK(s.mean[0][0] == 1.5f);
  CHECK(s.mean[1][0] == -2.f);
  CHECK(s.mean[2][0] == 0.25f);
  CHECK(s.log_scale[0][0] == Approx(-0.6931471806));  // log 0.5
  CHECK(s.log_scale[1][0] == Approx(0.0).margin(1e-7));
  CHECK(s.log_scale[2][0] == Approx(0.6931471806));
  CHECK(s.sh[0] == Approx(1.7724538509));   // (255/255 - 0.5) / C0
  CHECK(s.sh[1] == Approx(0.0069507994).margin(1e-6));   // (128/255 - 0.5) / C0
  CHECK(s.sh[2] == Approx(-1.7724538509));  // (0 - 0.5) / C0
  CHECK(s.opacity_logit[0] == Approx(1.0933903447));  // logit(191 / 255)
  CHECK(s.rotation[0][0] == Approx(0.9921875));       // (255 - 128) / 128
  for (int k = 1; k < 4; ++k) CHECK(s.rotation[k][0] == 0.f);
  // Alpha 0 is clamped half a step above 0: logit(0.5 / 255).
  CHECK(s.opacity_logit[1] == Approx(-6.2324480166));
  CHECK(s.rotation[1][1] == -1.f);
  CHECK(s.rotation[3][1] == Approx(127.f / 128.f));
}

TEST_CASE(".splat: encode rounds to the nearest byte and normalises the quaternion") {
  vcar::GaussianScene s;
  s.resize(1, 1);
  s.set(0, {1, 2, 3}, {0.f, std::log(2.f), -1.f}, {2, 0, 0, 0}, 0.f);  // |q| = 2: normalised
  s.sh[0] = 0.f;                 // colour 0.5 -> 127.5 -> 128
  s.sh[1] = 1.f / 0.28209479f;   // colour 1.5 -> clamped to 255
  s.sh[2] = -10.f;               // below 0 -> 0
  s.sh[3] = 5.f;                 // degree-1 SH: dropped
  const std::string b = vcar::io::encode_splat(s);
  REQUIRE(b.size() == 32);
  float v[6];
  std::memcpy(v, b.data(), 24);
  CHECK(v[0] == 1.f);
  CHECK(v[3] == 1.f);
  CHECK(v[4] == Approx(2.f));
  CHECK(v[5] == Approx(0.3678794412));  // exp(-1)
  const auto* u = reinterpret_cast<const std::uint8_t*>(b.data());
  CHECK(u[24] == 128);
  CHECK(u[25] == 255);
  CHECK(u[26] == 0);
  CHECK(u[27] == 128);  // sigmoid(0) * 255 = 127.5
  CHECK(u[28] == 255);  // 1 * 128 + 128 = 256, clamped
  CHECK(u[29] == 128);
}

TEST_CASE(".splat: write -> read keeps positions exactly and the rest within a byte") {
  TempDir tmp;
  const vcar::GaussianScene src = vcar::io::read_ply(std::filesystem::path(VCAR_TEST_DATA_DIR) / "train-1000.ply");
  vcar::io::write_splat(tmp / "t.splat", src);
  const vcar::GaussianScene back = vcar::io::read_splat(tmp / "t.splat");
  REQUIRE(back.size() == src.size());
  CHECK(back.sh_degree == 0);
  for (std::size_t i = 0; i < src.size(); ++i) {
    for (int d = 0; d < 3; ++d) {
      CHECK(back.mean[d][i] == src.mean[d][i]);
      CHECK(back.log_scale[d][i] == Approx(src.log_scale[d][i]).margin(1e-5));
    }
    const float a = vcar::io::sigmoid(src.opacity_logit[i]), b = vcar::io::sigmoid(back.opacity_logit[i]);
    CHECK(std::abs(a - b) <= 0.5f / 255.f + 1e-6f);
    for (std::size_t c = 0; c < 3; ++c) {
      const float want = std::clamp(vcar::io::colour_from_dc(src.sh[i * 48 + c]), 0.f, 1.f);
      CHECK(std::abs(vcar::io::colour_from_dc(back.sh[i * 3 + c]) - want) <= 0.5f / 255.f + 1e-6f);
    }
    float dot = 0, na = 0, nb = 0;
    for (int k = 0; k < 4; ++k) {
      dot += src.rotation[k][i] * back.rotation[k][i];
      na += src.rotation[k][i] * src.rotation[k][i];
      nb += back.rotation[k][i] * back.rotation[k][i];
    }
    CHECK(std::abs(dot) / std::sqrt(na * nb) >= 0.9995f);  // 8 bits per component: < 3.7 degrees
  }
}

TEST_CASE(".splat: bad input names the file and what is wrong") {
  TempDir tmp;
  const std::string good = record(0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 255, 128, 128, 128);
  write_bytes(tmp / "cut.splat", good + good.substr(0, 20));
  require_error([&] { vcar::io::read_splat(tmp / "cut.splat"); }, {"cut.splat", "not a multiple of 32"});
  write_bytes(tmp / "empty.splat", "");
  require_error([&] { vcar::io::read_splat(tmp / "empty.splat"); }, {"empty.splat", "empty"});
  write_bytes(tmp / "neg.splat", good + record(0, 0, 0, 1, -1, 1, 0, 0, 0, 0, 255, 128, 128, 128));
  require_error([&] { vcar::io::read_splat(tmp / "neg.splat"); }, {"neg.splat", "Gaussian 1", "byte 48", "scale"});
  write_bytes(tmp / "nan.splat", record(std::nanf(""), 0, 0, 1, 1, 1, 0, 0, 0, 0, 255, 128, 128, 128));
  require_error([&] { vcar::io::read_splat(tmp / "nan.splat"); }, {"nan.splat", "Gaussian 0", "NaN"});
  write_bytes(tmp / "zeroq.splat", record(0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 128, 128, 128, 128));
  require_error([&] { vcar::io::read_splat(tmp / "zeroq.splat"); }, {"zeroq.splat", "zero quaternion"});
  require_error([&] { vcar::io::read_splat(tmp / "missing.splat"); }, {"missing.splat", "cannot open"});
  // A zero linear scale (exp underflow of a very negative log-scale) is kept as the smallest float.
  write_bytes(tmp / "tiny.splat", record(0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 255, 128, 128, 128));
  CHECK(vcar::io::read_splat(tmp / "tiny.splat").log_scale[0][0] == Approx(std::log(std::numeric_limits<float>::denorm_min())));
}
