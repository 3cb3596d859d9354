#pragma once
// Test fixture: a scene of point-like Gaussians (unit scale, identity rotation, opacity logit 0)
// at the given means, for the tests of what looks only at means (voting, the sphere), and a small
// pinhole camera to view them.
#include <vector>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"

inline vcar::GaussianScene scene_of(const std::vector<Eigen::Vector3f>& mus) {
  vcar::GaussianScene s;
  s.resize(mus.size());
  for (std::size_t i = 0; i < mus.size(); ++i) s.set(i, mus[i], Eigen::Vector3f::Zero(), {1, 0, 0, 0}, 0.f);
  return s;
}

// Identity pose, fx = fy = 10, principal point (10, 10), 20 x 20: a mean (x, y, z) projects to
// pixel (10 x / z + 10, 10 y / z + 10).
inline vcar::Camera cam20(const char* name = "v") {
  vcar::Camera c;
  c.name = name;
  c.width = 20; c.height = 20; c.fx = 10; c.fy = 10; c.cx = 10; c.cy = 10;
  return c;
}
