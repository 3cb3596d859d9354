#pragma once
// Object-centric sphere (Eq. 4-5): a 3-sigma robust centre of the coarse Gaussians' means and a
// radius scaled from the reference camera's distance to it.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace vcar {

struct ObjectSphere {
  Eigen::Vector3f c = Eigen::Vector3f::Zero();  // robust centre (Eq. 4)
  float r = 0.f;                                // radius (Eq. 5)
  std::size_t inliers = 0;                      // |P*|
};

// The statistics of Eq. 4, kept for inspection and tests.
struct RobustCentre {
  Eigen::Vector3f c = Eigen::Vector3f::Zero();       // inlier mean
  Eigen::Vector3f mu_bar = Eigen::Vector3f::Zero();  // preliminary mean of P
  double mu_d = 0, sigma_d = 0;  // mean and population standard deviation of d_i
  std::size_t inliers = 0;
  float max_inlier_distance = 0;  // max |mu_i - c| over P* (the object's extent)
};

// Eq. 4: mu_bar = mean(P), d_i = |mu_i - mu_bar|, P* = {d_i <= mu_d + 3 sigma_d}, c = mean(P*).
// Sums in double in index order (deterministic). Empty `indices` -> vcar::Error.
inline RobustCentre robust_centre(const GaussianScene& scene, std::span<const Index> indices) {
  if (indices.empty()) throw Error("no Gaussians to fit the object sphere to (empty coarse selection)", "robust_sphere");
  const double n = static_cast<double>(indices.size());
  auto mu = [&](Index i) { return Eigen::Vector3d(scene.mean[0][i], scene.mean[1][i], scene.mean[2][i]); };
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (Index i : indices) sum += mu(i);
  const Eigen::Vector3d mu_bar = sum / n;
  std::vector<double> d(indices.size());
  double sd = 0;
  for (std::size_t k = 0; k < indices.size(); ++k) { d[k] = (mu(indices[k]) - mu_bar).norm(); sd += d[k]; }
  RobustCentre out;
  out.mu_bar = mu_bar.cast<float>();
  out.mu_d = sd / n;
  double var = 0;
  for (double dk : d) var += (dk - out.mu_d) * (dk - out.mu_d);
  out.sigma_d = std::sqrt(var / n);  // population standard deviation
  const double cut = out.mu_d + 3.0 * out.sigma_d;
  Eigen::Vector3d inl = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < indices.size(); ++k)
    if (d[k] <= cut) { inl += mu(indices[k]); ++out.inliers; }
  assert(out.inliers > 0);  // the point nearest mu_bar always has d <= mu_d
  const Eigen::Vector3d c = inl / static_cast<double>(out.inliers);
  out.c = c.cast<float>();
  double ext = 0;
  for (std::size_t k = 0; k < indices.size(); ++k)
    if (d[k] <= cut) ext = std::max(ext, (mu(indices[k]) - c).norm());
  out.max_inlier_distance = static_cast<float>(ext);
  return out;
}

// Eq. 4-5: sphere of centre c and radius r = eta |v_ref - c|. When the reference camera sits at
// the centre (r = 0), r falls back to eta * (max inlier distance), the object's own extent;
// when that is 0 too (all means coincide) there is no sphere: vcar::Error.
inline ObjectSphere robust_sphere(const GaussianScene& scene, std::span<const Index> indices,
                                  const Eigen::Vector3f& v_ref_pos, float eta) {
  const RobustCentre rc = robust_centre(scene, indices);
  ObjectSphere s;
  s.c = rc.c;
  s.inliers = rc.inliers;
  s.r = eta * (v_ref_pos - rc.c).norm();  // Eq. 5
  if (!(s.r > 0.f)) s.r = eta * rc.max_inlier_distance;
  if (!(s.r > 0.f) || !std::isfinite(s.r))
    throw Error("degenerate object sphere: the reference camera is at the centre and the object has no extent",
                "robust_sphere");
  return s;
}

}  // namespace vcar
