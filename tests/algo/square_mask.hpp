#pragma once
// Test fixture: a W x H mask whose foreground (255) is the rectangle [x0, x1) x [y0, y1).
#include <cstddef>

#include "vcar/core/image.hpp"

inline vcar::Mask square_mask(int W, int H, int x0, int y0, int x1, int y1) {
  vcar::Mask m(W, H, 1);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) m.data[static_cast<std::size_t>(y) * W + x] = 255;
  return m;
}
