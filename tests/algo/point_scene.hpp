#pragma once
// Test fixture: a scene of point-like Gaussians (unit scale, identity rotation, opacity logit 0)
// at the given means, for the tests of what looks only at means (voting, the sphere).
#include <vector>

#include <Eigen/Core>

#include "vcar/core/gaussian_scene.hpp"

inline vcar::GaussianScene scene_of(const std::vector<Eigen::Vector3f>& mus) {
  vcar::GaussianScene s;
  s.resize(mus.size());
  for (std::size_t i = 0; i < mus.size(); ++i) s.set(i, mus[i], Eigen::Vector3f::Zero(), {1, 0, 0, 0}, 0.f);
  return s;
}
