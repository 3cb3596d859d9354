#pragma once
// Spherical spiral sampling (Eq. 7-8): N_s = S1 S2 cameras on the object sphere, on a spiral
// of S1 revolutions whose elevation runs from phi_s to phi_e, all looking at the centre.
//
// Frame (conventions §5): e3 = the scene up; e1 = the world axis (x, then y, then z on ties) least
// aligned with up, made orthogonal to it; e2 = e3 x e1. Elevation is measured from the plane
// orthogonal to up, azimuth from e1 toward e2. SpiralVariant::ReferenceCode uses the world
// axes (e1, e2, e3) = (x, y, z) for the positions as the released code; the look-at up is the
// scene up in both (conventions §7).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vcar/algo/params.hpp"
#include "vcar/algo/robust_sphere.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"

namespace vcar {

// Normalised mean of the cameras' up() (-y camera axis in world). No camera, or ups that
// cancel out -> vcar::Error.
inline Eigen::Vector3f estimate_scene_up(std::span<const Camera> cameras) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Camera& c : cameras) sum += c.up().cast<double>();
  if (cameras.empty() || !(sum.norm() > 1e-6 * static_cast<double>(cameras.size())))
    throw Error("cannot estimate the scene up: no cameras or their up vectors cancel out", "estimate_scene_up");
  return sum.normalized().cast<float>();
}

// The orthonormal spiral frame: columns e1, e2, e3 (e3 = up), right-handed.
inline Eigen::Matrix3f spiral_frame(const Eigen::Vector3f& up, SpiralVariant variant = SpiralVariant::Paper) {
  if (variant == SpiralVariant::ReferenceCode) return Eigen::Matrix3f::Identity();
  const Eigen::Vector3f e3 = up.normalized();
  // World axis least aligned with up; ties (within 1e-4, so that the last-bit differences
  // between instruction sets, e.g. fused or not, cannot flip the choice) go to x, then y.
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(e3[a]) < std::abs(e3[axis]) - 1e-4f) axis = a;
  const Eigen::Vector3f a = Eigen::Vector3f::Unit(axis);
  const Eigen::Vector3f e1 = (a - a.dot(e3) * e3).normalized();
  Eigen::Matrix3f F;
  F.col(0) = e1;
  F.col(1) = e3.cross(e1);
  F.col(2) = e3;
  return F;
}

// Intrinsics of the sampled views: the reference view's, or a field of view `fov_deg` on the
// short side with a centred principal point at the reference image size (reference code).
inline Intrinsics sampled_view_intrinsics(const Camera& reference, SampledIntrinsics choice, float fov_deg = 45.f) {
  Intrinsics k = reference.intrinsics();
  if (choice == SampledIntrinsics::ReferenceCode45Fov) {
    const double half = 0.5 * fov_deg * std::numbers::pi / 180.0;
    const double f = 0.5 * std::min(k.width, k.height) / std::tan(half);
    k.fx = k.fy = static_cast<float>(f);
    k.cx = 0.5f * static_cast<float>(k.width);
    k.cy = 0.5f * static_cast<float>(k.height);
  }
  return k;
}

// The sampled views' intrinsics chosen by the parameters.
inline Intrinsics sampled_intrinsics(const Camera& reference, const VcarParams& p) {
  return sampled_view_intrinsics(reference, p.sampled_intrinsics, p.sampled_fov_deg);
}

// "prefix" + three-digit index: sss_000, sss_001, ...
inline std::string sampled_view_name(const char* prefix, std::size_t k) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%03zu", k);
  return std::string(prefix) + buf;
}

// Elevation of spiral point k (Eq. 7), radians; N_s = 1 gives phi_s.
inline double spiral_elevation(std::size_t k, std::size_t N_s, double phi_s, double phi_e) {
  return N_s <= 1 ? phi_s : phi_s + (phi_e - phi_s) * static_cast<double>(k) / static_cast<double>(N_s - 1);
}

// Eq. 7-8: theta_k = 2 pi S1 k / N_s, phi_k = phi_s + (phi_e - phi_s) k / (N_s - 1),
// p_k = c + r (cos phi cos theta e1 + cos phi sin theta e2 + sin phi e3); cameras look at c.
inline std::vector<Camera> spiral_cameras(const ObjectSphere& sphere, const Eigen::Vector3f& up,
                                          const Intrinsics& intrinsics, int S1, int S2, float phi_s_deg,
                                          float phi_e_deg, SpiralVariant variant = SpiralVariant::Paper) {
  if (S1 < 1) throw Error("must be >= 1", "S1");
  if (S2 < 1) throw Error("must be >= 1", "S2");
  const Eigen::Matrix3d F = spiral_frame(up, variant).cast<double>();
  const std::size_t N_s = static_cast<std::size_t>(S1) * static_cast<std::size_t>(S2);
  const double deg = std::numbers::pi / 180.0;
  const Eigen::Vector3d c = sphere.c.cast<double>();
  std::vector<Camera> cams;
  cams.reserve(N_s);
  for (std::size_t k = 0; k < N_s; ++k) {
    const double theta = 2.0 * std::numbers::pi * S1 * static_cast<double>(k) / static_cast<double>(N_s);  // Eq. 7
    const double phi = spiral_elevation(k, N_s, phi_s_deg * deg, phi_e_deg * deg);                           // Eq. 7
    const Eigen::Vector3d dir(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta), std::sin(phi));
    const Eigen::Vector3d p = c + static_cast<double>(sphere.r) * (F * dir);  // Eq. 8
    cams.push_back(Camera::look_at(p.cast<float>(), sphere.c, up, intrinsics, sampled_view_name("sss_", k)));
  }
  return cams;
}

// The whole stage from the parameters: frame, intrinsics and elevations of VcarParams.
inline std::vector<Camera> spiral_cameras(const ObjectSphere& sphere, const Eigen::Vector3f& up,
                                          const Camera& reference, const VcarParams& p) {
  return spiral_cameras(sphere, up, sampled_intrinsics(reference, p), p.S1, p.S2, p.phi_s_deg, p.phi_e_deg,
                        p.spiral_variant);
}
// Same, with the intrinsics already chosen.
inline std::vector<Camera> spiral_cameras(const ObjectSphere& sphere, const Eigen::Vector3f& up,
                                          const Intrinsics& intrinsics, const VcarParams& p) {
  return spiral_cameras(sphere, up, intrinsics, p.S1, p.S2, p.phi_s_deg, p.phi_e_deg, p.spiral_variant);
}

// Beyond the paper: n cameras on the sphere in a cone of half-angle cone_deg around the
// largest-gap direction g (from c outward), on one spiral turn from the axis to the cone's rim
// (camera k at angle cone k / (n - 1) from g, azimuth 2 pi k / n), so consecutive frames move
// smoothly. n = 1 gives the single camera on the axis. Named sss_gap_000, ...: sampled views, like the spiral's sss_000, ...
inline std::vector<Camera> gap_directed_cameras(const ObjectSphere& sphere, const Eigen::Vector3f& up,
                                                const Eigen::Vector3f& gap_direction, const Intrinsics& intrinsics,
                                                int n, float cone_deg) {
  if (n < 1) throw Error("must be >= 1", "gap_directed_views");
  if (!(gap_direction.norm() > 0.f)) throw Error("gap direction is zero", "gap_directed_cameras");
  const Eigen::Vector3d g = gap_direction.cast<double>().normalized();
  const Eigen::Vector3d a = g.unitOrthogonal(), b = g.cross(a);
  const double cone = cone_deg * std::numbers::pi / 180.0;
  std::vector<Camera> cams;
  for (int k = 0; k < n; ++k) {
    const double alpha = n == 1 ? 0.0 : cone * k / (n - 1);
    const double psi = 2.0 * std::numbers::pi * k / n;
    const Eigen::Vector3d d = std::cos(alpha) * g + std::sin(alpha) * (std::cos(psi) * a + std::sin(psi) * b);
    const Eigen::Vector3d p = sphere.c.cast<double>() + static_cast<double>(sphere.r) * d;
    cams.push_back(Camera::look_at(p.cast<float>(), sphere.c, up, intrinsics, sampled_view_name("sss_gap_", k)));
  }
  return cams;
}

}  // namespace vcar
