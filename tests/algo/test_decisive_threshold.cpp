#include <catch2/catch.hpp>

#include "vcar/algo/decisive_threshold.hpp"
#include "vcar/algo/pipeline.hpp"

#include "point_scene.hpp"
#include "square_mask.hpp"

using vcar::Index;

TEST_CASE("Eq. R7 by hand: decisive when N(tau_strict) >= (1 - s) N(tau_fine)") {
  CHECK(vcar::decisive_vote(90, 100, 0.1f));    // 90 >= 0.9 * 100
  CHECK_FALSE(vcar::decisive_vote(89, 100, 0.1f));
  CHECK(vcar::decisive_vote(100, 100, 0.f));    // s = 0: only a vote with nothing in between
  CHECK_FALSE(vcar::decisive_vote(99, 100, 0.f));
  CHECK(vcar::decisive_vote(0, 100, 1.f));      // s = 1: always strict
  CHECK(vcar::decisive_vote(0, 0, 0.1f));       // nothing kept either way
}

namespace {
// Nine Gaussians inside every mask (R = 1) and one, at pixel (1, 10), inside 6 of 10 (R = 0.6):
// N(0.5) = 10, N(0.85) = 9. The fine round's vote, paper or robust, over the ten views.
std::vector<Index> fine_selection(const vcar::VcarParams& p, vcar::detail::FineVerdict* verdict,
                                  float split = vcar::split_fraction) {
  std::vector<Eigen::Vector3f> mus;
  for (int k = 0; k < 9; ++k) mus.push_back({-0.25f + 0.05f * static_cast<float>(k), 0.05f, 1.f});  // pixels 7.5-11.5
  mus.push_back({-0.85f, 0.05f, 1.f});
  const vcar::GaussianScene scene = scene_of(mus);
  std::vector<Index> all(10);
  for (Index i = 0; i < 10; ++i) all[i] = i;
  vcar::detail::RoundVote fine(scene, &all, p, true);
  const vcar::Mask whole = square_mask(20, 20, 0, 0, 20, 20), inner = square_mask(20, 20, 5, 5, 15, 15);
  const vcar::Camera c = cam20();
  for (int v = 0; v < 10; ++v) fine.add_view(c, v < 6 ? &whole : &inner, nullptr, p.depth_tolerance);
  std::vector<Index> idx;
  std::vector<float> scores;
  *verdict = fine.selected(p.tau_fine, p.strict.tau, split, idx, scores);
  REQUIRE(idx.size() == scores.size());
  return idx;
}
}  // namespace

TEST_CASE("Eq. R7 in the fine round: a decisive vote takes tau_strict, a split one keeps tau_fine") {
  const std::vector<Index> nine{0, 1, 2, 3, 4, 5, 6, 7, 8};
  std::vector<Index> ten = nine;
  ten.push_back(9);
  for (vcar::VcarParams p : {vcar::VcarParams::robust(), vcar::VcarParams::nvos()}) {
    p.tau_fine = 0.5f;
    p.strict.tau = 0.85f;
    vcar::detail::FineVerdict v;
    CHECK(fine_selection(p, &v, 0.1f) == nine);  // 9 >= 0.9 * 10: decisive
    CHECK(v.tau == 0.85f);
    CHECK_FALSE(v.split);
    CHECK(fine_selection(p, &v, 0.05f) == ten);  // 9 < 0.95 * 10: split
    CHECK(v.tau == 0.5f);
    CHECK(v.split);
    p.strict.tau = 0.f;  // off: never split
    CHECK(fine_selection(p, &v) == ten);
    CHECK(v.tau == 0.5f);
    CHECK_FALSE(v.split);
    p.strict.tau = 0.55f;  // R = 0.6 passes the strict threshold too
    CHECK(fine_selection(p, &v) == ten);
    CHECK(v.tau == 0.55f);
    CHECK_FALSE(v.split);
  }
}

TEST_CASE("Eq. R7 by hand: in a decisive vote tau_strict is for the candidates seen in a fifth of their views") {
  // The ten Gaussians of fine_selection (nine at R = 1, the tenth inside 6 of 10 masks), now
  // with a render whose surface (depth 0.5, alpha 1) lies in front of the tenth, at pixel
  // (1, 10), in every view from `hidden_from` on: V_9 = 10, V^o_9 = hidden_from, F^o_9 =
  // min(hidden_from, 6). Eq. R2 (kappa 2): R_9 = (F^o + 2 * 0.6) / (V^o + 2).
  std::vector<Eigen::Vector3f> mus;
  for (int k = 0; k < 9; ++k) mus.push_back({-0.25f + 0.05f * static_cast<float>(k), 0.05f, 1.f});
  mus.push_back({-0.85f, 0.05f, 1.f});
  const vcar::GaussianScene scene = scene_of(mus);
  std::vector<Index> all(10);
  for (Index i = 0; i < 10; ++i) all[i] = i;
  const vcar::Mask whole = square_mask(20, 20, 0, 0, 20, 20), inner = square_mask(20, 20, 5, 5, 15, 15);
  const vcar::Camera c = cam20();
  vcar::RenderOutput open, front;
  open.alpha = vcar::ImageF(20, 20, 1);  // no surface anywhere: every Gaussian unoccluded
  open.depth = vcar::ImageF(20, 20, 1);
  front = open;
  front.alpha.data[10 * 20 + 1] = 1.f;
  front.depth.data[10 * 20 + 1] = 0.5f;
  vcar::VcarParams p = vcar::VcarParams::robust();
  p.tau_fine = 0.5f;
  p.strict.tau = 0.85f;
  REQUIRE(vcar::seen_fraction == 0.2f);
  auto run = [&](int hidden_from, vcar::detail::FineVerdict& verdict) {
    vcar::detail::RoundVote fine(scene, &all, p, true);
    for (int v = 0; v < 10; ++v) fine.add_view(c, v < 6 ? &whole : &inner, v < hidden_from ? &open : &front, p.depth_tolerance);
    std::vector<Index> idx;
    std::vector<float> scores;
    verdict = fine.selected(p.tau_fine, p.strict.tau, vcar::split_fraction, idx, scores);
    return idx;
  };
  const std::vector<Index> nine{0, 1, 2, 3, 4, 5, 6, 7, 8};
  std::vector<Index> ten = nine;
  ten.push_back(9);
  vcar::detail::FineVerdict v;
  CHECK(run(10, v) == nine);  // seen in every view: R_9 = 0.6 < tau_strict (as without a render)
  CHECK(v.tau == 0.85f);
  CHECK_FALSE(v.split);
  CHECK(run(2, v) == nine);   // V^o = 2 = 0.2 V: seen; R_9 = (2 + 1.2) / 4 = 0.8 < 0.85
  CHECK(v.tau == 0.85f);
  CHECK(run(1, v) == ten);    // V^o = 1 < 0.2 V: hidden; R_9 = (1 + 1.2) / 3 = 0.73 >= tau_fine
  CHECK(v.tau == 0.85f);
  CHECK_FALSE(v.split);
  CHECK(run(0, v) == ten);    // V^o = 0: R_9 = 0.6 (the plain level) >= tau_fine
}
