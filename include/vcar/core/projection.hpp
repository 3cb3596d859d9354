#pragma once
// Covariance projection of one Gaussian into one camera (B.6-B.7), with gsplat's near plane,
// Jacobian clamp, low-pass eps2d and opacity-aware extent (conventions §3).
#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"

namespace vcar {

struct ProjectionParams {
  float near_plane = 0.01f;     // camera-space z below this is not projected
  float far_plane = 1e10f;      // ... nor above this
  float eps2d = 0.3f;           // low-pass added to the diagonal of Sigma2D (px^2)
  float frustum_margin = 0.3f;  // Jacobian clamp: frustum widened by 30% (gsplat)
  float alpha_min = 1.f / 255.f;  // opacity below this is culled
  float extend_max = 3.33f;     // maximum extent in standard deviations (gsplat 1.5)
};

struct ProjectedGaussian {
  bool valid = false;            // false: behind the near plane, degenerate or transparent
  Eigen::Vector2f mean{0, 0};    // m = (u, v) in pixels (continuous, conventions §2)
  float depth = 0;               // camera-space z
  Eigen::Matrix2f Sigma2D = Eigen::Matrix2f::Zero();  // sum_d s_d^2 q_d q_d^T + eps2d I
  Eigen::Vector3f conic{0, 0, 0};  // Sigma2D^-1 as (xx, xy, yy)
  int radius_x = 0, radius_y = 0;  // pixel extent of the bounding box
  std::array<Eigen::Vector2f, 3> q{};  // q_d = M r_d, M = J R_w (Eq. 10, B.7)
  bool on_screen = false;          // valid and the bounding box overlaps the image (gsplat cull)
};

// The clamp of tx/z and ty/z in the perspective Jacobian (B.7, as gsplat): the frustum widened by
// `frustum_margin` of its half-extent, x in [-x_neg, x_pos] and y in [-y_neg, y_pos].
struct JacobianLimits {
  float x_pos, x_neg, y_pos, y_neg;

  static JacobianLimits of(const Camera& cam, float frustum_margin) {
    const float W = static_cast<float>(cam.width), H = static_cast<float>(cam.height);
    const float tan_x = 0.5f * W / cam.fx, tan_y = 0.5f * H / cam.fy;
    return {(W - cam.cx) / cam.fx + frustum_margin * tan_x, cam.cx / cam.fx + frustum_margin * tan_x,
            (H - cam.cy) / cam.fy + frustum_margin * tan_y, cam.cy / cam.fy + frustum_margin * tan_y};
  }
};

// Perspective Jacobian at the camera-space mean t (Eq. 10, B.7), tx/z and ty/z clamped to the
// frustum widened by `frustum_margin` (JacobianLimits).
inline Eigen::Matrix<float, 2, 3> perspective_jacobian(const Camera& cam, const Eigen::Vector3f& t,
                                                       float frustum_margin = 0.3f) {
  const JacobianLimits lim = JacobianLimits::of(cam, frustum_margin);
  const float rz = 1.f / t.z(), rz2 = rz * rz;
  const float tx = t.z() * std::min(lim.x_pos, std::max(-lim.x_neg, t.x() * rz));
  const float ty = t.z() * std::min(lim.y_pos, std::max(-lim.y_neg, t.y() * rz));
  Eigen::Matrix<float, 2, 3> J;
  J << cam.fx * rz, 0.f, -cam.fx * tx * rz2,
       0.f, cam.fy * rz, -cam.fy * ty * rz2;
  return J;
}

// Sigma2D = sum_d s_d^2 q_d q_d^T + eps2d I (Eq. 10, B.7) with q_d = M r_d, M = J R_w, from the
// perspective Jacobian J at the camera-space mean. Writes q and returns Sigma2D (exactly
// symmetric). project_gaussian's covariance; ABR calls it with the J it already has.
inline Eigen::Matrix2f project_covariance(const Camera& cam, const Eigen::Matrix<float, 2, 3>& J,
                                          const Eigen::Matrix3f& R, const Eigen::Vector3f& s, float eps2d,
                                          std::array<Eigen::Vector2f, 3>& q) {
  const Eigen::Matrix<float, 2, 3> M = J * cam.R_w;
  Eigen::Matrix2f S = Eigen::Matrix2f::Zero();
  for (int d = 0; d < 3; ++d) {
    q[d] = M * R.col(d);                                // q_d = M r_d (B.7)
    S.noalias() += (s[d] * s[d]) * q[d] * q[d].transpose();  // sum_d s_d^2 q_d q_d^T (Eq. 10)
  }
  S(0, 0) += eps2d;
  S(1, 1) += eps2d;
  S(1, 0) = S(0, 1);  // exact symmetry
  return S;
}

// Projects a Gaussian with mean mu, rotation R (columns r_d), scales s and opacity.
inline ProjectedGaussian project_gaussian(const Camera& cam, const Eigen::Vector3f& mu,
                                          const Eigen::Matrix3f& R, const Eigen::Vector3f& s,
                                          float opacity, const ProjectionParams& p = {}) {
  ProjectedGaussian g;
  const Eigen::Vector3f t = cam.to_camera(mu);
  g.depth = t.z();
  if (!(t.z() >= p.near_plane && t.z() <= p.far_plane)) return g;
  g.mean = {cam.fx * t.x() / t.z() + cam.cx, cam.fy * t.y() / t.z() + cam.cy};
  const Eigen::Matrix2f S = project_covariance(cam, perspective_jacobian(cam, t, p.frustum_margin), R, s, p.eps2d, g.q);
  g.Sigma2D = S;
  const float det = S(0, 0) * S(1, 1) - S(0, 1) * S(0, 1);
  if (!(det > 0.f) || !(opacity >= p.alpha_min)) return g;
  g.conic = {S(1, 1) / det, -S(0, 1) / det, S(0, 0) / det};
  const float extend = std::min(p.extend_max, std::sqrt(2.f * std::log(opacity / p.alpha_min)));
  g.radius_x = static_cast<int>(std::ceil(extend * std::sqrt(S(0, 0))));
  g.radius_y = static_cast<int>(std::ceil(extend * std::sqrt(S(1, 1))));
  g.valid = true;
  const float rx = static_cast<float>(g.radius_x), ry = static_cast<float>(g.radius_y);
  g.on_screen = (g.radius_x > 0 || g.radius_y > 0) && g.mean.x() + rx > 0.f &&
                g.mean.x() - rx < static_cast<float>(cam.width) && g.mean.y() + ry > 0.f &&
                g.mean.y() - ry < static_cast<float>(cam.height);
  return g;
}

}  // namespace vcar
