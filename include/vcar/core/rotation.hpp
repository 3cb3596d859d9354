#pragma once
// Quaternion (w, x, y, z), stored unnormalised, to rotation matrix (B.6: R = rot(q / |q|)).
#include <Eigen/Core>
#include <cmath>

namespace vcar {

// Column d of the result is the local axis r_d of the Gaussian (conventions §1).
// A zero quaternion is invalid input; it is rejected where scenes enter (GaussianScene::validate).
inline Eigen::Matrix3f rotation_from_quaternion(float w, float x, float y, float z) {
  const float n = std::sqrt(w * w + x * x + y * y + z * z);
  w /= n; x /= n; y /= n; z /= n;
  Eigen::Matrix3f R;
  R << 1.f - 2.f * (y * y + z * z), 2.f * (x * y - w * z), 2.f * (x * z + w * y),
       2.f * (x * y + w * z), 1.f - 2.f * (x * x + z * z), 2.f * (y * z - w * x),
       2.f * (x * z - w * y), 2.f * (y * z + w * x), 1.f - 2.f * (x * x + y * y);
  return R;
}

}  // namespace vcar
