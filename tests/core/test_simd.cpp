// The SIMD helper gives the same lane-wise results as plain scalar code on every target
// (SSE2, AVX2, AVX-512, NEON, and the scalar path itself); CI runs this in every architecture stage.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "vcar/core/simd.hpp"

namespace simd = vcar::simd;
using BF = simd::batch<float>;
using BI = simd::batch<std::int32_t>;
constexpr std::size_t L = simd::width;

TEST_CASE("simd: width is a power of two >= 4 and the same for float and int32", "[simd]") {
  CHECK(L >= 4);
  CHECK((L & (L - 1)) == 0);
  CHECK(BI::size == L);
  CHECK(std::string(simd::isa_name()).size() > 0);
}

TEST_CASE("simd: arithmetic, comparisons and select agree with scalar code lane by lane", "[simd]") {
  alignas(64) float a[L], b[L], out[L];
  for (std::size_t l = 0; l < L; ++l) {
    a[l] = 0.75f * static_cast<float>(l) - 2.f;
    b[l] = 1.5f - 0.25f * static_cast<float>(l * l);
  }
  const BF A = BF::load_aligned(a), B = BF::load_unaligned(b);
  (A * B + BF(1.f)).store_aligned(out);
  for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == a[l] * b[l] + 1.f);
  simd::max(A, B).store_aligned(out);
  for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == std::max(a[l], b[l]));
  simd::min(A, B).store_aligned(out);
  for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == std::min(a[l], b[l]));
  simd::select(A > B, A, -B).store_aligned(out);
  for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == (a[l] > b[l] ? a[l] : -b[l]));
  // fma: fused or not, within one rounding of the exact value.
  simd::fma(A, B, BF(0.1f)).store_aligned(out);
  for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == Approx(std::fma(a[l], b[l], 0.1f)).margin(1e-6));
  CHECK(simd::any(A > BF(a[L - 1] - 0.5f)));   // only the last lane
  CHECK(!simd::any(A > BF(a[L - 1])));
  CHECK(simd::any((A >= BF(a[1])) && (A <= BF(a[1]))));
}

TEST_CASE("simd: exp within 2 ulp of std::exp over the renderer's range", "[simd]") {
  alignas(64) float x[L], out[L];
  for (float x0 = -20.f; x0 <= 0.f; x0 += 0.37f) {
    for (std::size_t l = 0; l < L; ++l) x[l] = x0 + 0.01f * static_cast<float>(l);
    simd::exp(BF::load_aligned(x)).store_aligned(out);
    for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == Approx(std::exp(x[l])).epsilon(2.5e-7));
  }
}

TEST_CASE("simd: log within 2 ulp of std::log; floor and ceil exact (the renderer's projection)", "[simd]") {
  alignas(64) float x[L], out[L];
  for (float x0 = 1e-5f; x0 < 1e6f; x0 *= 1.61f) {  // ln(opacity / alpha_min) and beyond
    for (std::size_t l = 0; l < L; ++l) x[l] = x0 * (1.f + 0.011f * static_cast<float>(l));
    simd::log(BF::load_aligned(x)).store_aligned(out);
    for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == Approx(std::log(x[l])).epsilon(2.5e-7).margin(1e-7));
  }
  for (float x0 = -70.f; x0 <= 70.f; x0 += 0.73f) {  // tile coordinates, halves and integers included
    for (std::size_t l = 0; l < L; ++l) x[l] = l % 2 ? std::round(x0) + 0.5f * static_cast<float>(l) : x0 + 0.25f * static_cast<float>(l);
    simd::floor(BF::load_aligned(x)).store_aligned(out);
    for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == std::floor(x[l]));
    simd::ceil(BF::load_aligned(x)).store_aligned(out);
    for (std::size_t l = 0; l < L; ++l) CHECK(out[l] == std::ceil(x[l]));
  }
}

TEST_CASE("simd: sqrt is correctly rounded, as std::sqrt, bit for bit", "[simd]") {
  alignas(64) float x[L], out[L];
  int differing = 0;
  for (float x0 = 1e-6f; x0 < 1e6f; x0 *= 1.37f) {
    for (std::size_t l = 0; l < L; ++l) x[l] = x0 * (1.f + 0.013f * static_cast<float>(l));
    simd::sqrt(BF::load_aligned(x)).store_aligned(out);
    for (std::size_t l = 0; l < L; ++l) differing += out[l] != std::sqrt(x[l]);
  }
  x[0] = 0.f;
  simd::sqrt(BF::load_aligned(x)).store_aligned(out);
  CHECK(out[0] == 0.f);
  CHECK(differing == 0);
}

TEST_CASE("simd: to_int truncates, reduce_add sums, gather reads words[idx], integer shifts", "[simd]") {
  alignas(64) float f[L];
  alignas(64) std::int32_t idx[L], got[L];
  for (std::size_t l = 0; l < L; ++l) f[l] = 0.5f + 1.25f * static_cast<float>(l);
  simd::to_int(BF::load_aligned(f)).store_aligned(got);
  float sum = 0.f;
  for (std::size_t l = 0; l < L; ++l) {
    CHECK(got[l] == static_cast<std::int32_t>(f[l]));
    sum += f[l];
  }
  CHECK(simd::reduce_add(BF::load_aligned(f)) == Approx(sum).epsilon(1e-6));

  std::vector<std::int32_t> words(100);
  for (std::size_t k = 0; k < words.size(); ++k) words[k] = static_cast<std::int32_t>(k * k) - 1000;
  for (std::size_t l = 0; l < L; ++l) idx[l] = static_cast<std::int32_t>((l * 37 + 11) % words.size());
  simd::gather(words.data(), BI::load_aligned(idx)).store_aligned(got);
  for (std::size_t l = 0; l < L; ++l) CHECK(got[l] == words[static_cast<std::size_t>(idx[l])]);
  // Shifts left by a constant (the voting's tile-word index: (tile << 1) + half).
  ((BI::load_aligned(idx) << 1) + BI(1)).store_aligned(got);
  for (std::size_t l = 0; l < L; ++l) CHECK(got[l] == 2 * idx[l] + 1);
  // A bit lookup: (word >> (p & 31)) & 1 with shifts by a batch and by a constant.
  const BI p = BI::load_aligned(idx) * BI(7);
  ((simd::gather(words.data(), p >> 5) >> (p & BI(31))) & BI(1)).store_aligned(got);
  for (std::size_t l = 0; l < L; ++l) {
    const std::int32_t q = idx[l] * 7;
    CHECK(got[l] == ((words[static_cast<std::size_t>(q >> 5)] >> (q & 31)) & 1));
  }
  // shift_right (AVX-512's own variable shift; xsimd 8.1 has none there): arithmetic, every count
  // 0..31, negative words included.
  for (int base = 0; base < 32; base += static_cast<int>(L)) {
    alignas(64) std::int32_t w[L], s[L];
    for (std::size_t l = 0; l < L; ++l) {
      s[l] = (base + static_cast<int>(l)) % 32;
      w[l] = (l % 2 ? -1 : 1) * static_cast<std::int32_t>(0x12345678u >> (l % 5));
    }
    simd::shift_right(BI::load_aligned(w), BI::load_aligned(s)).store_aligned(got);
    for (std::size_t l = 0; l < L; ++l) CHECK(got[l] == (w[l] >> s[l]));
  }
}

TEST_CASE("simd: nonzero_bytes_64 and nonzero_bytes_8 set bit j iff byte j is nonzero", "[simd]") {
  std::mt19937 rng(17);
  alignas(64) std::uint8_t bytes[64 + 3];
  for (int rep = 0; rep < 200; ++rep) {
    for (auto& b : bytes) b = rng() % 3 == 0 ? static_cast<std::uint8_t>(rng() % 256) : 0;  // 0x80 and 0x01 included
    bytes[rep % 64] = rep % 2 ? 0x80 : 0x01;
    for (int offset : {0, 3}) {  // aligned and not
      const std::uint8_t* p = bytes + offset;
      std::uint64_t want = 0;
      for (int j = 0; j < 64; ++j) want |= static_cast<std::uint64_t>(p[j] != 0) << j;
      CHECK(vcar::simd::nonzero_bytes_64(p) == want);
      std::uint64_t v;
      std::memcpy(&v, p, 8);
      CHECK(vcar::simd::nonzero_bytes_8(v) == (want & 0xffu));
    }
  }
}

TEST_CASE("simd: nonzero_lanes sets bit l iff lane l is nonzero", "[simd]") {
  using BI = vcar::simd::batch<std::int32_t>;
  constexpr std::size_t L = BI::size;
  std::mt19937 rng(23);
  alignas(64) std::int32_t v[L];
  for (int rep = 0; rep < 300; ++rep) {
    std::uint32_t want = 0;
    for (std::size_t l = 0; l < L; ++l) {
      const int kind = static_cast<int>(rng() % 4);  // zero, small, negative, the sign bit alone
      v[l] = kind == 0 ? 0 : kind == 1 ? static_cast<std::int32_t>(rng() % 7 + 1)
                         : kind == 2 ? -static_cast<std::int32_t>(rng() % 1000 + 1) : std::numeric_limits<std::int32_t>::min();
      want |= static_cast<std::uint32_t>(v[l] != 0) << l;
    }
    CHECK(vcar::simd::nonzero_lanes(BI::load_aligned(v)) == want);
  }
  CHECK(vcar::simd::nonzero_lanes(BI(0)) == 0u);
  CHECK(vcar::simd::nonzero_lanes(BI(1)) == (L == 32 ? 0xffffffffu : (1u << L) - 1u));
}
