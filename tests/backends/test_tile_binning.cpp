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
// rectangle), depths from a few values (many ties) or spread over [0.01, 100].
vcar::cpu::ProjectedSplats random_splats(std::size_t n, unsigned seed, bool ties) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> tile(0, 8), level(0, 6);  // rectangles inside 10 x 10 tiles
  std::uniform_real_distribution<float> U(0.f, 1.f);
  vcar::cpu::ProjectedSplats s;
  s.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    s.splat[k] = {};
    s.splat[k].depth = ties ? 0.5f + static_cast<float>(level(rng)) : 0.01f * std::pow(1e4f, U(rng));
    const int tx = tile(rng), ty = tile(rng);
    s.rect[k] = U(rng) < 0.25f ? 0 : vcar::cpu::pack_rect(tx, tx + 1 + tile(rng) % 2, ty, ty + 1);
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
      // Each tile's list is the depth ranks touching it, ascending (front to back).
      std::size_t entries = 0;
      for (int t = 0; t < bins.tiles(); ++t) {
        const auto b = bins.ids.begin() + bins.start[t], e = bins.ids.begin() + bins.start[t + 1];
        CHECK(std::is_sorted(b, e));
        entries += static_cast<std::size_t>(e - b);
      }
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
