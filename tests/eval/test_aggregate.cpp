#include <catch2/catch.hpp>

#include "vcar/eval/aggregate.hpp"

TEST_CASE("evaluate_alpha thresholds the render and scores it") {
  vcar::ImageF alpha(4, 4, 1, 0.f);
  vcar::Mask gt(4, 4);
  for (int x = 0; x < 2; ++x) { alpha(x, 0) = 0.3f; gt(x, 0) = 255; }
  CHECK(vcar::eval::evaluate_alpha(alpha, gt, 0.5f).iou == 0.0);  // nothing above 0.5
  CHECK(vcar::eval::evaluate_alpha(alpha, gt, 0.1f).iou == 1.0);
  CHECK(vcar::eval::evaluate_alpha(alpha, gt, 0.1f).accuracy == 1.0);
}

TEST_CASE("mean over views, then over scenes") {
  using VM = vcar::eval::ViewMetrics;
  // Scene A: views with IoU 0.2 and 0.4 -> 0.3; scene B: one view 0.9 -> overall (0.3+0.9)/2.
  const std::vector<std::vector<VM>> per_view = {{VM{0.2, 1, 0, 0, 0}, VM{0.4, 0.5, 0, 0, 0}}, {VM{0.9, 0, 0, 0, 0}}};
  const auto s = vcar::eval::summarise(per_view);
  REQUIRE(s.per_scene.size() == 2);
  CHECK(s.per_scene[0].iou == Approx(0.3));
  CHECK(s.per_scene[0].accuracy == Approx(0.75));
  CHECK(s.overall.iou == Approx(0.6));
  CHECK(s.overall.accuracy == Approx(0.375));
}
