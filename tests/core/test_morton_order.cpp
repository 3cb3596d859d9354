#include <catch2/catch.hpp>

#include <algorithm>
#include <numeric>
#include <random>

#include "vcar/core/morton_order.hpp"

TEST_CASE("morton_order: a stable sort by the interleaved 10-bit cell codes") {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> U(-3.f, 5.f);
  const std::size_t n = 3000;
  std::vector<float> x(n), y(n), z(n);
  for (std::size_t k = 0; k < n; ++k) { x[k] = U(rng); y[k] = U(rng); z[k] = 0.5f * U(rng); }
  x[10] = x[11]; y[10] = y[11]; z[10] = z[11];  // a tie
  z[20] = NAN;                                  // non-finite: the low corner
  // Brute force: bit b of axis d's 10-bit cell goes to bit 3 b + d.
  float lo[3], hi[3];
  const std::vector<float>* c[3] = {&x, &y, &z};
  for (int d = 0; d < 3; ++d) {
    lo[d] = INFINITY; hi[d] = -INFINITY;
    for (float v : *c[d]) if (std::isfinite(v)) { lo[d] = std::min(lo[d], v); hi[d] = std::max(hi[d], v); }
  }
  std::vector<std::uint32_t> code(n);
  for (std::size_t k = 0; k < n; ++k) {
    std::uint32_t m = 0;
    for (int d = 0; d < 3; ++d) {
      const float v = (*c[d])[k];
      const float t = std::isfinite(v) ? std::clamp((v - lo[d]) / (hi[d] - lo[d]) * 1024.f, 0.f, 1023.f) : 0.f;
      const auto cell = static_cast<std::uint32_t>(t);
      for (int b = 0; b < 10; ++b) m |= ((cell >> b) & 1u) << (3 * b + d);
    }
    code[k] = m;
  }
  std::vector<std::uint32_t> want(n);
  std::iota(want.begin(), want.end(), 0u);
  std::stable_sort(want.begin(), want.end(), [&](std::uint32_t a, std::uint32_t b) { return code[a] < code[b]; });
  const auto got = vcar::morton_order(x.data(), y.data(), z.data(), n);
  CHECK(std::vector<std::uint32_t>(got.begin(), got.end()) == want);
  CHECK(vcar::morton_order(x.data(), y.data(), z.data(), 0).empty());
  // By the code's top 20 or 10 bits: a stable sort by code >> 10 or >> 20 (cells of the coarser
  // grid keep their position order).
  for (int bits : {20, 10}) {
    std::vector<std::uint32_t> coarse(n);
    std::iota(coarse.begin(), coarse.end(), 0u);
    std::stable_sort(coarse.begin(), coarse.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return code[a] >> (30 - bits) < code[b] >> (30 - bits); });
    const auto by_bits = vcar::morton_order(x.data(), y.data(), z.data(), n, bits);
    CHECK(std::vector<std::uint32_t>(by_bits.begin(), by_bits.end()) == coarse);
    CHECK(coarse != want);  // the coarser sort is a different order here
  }
  CHECK_THROWS_AS(vcar::morton_order(x.data(), y.data(), z.data(), n, 0), vcar::Error);
  CHECK_THROWS_AS(vcar::morton_order(x.data(), y.data(), z.data(), n, 31), vcar::Error);
  const float one = 1.f;
  const auto single = vcar::morton_order(&one, &one, &one, 1);
  CHECK(std::vector<std::uint32_t>(single.begin(), single.end()) == std::vector<std::uint32_t>{0});
}

TEST_CASE("morton_order: the same order for any thread count, across its blocks of points") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(-2.f, 2.f);
  const std::size_t n = 200000;  // several blocks of 2^16 points
  std::vector<float> x(n), y(n), z(n);
  for (std::size_t k = 0; k < n; ++k) { x[k] = U(rng); y[k] = U(rng) * U(rng); z[k] = U(rng); }
  for (std::size_t k = 0; k < n; k += 977) x[k + 1] = x[k], y[k + 1] = y[k], z[k + 1] = z[k];  // ties across positions
  const int saved = vcar::max_threads();
  vcar::set_num_threads(1);
  const auto one = vcar::morton_order(x.data(), y.data(), z.data(), n);
  vcar::set_num_threads(std::max(2, saved));
  const auto many = vcar::morton_order(x.data(), y.data(), z.data(), n);
  vcar::set_num_threads(saved);
  CHECK(one == many);
  // A stable sort by code: every position once, codes non-decreasing, ties in position order.
  std::vector<std::uint32_t> seen(n, 0);
  for (std::uint32_t k : one) ++seen[k];
  CHECK(std::count(seen.begin(), seen.end(), 1u) == static_cast<std::ptrdiff_t>(n));
  const std::vector<float>* c[3] = {&x, &y, &z};
  float lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = *std::min_element(c[d]->begin(), c[d]->end());
    hi[d] = *std::max_element(c[d]->begin(), c[d]->end());
  }
  auto code = [&](std::uint32_t k) {
    std::uint32_t m = 0;
    for (int d = 0; d < 3; ++d) {
      const auto cell = static_cast<std::uint32_t>(std::clamp(((*c[d])[k] - lo[d]) / (hi[d] - lo[d]) * 1024.f, 0.f, 1023.f));
      for (int b = 0; b < 10; ++b) m |= ((cell >> b) & 1u) << (3 * b + d);
    }
    return m;
  };
  int out_of_order = 0;
  for (std::size_t j = 1; j < n; ++j) {
    const std::uint32_t a = code(one[j - 1]), b = code(one[j]);
    out_of_order += a > b || (a == b && one[j - 1] > one[j]);
  }
  CHECK(out_of_order == 0);
}
