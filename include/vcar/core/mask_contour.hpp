#pragma once
// The contour of a mask (foreground pixels with a background 4-neighbour inside the image; the
// image border is not a contour) and the median and quartiles of a per-pixel value over it: what
// Eq. R6a and Eq. R11b measure (algo/undershoot.hpp, algo/overshoot.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "vcar/core/image.hpp"

namespace vcar {

// Calls f(q) (q = y * width + x) for every contour pixel of m, in row-major order.
template <class F>
void for_each_contour_pixel(const Mask& m, F&& f) {
  const int W = m.width, H = m.height;
  const std::uint8_t* M = m.data.data();
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * W + x;
      if (M[q] && ((x > 0 && !M[q - 1]) || (x + 1 < W && !M[q + 1]) || (y > 0 && !M[q - W]) ||
                   (y + 1 < H && !M[q + W])))
        f(q);
    }
}

// The quartiles {q1, median, q3} of value(q) over m's contour pixels whose value is not NaN:
// the elements at n / 4, n / 2 (the upper median for an even count) and 3n / 4 of the n sorted
// values; {0, 0, 0} when there is none.
template <class Value>
std::array<double, 3> contour_quartiles(const Mask& m, Value&& value) {
  std::vector<double> v;
  for_each_contour_pixel(m, [&](std::size_t q) {
    const double x = value(q);
    if (!std::isnan(x)) v.push_back(x);
  });
  if (v.empty()) return {0.0, 0.0, 0.0};
  std::sort(v.begin(), v.end());
  return {v[v.size() / 4], v[v.size() / 2], v[3 * v.size() / 4]};
}

// The median of contour_quartiles.
template <class Value>
double contour_median(const Mask& m, Value&& value) {
  return contour_quartiles(m, std::forward<Value>(value))[1];
}

}  // namespace vcar
