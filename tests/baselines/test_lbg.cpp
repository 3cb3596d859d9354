#include <catch2/catch.hpp>

#include "two_blobs.hpp"
#include "vcar/baselines/lbg.hpp"

TEST_CASE("LBG: a strict majority of the pixels that chose a Gaussian must be foreground") {
  // One 5x1 view. Pixels choose 0, 0, 0, 1, 1 ; mask 1, 1, 0, 1, 0. Gaussian 0: 2 of 3 fg -> kept;
  // Gaussian 1: 1 of 2 -> not kept (tie); Gaussian 2: no votes -> not kept.
  vcar::GaussianScene s;
  s.resize(3);
  vcar::Camera cam;
  cam.name = "strip";
  cam.width = 5; cam.height = 1;
  std::vector<vcar::Camera> cams{cam};
  vcar::Mask m(5, 1);
  m.data = {255, 255, 0, 255, 0};
  std::vector<std::optional<vcar::Mask>> masks{m};
  auto who_of = [](const vcar::Camera&) {
    vcar::Image<std::int32_t> w(5, 1, 1, -1);
    w.data = {0, 0, 0, 1, 1};
    return w;
  };
  const auto r = vcar::baselines::lbg(s, cams, vcar::baselines::masks_from(masks), who_of);
  CHECK(r.selected == std::vector<vcar::Index>{0});
  CHECK(r.score[0] == Approx(2.0 / 3.0));
  CHECK(r.score[1] == Approx(0.5));
  CHECK(r.score[2] == 0.f);
}

TEST_CASE("LBG with the reference walk selects only Gaussians of the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  const auto r = vcar::baselines::lbg(t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  REQUIRE(!r.selected.empty());
  for (auto i : r.selected) CHECK(i < 9u);  // A is 0..8
  for (auto i : t.B) CHECK(r.score[i] == 0.f);
  // The centre Gaussian of A is the front-most contributor near the blob's centre in every view.
  CHECK(std::find(r.selected.begin(), r.selected.end(), 4u) != r.selected.end());
}
