#pragma once
// A mask summarised in 8 x 8 pixel tiles, to answer "is this rectangle all background, all
// foreground, or mixed?" in O(1): two integral images over the tile grid count the tiles with
// some foreground pixel and the tiles whose pixels are all foreground. The answer is exact for
// "none" and "all" and conservative otherwise (a rectangle that covers part of a mixed tile is
// "mixed" even if its own pixels agree). Foreground = nonzero byte, as everywhere in voting.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "vcar/core/image.hpp"

namespace vcar {

class MaskTiles {
public:
  static constexpr int tile = 8;
  enum Content : std::uint8_t { background = 0, mixed = 1, foreground = 2 };

  // Rebuilds for `m` (capacity is kept: no allocation when the size does not grow).
  void build(const Mask& m) {
    width_ = m.width;
    height_ = m.height;
    tw_ = (m.width + tile - 1) / tile;
    th_ = (m.height + tile - 1) / tile;
    const std::size_t stride = static_cast<std::size_t>(tw_) + 1;
    any_.assign(stride * (static_cast<std::size_t>(th_) + 1), 0);
    all_.assign(any_.size(), 0);
    row_any_.assign(static_cast<std::size_t>(tw_), 0);
    row_all_.assign(static_cast<std::size_t>(tw_), 0);
    const std::uint8_t* src = m.data.data();
    for (int ty = 0; ty < th_; ++ty) {
      std::fill(row_any_.begin(), row_any_.end(), 0);
      std::fill(row_all_.begin(), row_all_.end(), 1);
      const int y1 = std::min(height_, (ty + 1) * tile);
      for (int y = ty * tile; y < y1; ++y) {
        const std::uint8_t* row = src + static_cast<std::size_t>(y) * width_;
        int tx = 0;
        for (; (tx + 1) * tile <= width_; ++tx) {  // whole tiles: one 8-byte word
          std::uint64_t v;
          std::memcpy(&v, row + tx * tile, 8);
          const std::uint64_t nz = nonzero_bytes(v);
          row_any_[tx] |= nz != 0;
          row_all_[tx] &= nz == 0x8080808080808080ULL;
        }
        if (tx < tw_) {  // the last, partial tile
          const int n = width_ - tx * tile;
          std::uint64_t v = 0;
          std::memcpy(&v, row + tx * tile, static_cast<std::size_t>(n));
          const std::uint64_t nz = nonzero_bytes(v);
          row_any_[tx] |= nz != 0;
          row_all_[tx] &= nz == (0x8080808080808080ULL >> (8 * (8 - n)));
        }
      }
      std::uint32_t run_any = 0, run_all = 0;
      for (int tx = 0; tx < tw_; ++tx) {
        run_any += row_any_[tx];
        run_all += row_all_[tx];
        const std::size_t at = (static_cast<std::size_t>(ty) + 1) * stride + tx + 1;
        any_[at] = any_[at - stride] + run_any;
        all_[at] = all_[at - stride] + run_all;
      }
    }
  }

  // Content of the pixel rectangle [x0, x1] x [y0, y1] (inclusive; clipped to the image).
  Content classify(int x0, int y0, int x1, int y1) const {
    x0 = std::max(x0, 0); y0 = std::max(y0, 0);
    x1 = std::min(x1, width_ - 1); y1 = std::min(y1, height_ - 1);
    if (x0 > x1 || y0 > y1) return background;
    const int a = x0 / tile, b = y0 / tile, c = x1 / tile + 1, d = y1 / tile + 1;
    const std::size_t stride = static_cast<std::size_t>(tw_) + 1;
    auto sum = [&](const std::vector<std::uint32_t>& I) {
      return I[d * stride + c] - I[b * stride + c] - I[d * stride + a] + I[b * stride + a];
    };
    if (sum(any_) == 0) return background;
    if (sum(all_) == static_cast<std::uint32_t>((c - a) * (d - b))) return foreground;
    return mixed;
  }

  std::size_t bytes() const { return (any_.capacity() + all_.capacity()) * sizeof(std::uint32_t); }

private:
  // High bit of each byte set iff the byte is nonzero (no carry crosses a byte).
  static std::uint64_t nonzero_bytes(std::uint64_t v) {
    return (v | ((v & 0x7f7f7f7f7f7f7f7fULL) + 0x7f7f7f7f7f7f7f7fULL)) & 0x8080808080808080ULL;
  }

  int width_ = 0, height_ = 0, tw_ = 0, th_ = 0;
  std::vector<std::uint32_t> any_, all_;        // integral counts over the tile grid
  std::vector<std::uint8_t> row_any_, row_all_;  // one tile row, scratch
};

}  // namespace vcar
