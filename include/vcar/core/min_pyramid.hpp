#pragma once
// The least value of an image over a rectangle, from below: a pyramid of minima over 8 x 8
// pixel tiles (level 0), then 2 x 2 blocks of the level below. A query reads the cells of the
// first level where the rectangle touches at most 4 x 4 of them: the least value over those
// cells, which hold every pixel of the rectangle (and possibly more). So the answer is never
// above the rectangle's least value, exact when the rectangle is those cells, and O(1).
//
// NaN values count as -inf (a rectangle holding one has no lower bound). The voting of
// docs/robust.md asks it whether a whole chunk of means lies in front of a render's surface.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace vcar {

class MinPyramid {
public:
  static constexpr int tile = 8;

  // Rebuilds over a width x height image whose pixel p (row-major) has value(p) (capacity kept).
  template <class Value>
  void build(int width, int height, Value&& value) {
    width_ = width;
    height_ = height;
    levels_.clear();
    int w = (width + tile - 1) / tile, h = (height + tile - 1) / tile;
    if (levels_storage_.empty()) levels_storage_.emplace_back();
    std::vector<float>& base = levels_storage_[0];
    base.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), std::numeric_limits<float>::infinity());
    row_.resize(static_cast<std::size_t>(w) * tile);
    std::fill(row_.begin() + width, row_.end(), std::numeric_limits<float>::infinity());  // past the last tile's edge
    for (int y = 0; y < height; ++y) {  // a row's values (vectorisable), then its tiles' minima
      const std::size_t at = static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
      for (int x = 0; x < width; ++x) {
        const float v = value(at + static_cast<std::size_t>(x));
        row_[static_cast<std::size_t>(x)] = v == v ? v : -std::numeric_limits<float>::infinity();
      }
      float* cells = base.data() + static_cast<std::size_t>(y / tile) * static_cast<std::size_t>(w);
      for (int tx = 0; tx < w; ++tx) {
        const float* r = row_.data() + static_cast<std::size_t>(tx) * tile;
        float m = cells[tx];
        for (int i = 0; i < tile; ++i) m = std::min(m, r[i]);
        cells[tx] = m;
      }
    }
    levels_.push_back({w, h});
    for (std::size_t l = 1; w > 1 || h > 1; ++l) {
      const int w2 = (w + 1) / 2, h2 = (h + 1) / 2;
      if (levels_storage_.size() <= l) levels_storage_.emplace_back();
      const std::vector<float>& below = levels_storage_[l - 1];
      std::vector<float>& up = levels_storage_[l];
      up.assign(static_cast<std::size_t>(w2) * static_cast<std::size_t>(h2), std::numeric_limits<float>::infinity());
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          float& m = up[static_cast<std::size_t>(y / 2) * static_cast<std::size_t>(w2) + static_cast<std::size_t>(x / 2)];
          m = std::min(m, below[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)]);
        }
      levels_.push_back({w2, h2});
      w = w2, h = h2;
    }
  }

  // A lower bound of the values over the pixel rectangle [x0, x1] x [y0, y1] (inclusive,
  // clipped to the image; +inf when nothing of it is inside).
  float min_over(int x0, int y0, int x1, int y1) const {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0);
    x1 = std::min(x1, width_ - 1), y1 = std::min(y1, height_ - 1);
    if (x0 > x1 || y0 > y1) return std::numeric_limits<float>::infinity();
    int a = x0 / tile, b = y0 / tile, c = x1 / tile, d = y1 / tile;
    std::size_t l = 0;
    while (c - a >= 4 || d - b >= 4) a /= 2, b /= 2, c /= 2, d /= 2, ++l;
    const std::vector<float>& cells = levels_storage_[l];
    const std::size_t w = static_cast<std::size_t>(levels_[l].width);
    float m = std::numeric_limits<float>::infinity();
    for (int y = b; y <= d; ++y)
      for (int x = a; x <= c; ++x) m = std::min(m, cells[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)]);
    return m;
  }

private:
  struct Size {
    int width, height;
  };
  int width_ = 0, height_ = 0;
  std::vector<Size> levels_;                     // cells per level
  std::vector<std::vector<float>> levels_storage_;  // minima per level, row-major
  std::vector<float> row_;                       // one row's values, padded to whole tiles
};

}  // namespace vcar
