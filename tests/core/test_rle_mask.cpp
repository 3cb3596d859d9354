#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <vector>

#include "vcar/core/parallel.hpp"
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

// The runs pixel by pixel: the definition that encode's 64-pixel words must reproduce.
static std::vector<std::uint32_t> runs_one_by_one(const vcar::Mask& m) {
  std::vector<std::uint32_t> runs;
  bool fg = false;
  std::uint32_t run = 0;
  for (std::uint8_t v : m.data) {
    if ((v != 0) != fg) runs.push_back(run), run = 0, fg = !fg;
    ++run;
  }
  runs.push_back(run);
  return runs;
}

TEST_CASE("run lengths equal the pixel-by-pixel runs across 64-pixel words") {
  std::mt19937 rng(11);
  // Sizes around whole words; runs from 1 pixel to several words; both ends fore- and background.
  for (int trial = 0; trial < 200; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 150), h = 1 + static_cast<int>(rng() % 5);
    vcar::Mask m(w, h, 1);
    const unsigned longest = 1u + rng() % 200;
    bool fg = rng() % 2;
    for (std::size_t k = 0; k < m.data.size();) {
      const std::size_t run = 1 + rng() % longest;
      for (std::size_t i = 0; i < run && k < m.data.size(); ++i, ++k)
        m.data[k] = fg ? static_cast<std::uint8_t>(1 + rng() % 255) : 0;
      fg = !fg;
    }
    CHECK(vcar::RleMask::encode(m).runs == runs_one_by_one(m));
  }
  vcar::Mask all(128, 1, 1), none(64, 2, 1), empty;
  std::fill(all.data.begin(), all.data.end(), 255);
  CHECK(vcar::RleMask::encode(all).runs == std::vector<std::uint32_t>{0, 128});
  CHECK(vcar::RleMask::encode(none).runs == std::vector<std::uint32_t>{128});
  CHECK(vcar::RleMask::encode(empty).runs == std::vector<std::uint32_t>{0});
}

TEST_CASE("large masks encode in blocks in parallel: the same runs as pixel by pixel, for any thread count") {
  std::mt19937 rng(13);
  // 1003 x 701 is above parallel_pixels; runs cross the blocks' borders (multiples of 2^16
  // pixels), and a run may start exactly at one.
  vcar::Mask m(1003, 701, 1);
  REQUIRE(m.data.size() >= vcar::RleMask::parallel_pixels);
  bool fg = false;
  for (std::size_t k = 0; k < m.data.size();) {
    const std::size_t run = 1 + rng() % (k < 300000 ? 40 : 90000);  // short runs, then runs longer than a block
    for (std::size_t i = 0; i < run && k < m.data.size(); ++i, ++k) m.data[k] = fg ? 200 : 0;
    fg = !fg;
  }
  m.data[std::size_t{1} << 16] = m.data[(std::size_t{1} << 16) - 1] ? 0 : 255;  // a boundary on a block's first pixel
  const int saved = vcar::max_threads();
  vcar::set_num_threads(1);
  const vcar::RleMask one = vcar::RleMask::encode(m);
  vcar::set_num_threads(std::max(2, saved));
  const vcar::RleMask many = vcar::RleMask::encode(m);
  vcar::set_num_threads(saved);
  CHECK(one.runs == runs_one_by_one(m));
  CHECK(many.runs == one.runs);
  std::fill(m.data.begin(), m.data.end(), 255);  // one run through every block
  CHECK(vcar::RleMask::encode(m).runs == std::vector<std::uint32_t>{0, static_cast<std::uint32_t>(m.data.size())});
}

TEST_CASE("MaskDecoder decodes a sequence of masks as RleMask::decode does, rewriting only foreground runs") {
  std::mt19937 rng(11);
  vcar::MaskDecoder decoder;
  // Sizes change now and then (a full decode), and consecutive masks of one size share nothing
  // on purpose: every pixel of the last foreground must be cleared.
  const int sizes[][2] = {{37, 23}, {37, 23}, {37, 23}, {64, 5}, {64, 5}, {37, 23}, {1, 1}, {1, 1}, {37, 23}};
  for (int round = 0; round < 3; ++round)
    for (const auto& wh : sizes) {
      vcar::Mask m(wh[0], wh[1], 1);
      const unsigned density = rng() % 5;  // 0: empty, 4: full
      for (auto& v : m.data) v = (rng() % 4 < density) ? 255 : 0;
      const auto r = vcar::RleMask::encode(m);
      const vcar::Mask& d = decoder.decode(r);
      REQUIRE(d.width == m.width);
      REQUIRE(d.height == m.height);
      REQUIRE(d.channels == 1);
      CHECK(d.data == r.decode().data);
    }
  // for_each_foreground: the runs in order, covering exactly the foreground.
  vcar::Mask m(9, 2, 1);
  for (int x : {0, 1, 4, 8, 9, 10, 17}) m.data[static_cast<std::size_t>(x)] = 7;
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  vcar::RleMask::encode(m).for_each_foreground([&](std::size_t b, std::size_t e) { runs.emplace_back(b, e); });
  CHECK(runs == std::vector<std::pair<std::size_t, std::size_t>>{{0, 2}, {4, 5}, {8, 11}, {17, 18}});
}
