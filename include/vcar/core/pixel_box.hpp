#pragma once
// A rectangle of an image's pixels, and distance transforms over it: the mask measures of the
// robust vote (algo: Eq. R6, R11) read distances near a mask's contour, and a box around the
// mask holds most of them at a fraction of the whole image's cost.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vcar/core/distance_transform.hpp"
#include "vcar/core/image.hpp"

namespace vcar {

// The pixel rectangle [x0, x1) x [y0, y1) of an image.
struct PixelBox {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  // Whether every pixel of o lies in this box (an empty o does).
  bool contains(const PixelBox& o) const {
    return o.empty() || (!empty() && o.x0 >= x0 && o.y0 >= y0 && o.x1 <= x1 && o.y1 <= y1);
  }
  // The smallest box holding both.
  PixelBox united(const PixelBox& o) const {
    if (empty()) return o;
    if (o.empty()) return *this;
    return {std::min(x0, o.x0), std::min(y0, o.y0), std::max(x1, o.x1), std::max(y1, o.y1)};
  }
  // The box grown by g px on every side, clipped to a W x H image (empty stays empty).
  PixelBox grown(int g, int W, int H) const {
    if (empty()) return {};
    return {std::max(0, x0 - g), std::max(0, y0 - g), std::min(W, x1 + g), std::min(H, y1 + g)};
  }
  // Position of image pixel (x, y), inside the box, in row-major box order.
  std::size_t at(int x, int y) const { return static_cast<std::size_t>(y - y0) * width() + (x - x0); }
  // Every pixel of a W x H image outside the box lies at least this far from (x, y) inside it
  // (no_seed: the box is the whole image).
  double distance_to_outside(int x, int y, int W, int H) const {
    double r = no_seed;
    if (x0 > 0) r = std::min(r, double(x - x0 + 1));
    if (x1 < W) r = std::min(r, double(x1 - x));
    if (y0 > 0) r = std::min(r, double(y - y0 + 1));
    if (y1 < H) r = std::min(r, double(y1 - y));
    return r;
  }
};

// The bounding box of m's foreground grown by `grow` px on every side and clipped to the image;
// empty (x0 == x1) without foreground.
inline PixelBox foreground_box(const Mask& m, int grow) {
  PixelBox b{m.width, m.height, 0, 0};
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      if (m.data[static_cast<std::size_t>(y) * m.width + x]) {
        b.x0 = std::min(b.x0, x), b.y0 = std::min(b.y0, y);
        b.x1 = std::max(b.x1, x + 1), b.y1 = std::max(b.y1, y + 1);
      }
  if (b.x1 == 0) return {};
  return b.grown(grow, m.width, m.height);
}

// squared_distance_to over the box only: seed(x, y) for the box's pixels, distances by box
// position (PixelBox::at). Exact for the image when every seed lies in the box; otherwise a
// distance d2 <= o^2, o = PixelBox::distance_to_outside, is, and a larger one bounds the image's
// from above (which is at least o).
template <class Seed>
std::vector<double> squared_distance_in(const PixelBox& b, Seed&& seed) {
  std::vector<std::uint8_t> s(static_cast<std::size_t>(b.width()) * b.height());
  for (int y = b.y0; y < b.y1; ++y)
    for (int x = b.x0; x < b.x1; ++x) s[b.at(x, y)] = seed(x, y);
  return squared_distance_to(s, b.width(), b.height());
}

}  // namespace vcar
