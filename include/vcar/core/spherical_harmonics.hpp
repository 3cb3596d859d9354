#pragma once
// View-dependent colour from spherical harmonics of degree 0-3 (CONVENTIONS 3): the real SH
// basis, ordering and signs of the reference 3DGS code (Condon-Shortley phase, m = -l..l),
// view direction = normalised (mean - camera centre), rgb = max(0, 0.5 + SH).
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>

#include <Eigen/Core>

#include "vcar/core/gaussian_scene.hpp"

namespace vcar {

namespace sh {
inline constexpr float C0 = 0.28209479177387814f;
inline constexpr float C1 = 0.4886025119029199f;
inline constexpr float C2[5] = {1.0925484305920792f, -1.0925484305920792f, 0.31539156525252005f,
                                -1.0925484305920792f, 0.5462742152960396f};
inline constexpr float C3[7] = {-0.5900435899266435f, 2.890611442640554f, -0.4570457994644658f,
                                0.3731763325901154f,  -0.4570457994644658f, 1.445305721320277f,
                                -0.5900435899266435f};
inline constexpr int max_degree = 3;
inline constexpr int coeffs(int degree) { return (degree + 1) * (degree + 1); }
}  // namespace sh

// The (degree+1)^2 basis values at the unit direction (x, y, z), written to Y[0..coeffs).
inline void sh_basis(int degree, float x, float y, float z, float* Y) {
  assert(degree >= 0 && degree <= sh::max_degree);
  Y[0] = sh::C0;
  if (degree < 1) return;
  Y[1] = -sh::C1 * y;
  Y[2] = sh::C1 * z;
  Y[3] = -sh::C1 * x;
  if (degree < 2) return;
  const float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
  Y[4] = sh::C2[0] * xy;
  Y[5] = sh::C2[1] * yz;
  Y[6] = sh::C2[2] * (2.f * zz - xx - yy);
  Y[7] = sh::C2[3] * xz;
  Y[8] = sh::C2[4] * (xx - yy);
  if (degree < 3) return;
  Y[9] = sh::C3[0] * y * (3.f * xx - yy);
  Y[10] = sh::C3[1] * xy * z;
  Y[11] = sh::C3[2] * y * (4.f * zz - xx - yy);
  Y[12] = sh::C3[3] * z * (2.f * zz - 3.f * xx - 3.f * yy);
  Y[13] = sh::C3[4] * x * (4.f * zz - xx - yy);
  Y[14] = sh::C3[5] * z * (xx - yy);
  Y[15] = sh::C3[6] * x * (xx - 3.f * yy);
}

// rgb = max(0, 0.5 + sum_k Y_k(dir) sh[k][c]); `coeffs` holds (degree+1)^2 x 3 values [k][c]
// and `dir` need not be normalised (a zero direction keeps only the DC term).
inline Eigen::Vector3f sh_to_rgb(int degree, const float* coeffs, const Eigen::Vector3f& dir) {
  const float n = dir.norm();
  const Eigen::Vector3f d = n > 0.f ? Eigen::Vector3f(dir / n) : Eigen::Vector3f::Zero();
  float Y[16];
  sh_basis(degree, d.x(), d.y(), d.z(), Y);
  float rgb[3] = {0.f, 0.f, 0.f};
  const int B = sh::coeffs(degree);
  for (int k = 0; k < B; ++k)
    for (int c = 0; c < 3; ++c) rgb[c] += Y[k] * coeffs[k * 3 + c];
  return {std::max(0.f, 0.5f + rgb[0]), std::max(0.f, 0.5f + rgb[1]), std::max(0.f, 0.5f + rgb[2])};
}

// Colour of Gaussian i seen from a camera centred at `eye` (world).
inline Eigen::Vector3f gaussian_rgb(const GaussianScene& scene, std::size_t i, const Eigen::Vector3f& eye) {
  const std::size_t B3 = static_cast<std::size_t>(scene.sh_coeffs()) * 3;
  return sh_to_rgb(scene.sh_degree, scene.sh.data() + i * B3, scene.mu(i) - eye);
}

}  // namespace vcar
