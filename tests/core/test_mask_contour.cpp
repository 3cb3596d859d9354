#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "vcar/core/mask_contour.hpp"

TEST_CASE("mask contour: foreground pixels with a background 4-neighbour, the image border excluded") {
  vcar::Mask m(6, 5, 1);
  for (int y = 1; y < 4; ++y)
    for (int x = 0; x < 4; ++x) m(x, y) = 255;  // [0, 4) x [1, 4): touches the left border
  std::vector<std::size_t> got;
  vcar::for_each_contour_pixel(m, [&](std::size_t q) { got.push_back(q); });
  // Row 1 and row 3 entirely (background above / below), row 2 only x = 3 (background at x = 4);
  // (0, 2) lies on the image border with foreground on its other three sides: not a contour.
  const std::vector<std::size_t> want{6, 7, 8, 9, 15, 18, 19, 20, 21};
  CHECK(got == want);
  vcar::Mask full(4, 4, 1, 255);
  got.clear();
  vcar::for_each_contour_pixel(full, [&](std::size_t q) { got.push_back(q); });
  CHECK(got.empty());
}

TEST_CASE("contour median: the upper median of the values that are not NaN, 0 without any") {
  vcar::Mask m(6, 5, 1);
  for (int y = 1; y < 4; ++y)
    for (int x = 0; x < 4; ++x) m(x, y) = 255;
  // Values: the pixel index; NaN for pixels of row 3 (18-21): median of {6, 7, 8, 9, 15} = 8.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(vcar::contour_median(m, [&](std::size_t q) { return q >= 18 ? nan : static_cast<double>(q); }) == 8.0);
  // Even count {6, 7, 8, 9, 15, 18}: the upper median, 9.
  CHECK(vcar::contour_median(m, [&](std::size_t q) { return q >= 19 ? nan : static_cast<double>(q); }) == 9.0);
  CHECK(vcar::contour_median(m, [&](std::size_t) { return nan; }) == 0.0);
  CHECK(vcar::contour_median(vcar::Mask(3, 3, 1), [](std::size_t) { return 1.0; }) == 0.0);
}

TEST_CASE("contour quartiles: the values at n / 4, n / 2 and 3n / 4 of the sorted values that are not NaN") {
  vcar::Mask m(6, 5, 1);
  for (int y = 1; y < 4; ++y)
    for (int x = 0; x < 4; ++x) m(x, y) = 255;
  // The 9 contour pixels {6, 7, 8, 9, 15, 18, 19, 20, 21} (the case above), values 21 - q:
  // sorted {0, 1, 2, 3, 6, 12, 13, 14, 15}: indices 2, 4 and 6.
  const auto q = vcar::contour_quartiles(m, [](std::size_t i) { return 21.0 - static_cast<double>(i); });
  CHECK(q == std::array<double, 3>{2.0, 6.0, 13.0});
  CHECK(vcar::contour_median(m, [](std::size_t i) { return 21.0 - static_cast<double>(i); }) == 6.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(vcar::contour_quartiles(m, [&](std::size_t) { return nan; }) == std::array<double, 3>{0.0, 0.0, 0.0});
}
