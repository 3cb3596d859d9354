#include <catch2/catch.hpp>

#include "clusters.hpp"
#include "two_blobs.hpp"
#include "vcar/baselines/ludvig.hpp"

TEST_CASE("LUDVIG selects the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  auto renderer = test_blobs::walk_renderer();
  const auto r = vcar::baselines::ludvig(renderer, t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  CHECK(r.selected == t.A);
}

TEST_CASE("LUDVIG: diffusion pulls outliers toward their neighbours") {
  auto t = test_clusters::make_clusters();
  t.c.weight_fg[13] = 0.3;       // f0 = 0.3 inside A: f -> ~0.15 + 0.5 * ~0.95 > 0.5
  t.c.weight_fg[27 + 13] = 0.7;  // f0 = 0.7 inside B: f -> ~0.35 + 0.5 * ~0.05 < 0.5
  vcar::baselines::LudvigParams p;
  p.iterations = 0;  // lifting only
  auto lift = vcar::baselines::ludvig_from(t.scene, t.c, p);
  CHECK(lift.score[13] == Approx(0.3f).epsilon(1e-6));
  CHECK(std::find(lift.selected.begin(), lift.selected.end(), 13u) == lift.selected.end());
  CHECK(std::find(lift.selected.begin(), lift.selected.end(), 40u) != lift.selected.end());
  p.iterations = 20;
  const auto r = vcar::baselines::ludvig_from(t.scene, t.c, p);
  std::vector<vcar::Index> A;
  for (vcar::Index i = 0; i < 27; ++i) A.push_back(i);
  CHECK(r.selected == A);
  CHECK(r.score[13] > 0.5f);
  CHECK(r.score[13] < 0.7f);
  CHECK(r.score[40] < 0.5f);
  // A constant field stays constant (anchored, row-normalised diffusion).
  CHECK(r.score[0] == Approx(1.f).epsilon(0.05));
}
