#include <catch2/catch.hpp>

#include <random>

#include "vcar/core/rle_mask.hpp"

TEST_CASE("run-length masks decode to the same foreground") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    vcar::Mask m(1 + static_cast<int>(rng() % 40), 1 + static_cast<int>(rng() % 30), 1);
    const unsigned density = rng() % 4;
    for (auto& v : m.data) v = (rng() % 4 < density) ? static_cast<std::uint8_t>(1 + rng() % 255) : 0;
    const auto r = vcar::RleMask::encode(m);
    const auto d = r.decode();
    REQUIRE(d.width == m.width);
    REQUIRE(d.height == m.height);
    std::size_t total = 0;
    for (auto run : r.runs) total += run;
    CHECK(total == m.pixels());
    for (std::size_t k = 0; k < m.data.size(); ++k) CHECK((d.data[k] != 0) == (m.data[k] != 0));
  }
}

TEST_CASE("a disc costs a few runs per row") {
  vcar::Mask m(200, 100, 1);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 200; ++x)
      m(x, y) = ((x - 100) * (x - 100) + (y - 50) * (y - 50) < 40 * 40) ? 255 : 0;
  const auto r = vcar::RleMask::encode(m);
  CHECK(r.runs.size() <= 2 * 100 + 1);
  CHECK(r.bytes() < m.pixels() / 10);
}
