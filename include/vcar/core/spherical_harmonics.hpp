#pragma once
// View-dependent colour from spherical harmonics of degree 0-3 (conventions §3): the real SH
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

// The (degree+1)^2 basis values at the unit direction (x, y, z), written to Y[0..coeffs). T is
// float, or a SIMD batch of floats with one direction per lane (the renderer's shading).
template <class T>
inline void sh_basis(int degree, T x, T y, T z, T* Y) {
  assert(degree >= 0 && degree <= sh::max_degree);
  Y[0] = T(sh::C0);
  if (degree < 1) return;
  Y[1] = T(-sh::C1) * y;
  Y[2] = T(sh::C1) * z;
  Y[3] = T(-sh::C1) * x;
  if (degree < 2) return;
  const T xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
  Y[4] = T(sh::C2[0]) * xy;
  Y[5] = T(sh::C2[1]) * yz;
  Y[6] = T(sh::C2[2]) * (T(2.f) * zz - xx - yy);
  Y[7] = T(sh::C2[3]) * xz;
  Y[8] = T(sh::C2[4]) * (xx - yy);
  if (degree < 3) return;
  Y[9] = T(sh::C3[0]) * y * (T(3.f) * xx - yy);
  Y[10] = T(sh::C3[1]) * xy * z;
  Y[11] = T(sh::C3[2]) * y * (T(4.f) * zz - xx - yy);
  Y[12] = T(sh::C3[3]) * z * (T(2.f) * zz - T(3.f) * xx - T(3.f) * yy);
  Y[13] = T(sh::C3[4]) * x * (T(4.f) * zz - xx - yy);
  Y[14] = T(sh::C3[5]) * z * (xx - yy);
  Y[15] = T(sh::C3[6]) * x * (xx - T(3.f) * yy);
}

namespace sh::detail {
// sum_k Y[k] coeffs[k][c] for a fixed number of coefficients B, k ascending (unrolled: the
// renderer calls this once per visible Gaussian).
template <int B>
inline void accumulate(const float* Y, const float* coeffs, float rgb[3]) {
  float r = rgb[0], g = rgb[1], b = rgb[2];  // locals: rgb might alias coeffs, registers cannot
  for (int k = 0; k < B; ++k) {
    r += Y[k] * coeffs[k * 3 + 0];
    g += Y[k] * coeffs[k * 3 + 1];
    b += Y[k] * coeffs[k * 3 + 2];
  }
  rgb[0] = r, rgb[1] = g, rgb[2] = b;
}
}  // namespace sh::detail

// rgb = max(0, 0.5 + sum_k Y_k(dir) sh[k][c]); `coeffs` holds (degree+1)^2 x 3 values [k][c]
// and `dir` need not be normalised (a zero direction keeps only the DC term).
inline Eigen::Vector3f sh_to_rgb(int degree, const float* coeffs, const Eigen::Vector3f& dir) {
  assert(degree >= 0 && degree <= sh::max_degree);
  float rgb[3] = {0.f, 0.f, 0.f};
  float Y[16];
  if (degree == 0) {
    Y[0] = sh::C0;  // no direction needed
    sh::detail::accumulate<1>(Y, coeffs, rgb);
  } else {
    const float n = std::sqrt(dir.squaredNorm());  // divide (not multiply by 1/n): same bits as dir / |dir|
    const float x = n > 0.f ? dir.x() / n : 0.f, y = n > 0.f ? dir.y() / n : 0.f,
                z = n > 0.f ? dir.z() / n : 0.f;
    sh_basis(degree, x, y, z, Y);
    switch (degree) {
      case 1: sh::detail::accumulate<4>(Y, coeffs, rgb); break;
      case 2: sh::detail::accumulate<9>(Y, coeffs, rgb); break;
      default: sh::detail::accumulate<16>(Y, coeffs, rgb); break;
    }
  }
  return {std::max(0.f, 0.5f + rgb[0]), std::max(0.f, 0.5f + rgb[1]), std::max(0.f, 0.5f + rgb[2])};
}

// Colour of Gaussian i seen from a camera centred at `eye` (world).
inline Eigen::Vector3f gaussian_rgb(const GaussianScene& scene, std::size_t i, const Eigen::Vector3f& eye) {
  const std::size_t B3 = static_cast<std::size_t>(scene.sh_coeffs()) * 3;
  return sh_to_rgb(scene.sh_degree, scene.sh.data() + i * B3, scene.mu(i) - eye);
}

}  // namespace vcar
