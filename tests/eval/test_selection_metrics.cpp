#include <catch2/catch.hpp>

#include "vcar/eval/selection_metrics.hpp"

TEST_CASE("per-Gaussian precision, recall, F1") {
  // selected {0,1,2,3}, true {2,3,4}: tp 2, fp 2, fn 1 -> P 1/2, R 2/3, F1 = 4/7.
  const auto s = vcar::eval::selection_scores({0, 1, 2, 3}, {2, 3, 4}, 10);
  CHECK(s.precision == Approx(0.5));
  CHECK(s.recall == Approx(2.0 / 3.0));
  CHECK(s.f1 == Approx(4.0 / 7.0));
}

TEST_CASE("selection edge cases") {
  const auto both = vcar::eval::selection_scores({}, {}, 5);
  CHECK(both.f1 == 1.0);
  const auto none = vcar::eval::selection_scores({}, {1}, 5);
  CHECK(none.recall == 0.0);
  CHECK(none.f1 == 0.0);
  CHECK_THROWS_AS(vcar::eval::selection_scores({7}, {1}, 5), vcar::Error);
}

TEST_CASE("opacity x largest cross-section weighting") {
  vcar::GaussianScene s;
  s.resize(5);  // opacity logit 0 -> 0.5, unit scales: weight 0.5
  s.log_scale[0][4] = std::log(3.f);
  s.log_scale[1][4] = std::log(1.f);
  s.log_scale[2][4] = std::log(2.f);  // largest two: 3 * 2 -> weight 0.5 * 6 = 3
  const auto w = vcar::eval::visible_area_weight(s);
  CHECK(w[0] == Approx(0.5));
  CHECK(w[4] == Approx(3.0));
  // selected {0,1}, true {1,4}: tp 0.5, fp 0.5, fn 3 -> P 1/2, R 1/7, F1 = 2/9.
  const auto r = vcar::eval::weighted_selection_scores({0, 1}, {1, 4}, s);
  CHECK(r.precision == Approx(0.5));
  CHECK(r.recall == Approx(0.5 / 3.5));
  CHECK(r.f1 == Approx(2.0 * 0.5 * (1.0 / 7.0) / (0.5 + 1.0 / 7.0)));
}
