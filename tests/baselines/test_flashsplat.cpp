#include <catch2/catch.hpp>

#include "two_blobs.hpp"
#include "vcar/baselines/flashsplat.hpp"

TEST_CASE("FlashSplat selects the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  auto renderer = test_blobs::walk_renderer();
  const auto r = vcar::baselines::flashsplat(renderer, t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  CHECK(r.selected == t.A);
}

TEST_CASE("FlashSplat: normalised columns and the background bias") {
  // Gaussian 0: A = (0.4, 0.6) -> normalised (0.5547, 0.8321): foreground unless gamma >= 0.2774.
  // Gaussian 1: A = (3, 1) -> (0.9487, 0.3162): background unless gamma <= -0.6325.
  // Gaussian 2: never contributes: background.
  vcar::Contributions c;
  c.weight = {1.0, 4.0, 0.0};
  c.weight_fg = {0.6, 1.0, 0.0};
  vcar::baselines::FlashSplatParams p;
  auto r = vcar::baselines::flashsplat_from(c, p);
  CHECK(r.selected == std::vector<vcar::Index>{0});
  CHECK(r.score[0] == Approx((0.6 - 0.4) / std::sqrt(0.52)));
  p.gamma = 0.25f;
  CHECK(vcar::baselines::flashsplat_from(c, p).selected == std::vector<vcar::Index>{0});
  p.gamma = 0.3f;
  CHECK(vcar::baselines::flashsplat_from(c, p).selected.empty());
  p.gamma = -0.7f;
  CHECK(vcar::baselines::flashsplat_from(c, p).selected == std::vector<vcar::Index>{0, 1});
  // Scale invariance: the same proportions from 100x the contributions give the same labels.
  c.weight = {100.0, 400.0, 0.0};
  c.weight_fg = {60.0, 100.0, 0.0};
  p.gamma = 0.f;
  CHECK(vcar::baselines::flashsplat_from(c, p).selected == std::vector<vcar::Index>{0});
}
