#pragma once
// Projected splats and their binning into 16 x 16 pixel tiles: one entry
// per tile a bounding box touches, each tile's list front to back (gsplat's (tile, depth) order).

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "vcar/core/huge_pages.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/radix_sort.hpp"

namespace vcar::cpu {

inline constexpr int tile_size = 16;  // pixels per tile side (gsplat)
// Rounding slack on sigma_max wherever a test must not reject a pixel whose exact alpha test
// passes (the lanes then decide exactly); it covers the float error of the conic's quadratic.
inline constexpr float sigma_slack = 5e-2f;

// What compositing reads of one splat, packed in one cache line: a tile visits its splats in
// depth order, each once, so one line per splat beats a dozen scattered column reads.
struct alignas(64) PackedSplat {
  float mx, my;          // projected mean (px)
  float rx, ry;          // bounding-box half extents (px)
  float ca, cb, cc;      // conic: Sigma2D^-1 = [[ca, cb], [cb, cc]]
  float sigma_max;       // ln(255 opacity): alpha >= 1/255 iff sigma <= this
  float opacity, depth;  // sigmoid(o), camera-space z
  float r, g, b;         // colour from SH (batch_shading.hpp; 0 where the pass needs none)
  std::uint32_t k;       // index into the request's drawn list
  float ex, ey;          // half extents of sigma <= sigma_max + sigma_slack (px): no pixel beyond passes
};
static_assert(sizeof(PackedSplat) == 64, "one cache line per splat");

// One entry per drawn Gaussian (index k into the request's drawn list); a splat whose tile
// rectangle is empty is culled.
struct ProjectedSplats {
  // On huge pages where the OS has them: compositing reads the splats at random, one per entry,
  // over 64 MB at 1M, and with 4 KiB pages it waited on their address translation.
  std::vector<PackedSplat, HugePageAllocator<PackedSplat>> splat;
  std::vector<std::uint64_t> rect;  // touched tiles [tx0, tx1) x [ty0, ty1), 16 bits each (pack_rect)
  std::vector<float> depth;         // splat[k].depth again, packed: the depth sort reads only these

  void resize(std::size_t n) {
    splat.resize(n);
    rect.resize(n);
    depth.resize(n);
  }
  std::size_t size() const { return splat.size(); }
};

// Tile rectangle [tx0, tx1) x [ty0, ty1) in one word (tile counts are below 2^16).
inline std::uint64_t pack_rect(std::int32_t tx0, std::int32_t tx1, std::int32_t ty0, std::int32_t ty1) {
  return static_cast<std::uint64_t>(tx0) | static_cast<std::uint64_t>(tx1) << 16 |
         static_cast<std::uint64_t>(ty0) << 32 | static_cast<std::uint64_t>(ty1) << 48;
}
inline bool rect_empty(std::uint64_t r) {
  return (r & 0xffff) >= ((r >> 16) & 0xffff) || ((r >> 32) & 0xffff) >= (r >> 48);
}

// Tile lists as one flat array: ids[start[t] .. start[t+1]) are the drawn indices k of the
// splats touching tile t (ProjectedSplats::splat[k]), front to back; equal depths keep increasing
// k (deterministic).
struct TileBins {
  int tiles_x = 0, tiles_y = 0;
  std::vector<std::uint32_t> ids;
  std::vector<std::int64_t> start;          // tiles + 1 offsets
  std::vector<std::uint32_t> order;         // splats that touch a tile, by depth
  std::vector<std::uint64_t> record, record_tmp;  // scratch: depth bits << 32 | drawn index
  std::vector<std::uint64_t> rect;          // scratch: tile rectangles in depth order
  std::vector<std::int64_t> chunk_offset;   // scratch: per (chunk, tile) write cursor
  std::vector<std::int32_t> corner;         // scratch: per chunk, tile-corner differences
  std::vector<std::int32_t> open;           // scratch: summed-area table of the tiles not skipped
  int tiles() const { return tiles_x * tiles_y; }
};

// Fixed number of chunks (independent of the thread count) so binning is deterministic.
inline constexpr std::int64_t binning_chunks = 64;

// Splats that touch a tile, sorted by camera depth with ties by index: records
// (depth key << 32 | k), made in fixed blocks (compaction order = k order), then the stable
// radix sort of core/radix_sort.hpp. The key is the depth's bits less the least depth's bits:
// depth >= near plane > 0, so the bits order like the floats, and a scene's depths span far
// fewer than 32 bits of them (2 to 10: 25 bits, three passes of the sort instead of four).
// The same order for any thread count. Also sizes the tile grid for a width x height image.
inline void sort_by_depth(const ProjectedSplats& s, int width, int height, TileBins& bins) {
  bins.tiles_x = (width + tile_size - 1) / tile_size;
  bins.tiles_y = (height + tile_size - 1) / tile_size;
  constexpr std::int64_t block = std::int64_t{1} << 16;
  const auto n = static_cast<std::int64_t>(s.size());
  const std::int64_t blocks = (n + block - 1) / block;
  std::vector<std::int64_t> at(static_cast<std::size_t>(blocks) + 1, 0);
  std::vector<std::uint32_t> largest(static_cast<std::size_t>(blocks), 0);
  std::vector<std::uint32_t> least(static_cast<std::size_t>(blocks), ~std::uint32_t{0});
  parallel_for(blocks, [&](std::int64_t b) {  // kept splats and their depth bits' range per block
    std::int64_t kept = 0;
    std::uint32_t top = 0, bottom = ~std::uint32_t{0};
    for (std::int64_t k = b * block, e = std::min(n, k + block); k < e; ++k)
      if (!rect_empty(s.rect[k])) {
        ++kept;
        const auto bits = std::bit_cast<std::uint32_t>(s.depth[k]);
        top = std::max(top, bits);
        bottom = std::min(bottom, bits);
      }
    at[b + 1] = kept;
    largest[b] = top;
    least[b] = bottom;
  });
  for (std::int64_t b = 0; b < blocks; ++b) at[b + 1] += at[b];
  const auto m = static_cast<std::size_t>(at[blocks]);
  const std::uint32_t base = m ? *std::min_element(least.begin(), least.end()) : 0u;
  const std::uint32_t top = m ? *std::max_element(largest.begin(), largest.end()) - base : 0u;
  bins.record.resize(m);
  parallel_for(blocks, [&](std::int64_t b) {
    std::uint64_t* out = bins.record.data() + at[b];
    for (std::int64_t k = b * block, e = std::min(n, k + block); k < e; ++k)
      if (!rect_empty(s.rect[k]))
        *out++ = static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(s.depth[k]) - base) << 32 | static_cast<std::uint64_t>(k);
  });
  sort_by_upper_word(bins.record, bins.record_tmp, top);
  // The rectangles in depth order, for the counting and scatter passes. (The packed splats stay
  // where they are: gathering them in depth order, 64 bytes each, cost more than it saved the
  // compositing, which reads only the splats in front of saturated pixels.) Each rectangle is
  // asked for `ahead` records before its turn.
  bins.order.resize(m);
  bins.rect.resize(m);
  constexpr std::int64_t ahead = 16;
  parallel_chunks(static_cast<std::int64_t>(m), 4096, [&](std::int64_t, std::int64_t b, std::int64_t e) {
    for (std::int64_t j = b; j < e; ++j) {
      if (j + ahead < e) {
        const auto a = static_cast<std::uint32_t>(bins.record[j + ahead]);
        __builtin_prefetch(&s.rect[a]);
      }
      const auto k = static_cast<std::uint32_t>(bins.record[j]);
      bins.order[j] = k;
      bins.rect[j] = s.rect[k];
    }
  });
}

// Bins the splats of depth ranks [j0, j1) (sort_by_depth first) into the tiles t with
// !skip[t] (skip may be null: every tile): per-chunk counts, prefix sum in (tile, chunk) order,
// scatter; each tile's list is then front to back (gsplat's (tile, depth) sort). The renderer
// bins in waves of depth ranks and skips the tiles whose pixels have all saturated.
inline void bin_ranks(TileBins& bins, std::int64_t j0, std::int64_t j1, const std::uint8_t* skip = nullptr) {
  const std::int64_t T = bins.tiles(), n = j1 - j0;
  const std::int64_t chunk = std::max<std::int64_t>(1, (n + binning_chunks - 1) / binning_chunks);
  const std::int64_t C = n == 0 ? 0 : (n + chunk - 1) / chunk;
  bins.chunk_offset.assign(static_cast<std::size_t>(C * T), 0);
  std::int64_t* off = bins.chunk_offset.data();
  const std::uint64_t* rect = bins.rect.data() + j0;
  const std::uint32_t* order = bins.order.data() + j0;
  const int tiles_x = bins.tiles_x, tiles_y = bins.tiles_y;
  // Per-chunk tile counts from a difference grid: +1 at the rectangle's corners (tx0, ty0) and
  // (tx1, ty1), -1 at the other two, then a 2D prefix sum. Four increments per splat, whatever
  // its size (a loop over its tiles mispredicts its exits).
  const int DX = tiles_x + 1;
  const std::int64_t D = static_cast<std::int64_t>(DX) * (tiles_y + 1);
  // With skipped tiles: open[(ty) * DX + tx] = open tiles in [0, tx) x [0, ty) (a summed-area
  // table), so a splat whose rectangle holds no open tile is passed over in O(1).
  if (skip) {
    bins.open.assign(static_cast<std::size_t>(D), 0);
    for (int ty = 0; ty < tiles_y; ++ty)
      for (int tx = 0; tx < tiles_x; ++tx)
        bins.open[(ty + 1) * DX + tx + 1] = bins.open[ty * DX + tx + 1] + bins.open[(ty + 1) * DX + tx] -
                                            bins.open[ty * DX + tx] + (skip[ty * tiles_x + tx] ? 0 : 1);
  }
  const std::int32_t* open = bins.open.data();
  auto none_open = [&](int tx0, int tx1, int ty0, int ty1) {
    return skip && open[ty1 * DX + tx1] - open[ty0 * DX + tx1] - open[ty1 * DX + tx0] + open[ty0 * DX + tx0] == 0;
  };
  bins.corner.assign(static_cast<std::size_t>(C * D), 0);
  parallel_chunks(n, chunk, [&](std::int64_t c, std::int64_t b, std::int64_t e) {
    std::int32_t* d = bins.corner.data() + c * D;
    for (std::int64_t j = b; j < e; ++j) {
      const std::uint64_t r = rect[j];
      const int tx0 = static_cast<int>(r & 0xffff), tx1 = static_cast<int>((r >> 16) & 0xffff);
      const int ty0 = static_cast<int>((r >> 32) & 0xffff), ty1 = static_cast<int>(r >> 48);
      if (none_open(tx0, tx1, ty0, ty1)) continue;
      ++d[ty0 * DX + tx0];
      --d[ty0 * DX + tx1];
      --d[ty1 * DX + tx0];
      ++d[ty1 * DX + tx1];
    }
    std::int64_t* cnt = off + c * T;
    for (int ty = 0; ty < tiles_y; ++ty) {
      std::int32_t row = 0;  // running sum of this row's differences
      for (int tx = 0; tx < tiles_x; ++tx) {
        row += d[ty * DX + tx];
        cnt[ty * tiles_x + tx] = row + (ty > 0 ? cnt[(ty - 1) * tiles_x + tx] : 0);
      }
    }
    if (skip)
      for (std::int64_t t = 0; t < T; ++t)
        if (skip[t]) cnt[t] = 0;
  });
  bins.start.assign(static_cast<std::size_t>(T + 1), 0);
  std::int64_t run = 0;
  for (std::int64_t t = 0; t < T; ++t) {
    bins.start[t] = run;
    for (std::int64_t c = 0; c < C; ++c) {
      const std::int64_t cnt = off[c * T + t];
      off[c * T + t] = run;
      run += cnt;
    }
  }
  bins.start[T] = run;
  bins.ids.resize(static_cast<std::size_t>(run));
  std::uint32_t* ids = bins.ids.data();
  parallel_chunks(n, chunk, [&](std::int64_t c, std::int64_t b, std::int64_t e) {
    std::int64_t* cur = off + c * T;
    for (std::int64_t j = b; j < e; ++j) {
      // One loop over the rectangle's tiles (one exit to mispredict, not one per row).
      const std::uint64_t r = rect[j];
      const int tx0 = static_cast<int>(r & 0xffff), w = static_cast<int>((r >> 16) & 0xffff) - tx0;
      const int ty0 = static_cast<int>((r >> 32) & 0xffff), h = static_cast<int>(r >> 48) - ty0;
      if (none_open(tx0, tx0 + w, ty0, ty0 + h)) continue;
      int t = ty0 * tiles_x + tx0, col = 0;
      for (int k = w * h; k > 0; --k) {
        if (!skip || !skip[t]) ids[cur[t]++] = order[j];
        if (++col == w) col = 0, t += tiles_x - w + 1;
        else ++t;
      }
    }
  });
}

// All splats into all tiles: sort_by_depth, then bin_ranks over every rank.
inline void bin_tiles(const ProjectedSplats& s, int width, int height, TileBins& bins) {
  sort_by_depth(s, width, height, bins);
  bin_ranks(bins, 0, static_cast<std::int64_t>(bins.order.size()));
}

// Tiles touched by a bounding box [m - r, m + r] (clamped to the image's tiles, end exclusive).
inline void tile_rect(float m, float r, int tiles, std::int32_t& t0, std::int32_t& t1) {
  const float ts = static_cast<float>(tile_size);
  t0 = static_cast<std::int32_t>(std::clamp(std::floor((m - r) / ts), 0.f, static_cast<float>(tiles)));
  t1 = static_cast<std::int32_t>(std::clamp(std::ceil((m + r) / ts), 0.f, static_cast<float>(tiles)));
}

}  // namespace vcar::cpu
