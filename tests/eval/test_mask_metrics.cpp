#include <catch2/catch.hpp>

#include "vcar/eval/mask_metrics.hpp"

namespace {
vcar::Mask square(int w, int h, int x0, int y0, int x1, int y1) {
  vcar::Mask m(w, h);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) m(x, y) = 255;
  return m;
}
}  // namespace

TEST_CASE("IoU and accuracy of two offset squares") {
  // GT [2,12)^2 (100 px); prediction shifted right by 2: overlap 8x10 = 80, union 120.
  const auto gt = square(20, 20, 2, 2, 12, 12), pred = square(20, 20, 4, 2, 14, 12);
  CHECK(vcar::eval::mask_iou(pred, gt) == Approx(80.0 / 120.0));
  // 40 pixels differ out of 400.
  CHECK(vcar::eval::mask_accuracy(pred, gt) == Approx(360.0 / 400.0));
  const auto c = vcar::eval::confusion(pred, gt);
  CHECK(c.tp == 80); CHECK(c.fp == 20); CHECK(c.fn == 20); CHECK(c.tn == 280);
}

TEST_CASE("IoU edge cases") {
  const vcar::Mask empty(8, 6), full(8, 6, 1, 255);
  CHECK(vcar::eval::mask_iou(empty, empty) == 1.0);   // both empty: defined as 1
  CHECK(vcar::eval::mask_iou(full, empty) == 0.0);    // GT empty, prediction not
  CHECK(vcar::eval::mask_iou(empty, full) == 0.0);
  CHECK(vcar::eval::mask_accuracy(full, empty) == 0.0);
  CHECK(vcar::eval::mask_accuracy(empty, empty) == 1.0);
}

TEST_CASE("predicted mask thresholds alpha strictly at a") {
  vcar::ImageF alpha(3, 1);
  alpha.data = {0.05f, 0.3f, 0.5f};
  const auto m05 = vcar::eval::predicted_mask(alpha);
  const auto m01 = vcar::eval::predicted_mask(alpha, vcar::eval::alpha_released);
  CHECK(m05.data[0] == 0); CHECK(m05.data[1] == 0); CHECK(m05.data[2] == 0);  // 0.5 is not > 0.5
  CHECK(m01.data[0] == 0); CHECK(m01.data[1] != 0); CHECK(m01.data[2] != 0);
}

TEST_CASE("size mismatch is an error naming the view") {
  const vcar::Mask a(4, 4), b(4, 5);
  try {
    vcar::eval::mask_iou(a, b, "view 'frame_003'");
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(e.where() == "view 'frame_003'");
  }
}
