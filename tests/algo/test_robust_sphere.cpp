#include <catch2/catch.hpp>

#include <cmath>

#include "vcar/algo/robust_sphere.hpp"

#include "point_scene.hpp"

TEST_CASE("Eq. 4 by hand: 3-sigma rejection of a planted outlier") {
  // Four points of a unit square around (1, 1, 0) and an outlier; with 4 inliers one outlier at
  // distance D is not rejected (mu_d + 3 sigma_d > D), so plant it among 16 inliers (4 copies).
  std::vector<Eigen::Vector3f> mus;
  for (int copy = 0; copy < 4; ++copy)
    for (auto p : {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(2, 0, 0), Eigen::Vector3f(0, 2, 0), Eigen::Vector3f(2, 2, 0)})
      mus.push_back(p);
  mus.push_back({1, 1, 170});  // index 16
  const auto scene = scene_of(mus);
  std::vector<vcar::Index> idx(mus.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<vcar::Index>(i);

  // By hand: mu_bar = (1, 1, 170/17) = (1, 1, 10). Inliers: d = sqrt(1 + 1 + 100) = sqrt(102);
  // outlier: d = 160. mu_d = (16 sqrt(102) + 160) / 17, sigma_d = population std of the 17 d_i.
  const double di = std::sqrt(102.0), dout = 160.0;
  const double mu_d = (16 * di + dout) / 17;
  const double sigma_d = std::sqrt((16 * (di - mu_d) * (di - mu_d) + (dout - mu_d) * (dout - mu_d)) / 17);
  REQUIRE(dout > mu_d + 3 * sigma_d);  // the outlier is beyond 3 sigma
  REQUIRE(di <= mu_d + 3 * sigma_d);

  const auto rc = vcar::robust_centre(scene, idx);
  CHECK(rc.mu_bar.x() == Approx(1.0));
  CHECK(rc.mu_bar.z() == Approx(10.0));
  CHECK(rc.mu_d == Approx(mu_d));
  CHECK(rc.sigma_d == Approx(sigma_d));
  CHECK(rc.inliers == 16);
  CHECK((rc.c - Eigen::Vector3f(1, 1, 0)).norm() == Approx(0).margin(1e-5));  // c = inlier mean
  CHECK(rc.max_inlier_distance == Approx(std::sqrt(2.0)));

  // Eq. 5: r = eta |v_ref - c|.
  const auto s = vcar::robust_sphere(scene, idx, Eigen::Vector3f(1, 1, 5), 1.2f);
  CHECK(s.r == Approx(6.0));
  CHECK(s.inliers == 16);
}

TEST_CASE("without outliers every point is an inlier and c is the plain mean") {
  const auto scene = scene_of({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {0, 0, 4}});
  const std::vector<vcar::Index> idx = {0, 1, 2, 3};
  const auto s = vcar::robust_sphere(scene, idx, Eigen::Vector3f(1, 1, 11), 1.f);
  CHECK(s.inliers == 4);
  CHECK((s.c - Eigen::Vector3f(1, 1, 1)).norm() == Approx(0).margin(1e-6));
  CHECK(s.r == Approx(10.0));
}

TEST_CASE("degenerate spheres: empty set, camera at the centre, no extent") {
  const auto scene = scene_of({{1, 0, 0}, {-1, 0, 0}, {5, 5, 5}});
  CHECK_THROWS_AS(vcar::robust_sphere(scene, std::vector<vcar::Index>{}, Eigen::Vector3f(0, 0, 1), 1.2f), vcar::Error);
  // Camera at c = 0: r falls back to eta * max inlier distance = 1.2 * 1.
  const std::vector<vcar::Index> pair = {0, 1};
  CHECK(vcar::robust_sphere(scene, pair, Eigen::Vector3f::Zero(), 1.2f).r == Approx(1.2));
  // A single point with the camera on it: no radius at all.
  const std::vector<vcar::Index> one = {2};
  CHECK_THROWS_AS(vcar::robust_sphere(scene, one, Eigen::Vector3f(5, 5, 5), 1.2f), vcar::Error);
  CHECK(vcar::robust_sphere(scene, one, Eigen::Vector3f(5, 5, 7), 1.5f).r == Approx(3.0));
}
