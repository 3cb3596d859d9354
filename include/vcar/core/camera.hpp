#pragma once
// Pinhole camera in the OpenCV/COLMAP frame: x right, y down, z forward (conventions §2).
// World-to-camera W = [R_w | t_w]; pixel (col j, row i) covers [j, j+1) x [i, i+1).
#include <cmath>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vcar/core/error.hpp"

namespace vcar {

struct Intrinsics {
  int width = 0, height = 0;        // image size in pixels
  float fx = 0, fy = 0, cx = 0, cy = 0;  // focal lengths and principal point in pixels
};

struct Camera {
  std::string name;  // the image name (`img_name`); views are named by it in errors
  int width = 0, height = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0;
  Eigen::Matrix3f R_w = Eigen::Matrix3f::Identity();  // world-to-camera rotation
  Eigen::Vector3f t_w = Eigen::Vector3f::Zero();      // world-to-camera translation

  Intrinsics intrinsics() const { return {width, height, fx, fy, cx, cy}; }
  void set_intrinsics(const Intrinsics& k) {
    width = k.width; height = k.height; fx = k.fx; fy = k.fy; cx = k.cx; cy = k.cy;
  }

  Eigen::Vector3f to_camera(const Eigen::Vector3f& p) const { return R_w * p + t_w; }
  // Sets the pose from a camera-to-world rotation (OpenCV axes) and the camera centre.
  void set_camera_to_world(const Eigen::Matrix3f& R_c2w, const Eigen::Vector3f& centre) {
    R_w = R_c2w.transpose();
    t_w = -(R_w * centre);
  }
  // Camera centre in world: -R_w^T t_w.
  Eigen::Vector3f position() const { return -(R_w.transpose() * t_w); }
  // World directions of the camera's forward (+z), right (+x) and up (-y) axes.
  Eigen::Vector3f forward() const { return R_w.row(2).transpose(); }
  Eigen::Vector3f right() const { return R_w.row(0).transpose(); }
  Eigen::Vector3f up() const { return -R_w.row(1).transpose(); }

  // Camera at `eye` looking at `target`, with `up` the world direction that appears upward.
  static Camera look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                        const Eigen::Vector3f& up, const Intrinsics& k, std::string name = {}) {
    const Eigen::Vector3f z = (target - eye).normalized();
    Eigen::Vector3f x = z.cross(up);  // image x (right) = forward x up
    if (x.squaredNorm() < 1e-12f) {    // looking along up: any perpendicular will do
      x = z.unitOrthogonal();
    }
    x.normalize();
    const Eigen::Vector3f y = z.cross(x);
    Camera c;
    c.name = std::move(name);
    c.set_intrinsics(k);
    c.R_w.row(0) = x.transpose();
    c.R_w.row(1) = y.transpose();
    c.R_w.row(2) = z.transpose();
    c.t_w = -(c.R_w * eye);
    return c;
  }

  // Throws vcar::Error naming the camera for a non-positive size or focal length, a non-finite
  // value, or a rotation that is not orthonormal.
  void validate() const {
    const std::string where = "camera '" + name + "'";
    if (width <= 0 || height <= 0) throw Error("image size must be positive", where);
    if (!(fx > 0 && fy > 0) || !std::isfinite(fx) || !std::isfinite(fy))
      throw Error("focal lengths must be positive and finite", where);
    if (!std::isfinite(cx) || !std::isfinite(cy) || !R_w.allFinite() || !t_w.allFinite())
      throw Error("non-finite pose or principal point", where);
    if (!(R_w * R_w.transpose()).isApprox(Eigen::Matrix3f::Identity(), 1e-3f) || R_w.determinant() < 0)
      throw Error("world-to-camera rotation is not a rotation", where);
  }
};

// Pixel of a continuous point, conventions §2: floor, and inside test 0 <= u < W, 0 <= v < H.
inline bool inside_image(float u, float v, int width, int height) {
  return u >= 0.f && v >= 0.f && u < static_cast<float>(width) && v < static_cast<float>(height);
}

}  // namespace vcar
