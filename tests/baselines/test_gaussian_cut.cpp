#include <catch2/catch.hpp>

#include "clusters.hpp"
#include "two_blobs.hpp"
#include "vcar/baselines/gaussian_cut.hpp"

namespace {
std::vector<vcar::Index> range(int a, int b) {
  std::vector<vcar::Index> v;
  for (int i = a; i < b; ++i) v.push_back(static_cast<vcar::Index>(i));
  return v;
}
}  // namespace

TEST_CASE("GaussianCut selects the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  auto renderer = test_blobs::walk_renderer();
  const auto r = vcar::baselines::gaussian_cut(renderer, t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  CHECK(r.selected == t.A);
}

TEST_CASE("GaussianCut: coarse threshold, then the graph cut follows the neighbours") {
  auto t = test_clusters::make_clusters();
  // A's centre at w = 0.85 (< 0.9: coarse background, unary cost of fg 0.05/0.9 = 0.056);
  // one Gaussian of B at w = 0.95 (coarse foreground, unary cost of bg 0.05/0.1 = 0.5).
  // Each has >= 10 similar neighbours of the other label, pairwise >= 10 * 0.1 * ~0.5: both flip.
  t.c.weight_fg[13] = 0.85;
  t.c.weight_fg[27 + 13] = 0.95;
  vcar::baselines::GaussianCutParams p;
  p.graph_cut = false;
  auto coarse = vcar::baselines::gaussian_cut_from(t.scene, t.c, p);
  auto expect = range(0, 27);
  expect.erase(expect.begin() + 13);
  expect.push_back(27 + 13);
  CHECK(coarse.selected == expect);
  CHECK(coarse.score[13] == Approx(0.85f));
  p.graph_cut = true;
  const auto cut = vcar::baselines::gaussian_cut_from(t.scene, t.c, p);
  CHECK(cut.selected == range(0, 27));
  // 360-degree threshold 0.3: a Gaussian of B at w = 0.35 among zeros is removed by the cut only.
  t = test_clusters::make_clusters();
  t.c.weight_fg[27] = 0.35;
  p.tau_w = 0.3f;
  CHECK(vcar::baselines::gaussian_cut_from(t.scene, t.c, p).selected == range(0, 27));
  p.graph_cut = false;
  CHECK(vcar::baselines::gaussian_cut_from(t.scene, t.c, p).selected.size() == 28);
}

TEST_CASE("GaussianCut: strong evidence survives the neighbours") {
  auto t = test_clusters::make_clusters();
  t.c.weight_fg[13] = 0.0;  // w = 0: unary cost of fg = lambda_u = 1
  vcar::baselines::GaussianCutParams p;
  p.lambda_p = 0.01f;       // pairwise <= 20 edges * 0.01 < 1: the evidence wins
  const auto r = vcar::baselines::gaussian_cut_from(t.scene, t.c, p);
  auto expect = range(0, 27);
  expect.erase(expect.begin() + 13);
  CHECK(r.selected == expect);
}
