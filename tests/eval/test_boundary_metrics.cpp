#include <catch2/catch.hpp>


#include "vcar/eval/boundary_metrics.hpp"

namespace {
vcar::Mask square_mask(int w, int h, int x0, int y0, int x1, int y1) {
  vcar::Mask m(w, h);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) m(x, y) = 255;
  return m;
}
}  // namespace

TEST_CASE("band width is 2% of the diagonal, at least 1") {
  CHECK(vcar::eval::band_width(640, 480) == 16);  // diagonal 800
  CHECK(vcar::eval::band_width(20, 20) == 1);     // 0.57 rounds to 1
  CHECK(vcar::eval::band_width(10, 10) == 1);     // 0.28 -> 0 -> clamped to 1
}

TEST_CASE("repeated 3x3 erosion shrinks a square by one pixel per side each time") {
  const auto m = square_mask(20, 20, 3, 3, 13, 13);
  const auto e = vcar::eval::erode3x3(vcar::eval::binary(m), 20, 20, 3, true);
  std::size_t n = 0;
  for (auto v : e) n += v;
  CHECK(n == 16);  // 10 - 2*3 = 4 per side
  CHECK(e[6 * 20 + 6] == 1);
  CHECK(e[5 * 20 + 6] == 0);
}

TEST_CASE("Boundary IoU of two offset squares (d = 1)") {
  // Bands are the 1-pixel inner rings (36 px each). GT ring: cols 2, 11 and rows 2, 11 over
  // [2,11]; prediction ring: cols 4, 13 and rows 2, 11 over [4,13]. Shared: rows 2 and 11 for
  // x in [4,11] = 16 px. Union 72 - 16 = 56 -> 2/7.
  const auto gt = square_mask(20, 20, 2, 2, 12, 12), pred = square_mask(20, 20, 4, 2, 14, 12);
  CHECK(vcar::eval::boundary_iou(pred, gt, 1) == Approx(16.0 / 56.0));
  CHECK(vcar::eval::boundary_iou(gt, gt, 1) == 1.0);
}

TEST_CASE("Boundary IoU counts the image border as a contour") {
  const vcar::Mask full(10, 10, 1, 255);
  const auto band = vcar::eval::boundary_band(full, 1);
  std::size_t n = 0;
  for (auto v : band) n += v;
  CHECK(n == 36);  // 100 - 8x8
}

TEST_CASE("Boundary F1 of two offset squares") {
  // Boundaries: the same two rings. With d = 1 a prediction ring pixel matches when a GT ring
  // pixel is within distance 1: rows 2/11 for x in [4,12] (18 px) and (4,3), (4,10) (2 px) -> 20
  // of 36. The configuration is mirror-symmetric (x -> 15 - x), so recall is 20/36 too.
  const auto gt = square_mask(20, 20, 2, 2, 12, 12), pred = square_mask(20, 20, 4, 2, 14, 12);
  const auto f = vcar::eval::boundary_f1(pred, gt, 1);
  CHECK(f.precision == Approx(20.0 / 36.0));
  CHECK(f.recall == Approx(20.0 / 36.0));
  CHECK(f.f1 == Approx(20.0 / 36.0));
  // With d = 2 every boundary pixel is within 2 of the other ring.
  CHECK(vcar::eval::boundary_f1(pred, gt, 2).f1 == Approx(1.0));
}

TEST_CASE("Boundary F1 does not count the image border as a contour") {
  const vcar::Mask full(10, 10, 1, 255), empty(10, 10);
  const auto f = vcar::eval::boundary_f1(full, full, 1);
  CHECK(f.f1 == 1.0);
  CHECK(vcar::eval::boundary_map(full)[0] == 0);
  CHECK(vcar::eval::boundary_f1(empty, empty, 1).f1 == 1.0);
  CHECK(vcar::eval::boundary_f1(square_mask(10, 10, 2, 2, 5, 5), empty, 1).f1 == 0.0);
  CHECK(vcar::eval::boundary_f1(empty, square_mask(10, 10, 2, 2, 5, 5), 1).f1 == 0.0);
}

TEST_CASE("Trimap IoU of two offset squares (d = 1)") {
  // Band: GT inner ring (36) + outer ring at Euclidean distance 1 (44 - 4 diagonal corners = 40).
  // G in band = 36. P in band: inner ring with x >= 4 (rows 2/11: 16, col 11: 8) + outer col 12
  // for y in [2,11] (10) = 34. Intersection 24, union 36 + 34 - 24 = 46.
  const auto gt = square_mask(20, 20, 2, 2, 12, 12), pred = square_mask(20, 20, 4, 2, 14, 12);
  const auto band = vcar::eval::trimap_band(gt, 1);
  std::size_t n = 0;
  for (auto v : band) n += v;
  CHECK(n == 76);
  CHECK(vcar::eval::trimap_iou(pred, gt, 1) == Approx(24.0 / 46.0));
}

TEST_CASE("boundary metrics on empty masks") {
  const vcar::Mask empty(12, 12);
  const auto obj = square_mask(12, 12, 3, 3, 8, 8);
  CHECK(vcar::eval::boundary_iou(empty, empty, 1) == 1.0);
  CHECK(vcar::eval::boundary_iou(obj, empty, 1) == 0.0);
  CHECK(vcar::eval::trimap_iou(empty, empty, 1) == 1.0);
  CHECK(vcar::eval::trimap_iou(obj, empty, 1) == 0.0);  // no GT contour: plain IoU
}
