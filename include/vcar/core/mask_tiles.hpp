#pragma once
// A mask packed to bits in 8 x 8 pixel tiles, one 64-bit word per tile, and summarised to answer
// "is this rectangle all background, all foreground, or mixed?" in O(1).
//
// The bits: tile (tx, ty) is word ty * tiles_x() + tx, pixel (x, y) its bit (y % 8) * 8 + x % 8,
// so a few neighbouring pixels share one or two cache lines whatever their rows (voting's lookups
// of Morton-ordered means). Foreground = nonzero byte, as everywhere in voting; pixels past the
// image's right and bottom edges are 0.
//
// The summary: one integral image over the tile grid counts, in the low 16 bits of each 32-bit
// entry, the tiles with some foreground pixel and, in the high 16, the tiles whose pixels are all
// foreground (the entries wrap modulo 2^32; a rectangle's count, taken modulo 2^32 as well, is
// exact in both halves while it covers at most 65535 tiles). Both counts of a corner are in one
// load: half the bytes and lines of two images. The answer is exact for "none" and "all" and
// conservative otherwise (a rectangle that covers part of a mixed tile is "mixed" even if its own
// pixels agree; so is one of more than 65535 tiles, 4.2 Mpx).
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/rle_mask.hpp"
#include "vcar/core/simd.hpp"

namespace vcar {

class MaskTiles {
public:
  static constexpr int tile = 8;
  static constexpr std::size_t parallel_pixels = RleMask::parallel_pixels;  // masks this large pack in parallel
  enum Content : std::uint8_t { background = 0, mixed = 1, foreground = 2 };

  // Rebuilds for `m` (capacity is kept: no allocation when the size does not grow). One pass over
  // the mask's bytes packs the tiles (rows of tiles in parallel for large masks); the summary is
  // read from the tile words.
  void build(const Mask& m) {
    resize(m.width, m.height);
    const std::uint8_t* src = m.data.data();
    const int whole = width_ / tile, rest = width_ - whole * tile;
    const auto pack_tile_row = [&](std::int64_t ty) {  // writes tile row ty's words only
      std::uint64_t* out = words_.data() + static_cast<std::size_t>(ty) * tw_;
      std::fill(out, out + tw_, std::uint64_t{0});
      for (int y = static_cast<int>(ty) * tile; y < std::min(height_, static_cast<int>(ty + 1) * tile); ++y) {
        const std::uint8_t* row = src + static_cast<std::size_t>(y) * width_;
        const int shift = 8 * (y % tile);
        int tx = 0;
        for (; tx + 8 <= whole; tx += 8) {  // 8 whole tiles: 64 bytes at once
          const std::uint64_t bits = simd::nonzero_bytes_64(row + tx * tile);
          for (int i = 0; i < 8; ++i) out[tx + i] |= ((bits >> (8 * i)) & 0xffu) << shift;
        }
        for (; tx < whole; ++tx) {  // whole tiles: one 8-byte load
          std::uint64_t v;
          std::memcpy(&v, row + tx * tile, 8);
          out[tx] |= static_cast<std::uint64_t>(simd::nonzero_bytes_8(v)) << shift;
        }
        if (rest > 0) {  // the last, partial tile
          std::uint64_t v = 0;
          std::memcpy(&v, row + whole * tile, static_cast<std::size_t>(rest));
          out[whole] |= static_cast<std::uint64_t>(simd::nonzero_bytes_8(v)) << shift;
        }
      }
    };
    pack_rows(pack_tile_row);
  }

  // Rebuilds for the run-length encoded mask `r`, without decoding it: each tile row ORs in the
  // bits of the foreground runs that cross its pixel rows (tile rows in parallel for large
  // masks), in time that grows with the foreground's tiles rather than with the pixels.
  void build(const RleMask& r) {
    resize(r.width, r.height);
    const std::size_t W = static_cast<std::size_t>(width_);
    // first_run_[ty]: the first run that ends past the first pixel of tile row ty, and where it starts.
    first_run_.resize(static_cast<std::size_t>(th_));
    {
      std::size_t at = 0, i = 0;
      for (int ty = 0; ty < th_; ++ty) {
        const std::size_t row_begin = static_cast<std::size_t>(ty) * tile * W;
        while (i < r.runs.size() && at + r.runs[i] <= row_begin) at += r.runs[i++];
        first_run_[static_cast<std::size_t>(ty)] = {i, at};
      }
    }
    const auto pack_tile_row = [&](std::int64_t t) {  // writes tile row ty's words only
      const int ty = static_cast<int>(t);
      std::uint64_t* out = words_.data() + static_cast<std::size_t>(ty) * tw_;
      std::fill(out, out + tw_, std::uint64_t{0});
      const std::size_t row_begin = static_cast<std::size_t>(ty) * tile * W;
      const std::size_t row_end = std::min(static_cast<std::size_t>(height_), static_cast<std::size_t>(ty + 1) * tile) * W;
      auto [i, at] = first_run_[static_cast<std::size_t>(ty)];
      for (; i < r.runs.size() && at < row_end; at += r.runs[i++]) {
        if (i % 2 == 0 || r.runs[i] == 0) continue;  // background runs: even positions
        // The run's pixels in this tile row, one image row at a time.
        std::size_t b = std::max(at, row_begin);
        const std::size_t e = std::min(at + r.runs[i], row_end);
        while (b < e) {
          const std::size_t y = b / W, x0 = b - y * W, x1 = std::min(W, x0 + (e - b));
          set_bits(out, static_cast<int>(x0), static_cast<int>(x1), 8 * static_cast<int>(y % tile));
          b += x1 - x0;
        }
      }
    };
    pack_rows(pack_tile_row);
  }

  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  int tiles_x() const noexcept { return tw_; }
  // Per lane, 1 where pixel (iu, iv) is foreground, else 0; every pixel inside the image. Pixel
  // (x, y) is bit (y % 8) * 8 + x % 8 of tile word (y / 8) * tiles_x + x / 8, i.e. bit
  // (y % 4) * 8 + x % 8 of its 32-bit half (y % 8) / 4: one 32-bit gather per batch.
  simd::batch<std::int32_t> pixels(const simd::batch<std::int32_t>& iu, const simd::batch<std::int32_t>& iv) const {
    using BI = simd::batch<std::int32_t>;
    const BI word_index = ((((iv >> 3) * BI(tw_)) + (iu >> 3)) << 1) + ((iv >> 2) & BI(1));
    const BI shift = ((iv & BI(3)) << 3) + (iu & BI(7));
    return simd::shift_right(simd::gather(reinterpret_cast<const std::int32_t*>(words_.data()), word_index), shift) & BI(1);
  }
  // The tile words (see the top of the file), tiles_x() x ceil(height / 8).
  const std::uint64_t* words() const noexcept { return words_.data(); }

  // Content of the pixel rectangle [x0, x1] x [y0, y1] (inclusive; clipped to the image).
  Content classify(int x0, int y0, int x1, int y1) const {
    x0 = std::max(x0, 0); y0 = std::max(y0, 0);
    x1 = std::min(x1, width_ - 1); y1 = std::min(y1, height_ - 1);
    if (x0 > x1 || y0 > y1) return background;
    const int a = x0 / tile, b = y0 / tile, c = x1 / tile + 1, d = y1 / tile + 1;
    const std::size_t stride = static_cast<std::size_t>(tw_) + 1;
    const std::uint32_t tiles = static_cast<std::uint32_t>((c - a) * (d - b));
    if (tiles > 0xffffu) return mixed;  // the 16-bit halves below hold counts of up to 65535 tiles
    const std::uint32_t* I = counts_.data();
    const std::uint32_t sum = I[d * stride + c] - I[b * stride + c] - I[d * stride + a] + I[b * stride + a];
    if ((sum & 0xffffu) == 0) return background;
    if ((sum >> 16) == tiles) return foreground;
    return mixed;
  }

  // Bytes held: tile words and the integral image.
  std::size_t bytes() const {
    return words_.capacity() * sizeof(std::uint64_t) + counts_.capacity() * sizeof(std::uint32_t);
  }

private:
  // Sizes for a w x h mask: the tile words (each tile row zeroed by its packer) and the summary.
  void resize(int w, int h) {
    width_ = w;
    height_ = h;
    tw_ = (w + tile - 1) / tile;
    th_ = (h + tile - 1) / tile;
    words_.resize(static_cast<std::size_t>(tw_) * th_);
    counts_.resize((static_cast<std::size_t>(tw_) + 1) * (static_cast<std::size_t>(th_) + 1));
  }
  // pack_tile_row(ty) writes tile row ty's words; each row is counted by the thread that packed
  // it (tile rows in parallel for large masks), then the summary is integrated.
  template <class PackRow>
  void pack_rows(const PackRow& pack_tile_row) {
    const auto pack_and_count = [&](std::int64_t ty) {
      pack_tile_row(ty);
      count_tile_row(static_cast<int>(ty));
    };
    if (static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) >= parallel_pixels)
      parallel_for(th_, pack_and_count);
    else
      for (int ty = 0; ty < th_; ++ty) pack_and_count(ty);
    integrate_rows();
  }
  // The summary, in two steps. count_tile_row(ty) writes row ty + 1 of the integral image as
  // counts along tile row ty only (the packer's thread, right after packing it; column 0 is 0);
  // integrate_rows() then adds each row to the one below it, which makes it the integral image
  // of "some foreground" | "all foreground" << 16 over the tile grid (row 0 is 0).
  void count_tile_row(int ty) {
    const std::size_t stride = static_cast<std::size_t>(tw_) + 1;
    if (tw_ == 0) {  // an image 0 pixels wide: the row is its column 0
      counts_[(static_cast<std::size_t>(ty) + 1) * stride] = 0;
      return;
    }
    const int rest_x = width_ - (tw_ - 1) * tile, rest_y = height_ - (th_ - 1) * tile;
    const int rows = ty + 1 < th_ ? tile : rest_y;
    const std::uint64_t* w = words_.data() + static_cast<std::size_t>(ty) * tw_;
    std::uint32_t* out = counts_.data() + (static_cast<std::size_t>(ty) + 1) * stride;
    // A tile's in-image pixels: the low `cols` bits in each of its first `rows` bytes.
    const std::uint64_t row_bytes = 0x0101010101010101ULL >> (8 * (tile - rows));
    const std::uint64_t full = 0xffULL * row_bytes, last = ((1ULL << rest_x) - 1) * row_bytes;
    auto count = [](std::uint64_t word, std::uint64_t all) {  // some foreground | all foreground << 16
      return static_cast<std::uint32_t>(word != 0) + (static_cast<std::uint32_t>(word == all) << 16);
    };
    std::uint32_t run = 0;
    out[0] = 0;
    for (int tx = 0; tx + 1 < tw_; ++tx) out[tx + 1] = run += count(w[tx], full);
    out[tw_] = run + count(w[tw_ - 1], last);  // the last tile, perhaps partial
  }
  // Sets pixels [x0, x1) of one image row in a row of tile words, `shift` = 8 * (y % 8).
  static void set_bits(std::uint64_t* out, int x0, int x1, int shift) {
    const int t0 = x0 / tile, t1 = (x1 - 1) / tile;  // the first and last tile, x0 < x1
    const auto bits = [&](int lo, int hi) { return ((0xffULL >> (tile - (hi - lo))) << lo) << shift; };
    if (t0 == t1) {
      out[t0] |= bits(x0 - t0 * tile, x1 - t0 * tile);
      return;
    }
    out[t0] |= bits(x0 - t0 * tile, tile);
    const std::uint64_t whole = 0xffULL << shift;
    for (int tx = t0 + 1; tx < t1; ++tx) out[tx] |= whole;
    out[t1] |= bits(0, x1 - t1 * tile);
  }
  void integrate_rows() {
    const std::size_t stride = static_cast<std::size_t>(tw_) + 1;
    std::fill(counts_.begin(), counts_.begin() + static_cast<std::ptrdiff_t>(stride), 0u);
    for (std::size_t at = stride; at < counts_.size(); at += stride)
      add_row(counts_.data() + at, counts_.data() + at - stride, stride);
  }
  static void add_row(std::uint32_t* row, const std::uint32_t* above, std::size_t count) {
    using BI = simd::batch<std::int32_t>;  // wrapping adds: the same bits as uint32_t's
    auto* r = reinterpret_cast<std::int32_t*>(row);
    const auto* a = reinterpret_cast<const std::int32_t*>(above);
    std::size_t x = 0;
    for (; x + simd::width <= count; x += simd::width)
      (BI::load_unaligned(r + x) + BI::load_unaligned(a + x)).store_unaligned(r + x);
    for (; x < count; ++x) row[x] += above[x];
  }

  int width_ = 0, height_ = 0, tw_ = 0, th_ = 0;
  std::vector<std::uint64_t> words_;       // the packed tiles
  std::vector<std::uint32_t> counts_;      // integral counts over the tile grid: some fg | all fg << 16 (mod 2^32)
  std::vector<std::pair<std::size_t, std::size_t>> first_run_;  // build(RleMask): per tile row, run and its start
};

// mask_at (core/image.hpp) for a batch of points: per lane 1 where (u, v) lies inside the image
// on a foreground pixel (floor), else 0 (NaN: 0).
inline simd::batch<std::int32_t> mask_at(const MaskTiles& t, const simd::batch<float>& u, const simd::batch<float>& v) {
  using B = simd::batch<float>;
  const B zero(0.f);
  const auto in = (u >= zero) & (v >= zero) & (u < B(static_cast<float>(t.width()))) &
                  (v < B(static_cast<float>(t.height())));
  return t.pixels(simd::to_int(simd::select(in, u, zero)), simd::to_int(simd::select(in, v, zero))) &
         simd::to_int(simd::select(in, B(1.f), zero));
}

}  // namespace vcar
