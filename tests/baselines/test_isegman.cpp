#include <catch2/catch.hpp>

#include "two_blobs.hpp"
#include "vcar/baselines/isegman.hpp"

TEST_CASE("iSegMan selects the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  const auto r = vcar::baselines::isegman(t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  CHECK(r.selected == t.A);
}

TEST_CASE("iSegMan: an occluded view barely votes") {
  // Gaussian 1 sits behind an opaque Gaussian 0 in view "behind" and is seen freely in view
  // "free". Masks: view "behind" says background at the centre, view "free" foreground.
  // Centre voting would tie 1:1; here the occluded view's weight is ~(1 - 0.999) of the free one.
  vcar::GaussianScene s;
  s.resize(2);
  s.set(0, {0, 0, -1.f}, Eigen::Vector3f::Constant(std::log(0.3f)), {1, 0, 0, 0}, 10.f);  // opaque occluder
  s.set(1, {0, 0, 1.f}, Eigen::Vector3f::Constant(std::log(0.3f)), {1, 0, 0, 0}, 10.f);
  const vcar::Intrinsics K{32, 32, 40.f, 40.f, 15.5f, 15.5f};  // centres land on a pixel centre
  const std::vector<vcar::Camera> cams = {
      vcar::Camera::look_at({0, 0, -5.f}, {0, 0, 0}, {0, -1, 0}, K, "behind"),   // 0 in front of 1
      vcar::Camera::look_at({0, 0, 5.f}, {0, 0, 1.f}, {0, -1, 0}, K, "free")};   // 1 in front of 0
  std::vector<std::optional<vcar::Mask>> masks = {vcar::Mask(32, 32), vcar::Mask(32, 32, 1, 255)};
  const auto w_behind = vcar::baselines::centre_visibility(s, cams[0]);
  const auto w_free = vcar::baselines::centre_visibility(s, cams[1]);
  CHECK(w_free[1] == Approx(0.999f));  // alpha clamped, T = 1
  CHECK(w_behind[1] < 2e-3f);          // T <= 0.001 behind an alpha-0.999 Gaussian
  const auto r = vcar::baselines::isegman(s, cams, vcar::baselines::masks_from(masks));
  CHECK(r.score[1] > 0.99f);
  CHECK(r.score[0] < 0.01f);  // symmetric: 0 is occluded in "free", background in "behind"
  CHECK(r.selected == std::vector<vcar::Index>{1});
}
