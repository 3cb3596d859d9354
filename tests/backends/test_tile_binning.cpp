#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "vcar/backends/cpu/tile_binning.hpp"
#include "vcar/core/parallel.hpp"

namespace {

// n splats over several of sort_by_depth's 2^16-splat blocks: a quarter culled (empty
// rectangle), 1-3 x 1-3 tiles, depths from a few values (many ties) or spread over [0.01, 100].
vcar::cpu::ProjectedSplats random_splats(std::size_t n, unsigned seed, bool ties) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> tile(0, 8), level(0, 6);  // rectangles inside 10 x 10 tiles
  std::uniform_real_distribution<float> U(0.f, 1.f);
  vcar::cpu::ProjectedSplats s;
  s.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    s.splat[k] = {};
    s.splat[k].depth = s.depth[k] = ties ? 0.5f + static_cast<float>(level(rng)) : 0.01f * std::pow(1e4f, U(rng));
    const int tx = tile(rng), ty = tile(rng);
    const int w = std::min(1 + tile(rng) % 3, 10 - tx), h = std::min(1 + tile(rng) % 3, 10 - ty);
    s.rect[k] = U(rng) < 0.25f ? 0 : vcar::cpu::pack_rect(tx, tx + w, ty, ty + h);
  }
  return s;
}

}  // namespace

TEST_CASE("tile binning: depth order is the stable sort by depth, for any thread count") {
  const int saved = vcar::max_threads();
  for (bool ties : {true, false}) {
    const vcar::cpu::ProjectedSplats s = random_splats(200003, ties ? 3u : 4u, ties);
    // Brute force: the kept drawn indices, stably sorted by depth.
    std::vector<std::uint32_t> expected;
    for (std::size_t k = 0; k < s.size(); ++k)
      if (!vcar::cpu::rect_empty(s.rect[k])) expected.push_back(static_cast<std::uint32_t>(k));
    std::stable_sort(expected.begin(), expected.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return s.splat[a].depth < s.splat[b].depth; });
    REQUIRE(expected.size() > 100000);
    for (int threads : {1, 3}) {
      vcar::set_num_threads(threads);
      vcar::cpu::TileBins bins;
      vcar::cpu::bin_tiles(s, 160, 160, bins);
      CHECK(bins.order == expected);
      // Each tile's list holds drawn indices whose rectangle contains the tile, in ascending depth
      // rank (front to back).
      std::vector<std::uint32_t> rank(s.size(), 0);
      for (std::size_t j = 0; j < expected.size(); ++j) rank[expected[j]] = static_cast<std::uint32_t>(j);
      std::size_t entries = 0, outside = 0, unordered = 0;
      for (int t = 0; t < bins.tiles(); ++t) {
        const int tx = t % bins.tiles_x, ty = t / bins.tiles_x;
        for (std::int64_t e = bins.start[t]; e < bins.start[t + 1]; ++e) {
          const std::uint32_t k = bins.ids[e];
          const std::uint64_t r = s.rect[k];
          outside += !(tx >= int(r & 0xffff) && tx < int(r >> 16 & 0xffff) && ty >= int(r >> 32 & 0xffff) && ty < int(r >> 48));
          unordered += e > bins.start[t] && rank[bins.ids[e - 1]] >= rank[k];
        }
        entries += static_cast<std::size_t>(bins.start[t + 1] - bins.start[t]);
      }
      CHECK(outside == 0);
      CHECK(unordered == 0);
      std::size_t touched = 0;
      for (std::uint32_t k : expected) {
        const std::uint64_t r = s.rect[k];
        touched += ((r >> 16 & 0xffff) - (r & 0xffff)) * ((r >> 48) - (r >> 32 & 0xffff));
      }
      CHECK(entries == touched);
    }
  }
  vcar::set_num_threads(saved);
}

TEST_CASE("tile binning: one depth for every splat keeps drawn order (a zero-bit sort key)") {
  vcar::cpu::ProjectedSplats s = random_splats(70001, 5u, true);
  std::vector<std::uint32_t> expected;
  for (std::size_t k = 0; k < s.size(); ++k) {
    s.splat[k].depth = s.depth[k] = 3.25f;
    if (!vcar::cpu::rect_empty(s.rect[k])) expected.push_back(static_cast<std::uint32_t>(k));
  }
  vcar::cpu::TileBins bins;
  vcar::cpu::bin_tiles(s, 160, 160, bins);
  CHECK(bins.order == expected);
}
