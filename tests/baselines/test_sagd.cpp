#include <catch2/catch.hpp>

#include "two_blobs.hpp"
#include "vcar/baselines/sagd.hpp"

namespace {
// Camera at (0, 0, -10) looking down +z: u = 10 x + 50, v = 10 y + 50.
vcar::Camera front(const std::string& name) {
  vcar::Camera c;
  c.name = name;
  c.width = c.height = 100;
  c.fx = c.fy = 100.f; c.cx = c.cy = 50.f;
  c.t_w = {0, 0, 10};
  return c;
}
vcar::Mask columns_from(int u0) {
  vcar::Mask m(100, 100);
  for (int y = 0; y < 100; ++y)
    for (int x = u0; x < 100; ++x) m(x, y) = 255;
  return m;
}
}  // namespace

TEST_CASE("SAGD selects the masked blob") {
  const auto t = test_blobs::make_two_blobs();
  vcar::baselines::SagdParams p;
  p.decompose = false;
  const auto r = vcar::baselines::sagd(t.scene, t.cameras, vcar::baselines::masks_from(t.masks), p);
  CHECK(r.selected == t.A);
}

TEST_CASE("SAGD: the mode over all views includes -1, its share must exceed 0.7") {
  vcar::GaussianScene s;
  s.resize(1);
  std::vector<vcar::Camera> cams;
  for (int j = 0; j < 5; ++j) cams.push_back(front("v" + std::to_string(j)));
  std::vector<std::optional<vcar::Mask>> masks(5, columns_from(0));  // all foreground
  auto run = [&] { return vcar::baselines::sagd(s, cams, vcar::baselines::masks_from(masks)).selected.size(); };
  CHECK(run() == 1);             // 5/5
  masks[4] = vcar::Mask(100, 100);
  CHECK(run() == 1);             // 4/5 = 0.8 > 0.7
  masks[3] = vcar::Mask(100, 100);
  CHECK(run() == 0);             // 3/5 = 0.6
  // Visible in few views: foreground in 2 views, no mask (label -1) in 3: mode is -1.
  masks = {columns_from(0), columns_from(0), std::nullopt, std::nullopt, std::nullopt};
  CHECK(run() == 0);
}

TEST_CASE("SAGD boundary decomposition of a Gaussian crossing the mask edge") {
  // Major axis x with s = 1 (others 0.1), at the origin; mask = columns u >= 45, i.e. x >= -0.5.
  // Endpoints x = -1.5 (u = 35, outside) and +1.5 (u = 65, inside). 33 samples
  // x_k = -1.5 + 3k/32: inside for k >= 11 -> 22 of 33, r = 2/3.
  // scales *= 0.8 * 2/3; mean moves +x by 0.5 (1 - 2/3) * 3 * 1 = 0.5.
  vcar::GaussianScene s;
  s.resize(1);
  s.set(0, {0, 0, 0}, {0.f, std::log(0.1f), std::log(0.1f)}, {1, 0, 0, 0}, 2.f);
  std::vector<vcar::Camera> cams = {front("a"), front("b"), front("c")};
  std::vector<std::optional<vcar::Mask>> masks(3, columns_from(45));
  const auto r = vcar::baselines::sagd(s, cams, vcar::baselines::masks_from(masks));
  REQUIRE(r.selected.size() == 1);
  CHECK(r.decomposed[0] == 1);
  const float f = std::log(0.8f * 2.f / 3.f);
  CHECK(r.log_scale[0][0] == Approx(0.f + f));
  CHECK(r.log_scale[1][0] == Approx(std::log(0.1f) + f));
  CHECK(r.mean[0][0] == Approx(0.5f));
  CHECK(r.mean[1][0] == Approx(0.f).margin(1e-6));
  // Mirrored mask (inside on the left: columns < 55, x < 0.5): the mean moves to -x.
  vcar::Mask left(100, 100);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 55; ++x) left(x, y) = 255;
  masks.assign(3, left);
  const auto l = vcar::baselines::sagd(s, cams, vcar::baselines::masks_from(masks));
  CHECK(l.mean[0][0] == Approx(-0.5f));
  // Entirely inside: no endpoint differs, nothing changes.
  masks.assign(3, columns_from(0));
  const auto in = vcar::baselines::sagd(s, cams, vcar::baselines::masks_from(masks));
  CHECK(in.decomposed[0] == 0);
  CHECK(in.log_scale[0][0] == 0.f);
  CHECK(in.scene_of(s).mean[0][0] == 0.f);
}
