#include <catch2/catch.hpp>

#include "two_blobs.hpp"
#include "vcar/baselines/naive_voting.hpp"

TEST_CASE("naive voting selects the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  const auto r = vcar::baselines::naive_voting(t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  CHECK(r.selected == t.A);
  for (auto i : t.A) CHECK(r.score[i] == 1.f);
  for (auto i : t.B) CHECK(r.score[i] == 0.f);
}

TEST_CASE("naive voting counts invisible as background and skips views without a mask") {
  // One Gaussian at the origin, a camera that sees it and one facing away.
  vcar::GaussianScene s;
  s.resize(1);
  const vcar::Intrinsics K{20, 20, 20.f, 20.f, 10.f, 10.f};
  std::vector<vcar::Camera> cams = {vcar::Camera::look_at({0, 0, -3}, {0, 0, 0}, {0, -1, 0}, K),
                                    vcar::Camera::look_at({0, 0, -3}, {0, 0, -6}, {0, -1, 0}, K)};
  std::vector<std::optional<vcar::Mask>> masks = {vcar::Mask(20, 20, 1, 255), vcar::Mask(20, 20, 1, 255)};
  auto r = vcar::baselines::naive_voting(s, cams, vcar::baselines::masks_from(masks));
  CHECK(r.score[0] == Approx(0.5));  // fg in view 0, invisible (= background) in view 1
  CHECK(r.selected.size() == 1);     // 0.5 >= tau
  masks[1].reset();                  // no mask: no evidence
  r = vcar::baselines::naive_voting(s, cams, vcar::baselines::masks_from(masks));
  CHECK(r.score[0] == 1.f);
}

TEST_CASE("a mask of the wrong size is an error naming the view") {
  auto t = test_blobs::make_two_blobs();
  t.masks[2] = vcar::Mask(10, 10);
  try {
    vcar::baselines::naive_voting(t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(e.where().find("view2") != std::string::npos);
  }
}
