#pragma once
// What ABR needs to know of a Gaussian in a view before it looks at the mask (Eq. 9-10, B.1-B.2,
// B.7): the camera-space depth, the projected centre m, q_d = J R_w r_d, Sigma2D and its
// eigen-decomposition, computed for simd::width Gaussians at once. observe_gaussian (one
// Gaussian, broadcast to every lane) and BoundaryRefinement (a run of candidates) both call
// abr_geometry, so the single-Gaussian reference and the batched refinement see the same bits.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/core/simd.hpp"

namespace vcar {

// Eigen-decomposition of a symmetric 2x2 matrix, lambda1 >= lambda2, unit e1 _|_ e2 (Eq. 9).
struct SymmetricEigen2 {
  float lambda1 = 0, lambda2 = 0;
  Eigen::Vector2f e1{1, 0}, e2{0, 1};
};

namespace detail {

// symmetric_eigen2 lane by lane: lambda1, lambda2 and e1 (e2 = (-e1.y, e1.x)).
struct SymmetricEigen2Batch {
  simd::batch<float> lambda1, lambda2, e1x, e1y;
};

// Closed form for [[a, b], [b, c]]: lambda = mean +- sqrt(diff^2 + b^2); e1 from the row of
// (S - lambda1 I) that is better conditioned; an isotropic matrix gets the image axes.
inline SymmetricEigen2Batch symmetric_eigen2(const simd::batch<float>& a, const simd::batch<float>& b,
                                             const simd::batch<float>& c) {
  using B = simd::batch<float>;
  const B zero(0.f), half(0.5f);
  const B mean = half * (a + c), diff = half * (a - c);
  const B r = simd::sqrt(diff * diff + b * b);
  const auto upper = diff >= zero;
  const B vx = simd::select(upper, diff + r, b), vy = simd::select(upper, b, r - diff);
  const B n2 = vx * vx + vy * vy;
  const auto ok = n2 > zero;
  const B inv = B(1.f) / simd::sqrt(simd::select(ok, n2, B(1.f)));
  return {mean + r, mean - r, simd::select(ok, vx * inv, B(1.f)), simd::select(ok, vy * inv, zero)};
}

}  // namespace detail

// One symmetric 2x2 matrix (lane 0 of the batched form).
inline SymmetricEigen2 symmetric_eigen2(const Eigen::Matrix2f& S) {
  using B = simd::batch<float>;
  const detail::SymmetricEigen2Batch E = detail::symmetric_eigen2(B(S(0, 0)), B(S(0, 1)), B(S(1, 1)));
  alignas(64) float l1[simd::width], l2[simd::width], x[simd::width], y[simd::width];
  E.lambda1.store_aligned(l1);
  E.lambda2.store_aligned(l2);
  E.e1x.store_aligned(x);
  E.e1y.store_aligned(y);
  SymmetricEigen2 out;
  out.lambda1 = l1[0];
  out.lambda2 = l2[0];
  out.e1 = {x[0], y[0]};
  out.e2 = {-y[0], x[0]};
  return out;
}

// A camera reduced to what abr_geometry reads, with the near/far planes, the Jacobian clamp
// (perspective_jacobian) and eps2d of ProjectionParams.
struct AbrCamera {
  float R[9], t[3], fx, fy, cx, cy;
  JacobianLimits lim;  // tx/z, ty/z clamp (frustum widened)
  float near_plane, far_plane, eps2d;

  static AbrCamera from(const Camera& c, const ProjectionParams& p) {
    AbrCamera a{};
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) a.R[3 * r + k] = c.R_w(r, k);
      a.t[r] = c.t_w[r];
    }
    a.fx = c.fx; a.fy = c.fy; a.cx = c.cx; a.cy = c.cy;
    a.lim = JacobianLimits::of(c, p.frustum_margin);
    a.near_plane = p.near_plane;
    a.far_plane = p.far_plane;
    a.eps2d = p.eps2d;
    return a;
  }
};

// abr_geometry's output: lane l describes Gaussian l of the batch.
struct AbrBatch {
  static constexpr std::size_t L = simd::width;
  alignas(64) float front[L];       // 1 when near_plane <= z <= far_plane (rule (e)), else 0
  alignas(64) float mx[L], my[L];   // projected centre m (pixels, conventions §2)
  alignas(64) float qx[3][L], qy[3][L];  // q_d = J R_w r_d (B.7)
  alignas(64) float det[L];         // det Sigma2D
  alignas(64) float lambda1[L], lambda2[L], e1x[L], e1y[L];  // eigen-decomposition of Sigma2D (Eq. 9)
  // Eq. 9's semi-axes a = sigma_c sqrt(max(lambda1, 0)), b (the same of lambda2), and the four
  // 3-sigma endpoints m + a e1, m - a e1, m + b e2, m - b e2 (e2 = (-e1.y, e1.x)), in that order.
  alignas(64) float axis[2][L];
  alignas(64) float ex[4][L], ey[4][L];

  Eigen::Vector2f m(std::size_t l) const { return {mx[l], my[l]}; }
  Eigen::Vector2f q(int d, std::size_t l) const { return {qx[d][l], qy[d][l]}; }
};

// Beyond the paper (a bound for skipping work; no result depends on it): an upper bound on
// Eq. 10's lambda_1 (largest eigenvalue of Sigma2D) for every Gaussian whose max_d s_d^2 is at
// most s2 and whose mean lies at camera depth z >= zmin > 0 and projects to u in [u0, u1], v in
// [v0, v1] (pixels). Sigma2D = J W Sigma W^T J^T + eps2d I with ||W Sigma W^T|| = max_d s_d^2,
// and J = diag(fx, fy) [[1, 0, -a], [0, 1, -b]] / z, a = tx/z, b = ty/z clamped (B.7), whose
// spectral norm is ||J||^2 <= (max(fx, fy) / z)^2 (1 + a^2 + b^2); |a| <= max |u - cx| / fx over
// the rectangle (clamping only shrinks it) and <= the clamp's own limit, b alike.
inline float lambda1_bound(const AbrCamera& C, float u0, float v0, float u1, float v1, float zmin, float s2) {
  const float a = std::min(std::max(std::abs(u0 - C.cx), std::abs(u1 - C.cx)) / C.fx, std::max(C.lim.x_pos, C.lim.x_neg));
  const float b = std::min(std::max(std::abs(v0 - C.cy), std::abs(v1 - C.cy)) / C.fy, std::max(C.lim.y_pos, C.lim.y_neg));
  const float f = std::max(C.fx, C.fy) / zmin;
  return f * f * (1.f + a * a + b * b) * s2 + C.eps2d;
}

// Eq. 9-10 and B.7 for simd::width Gaussians: means x, y, z, rotations rot[e] (R(e % 3, e / 3),
// column-major) and scales s[d], each a pointer to simd::width consecutive values; endpoints at
// sigma_c standard deviations. The perspective Jacobian is perspective_jacobian's (tx/z, ty/z
// clamped); Sigma2D = sum_d s_d^2 q_d q_d^T + eps2d I. Kept out of line: every caller runs the same instructions, so a Gaussian
// gets the same bits whichever lane or caller computes it.
[[gnu::noinline]] inline void abr_geometry(const AbrCamera& C, const float* x, const float* y, const float* z,
                                           const float* const rot[9], const float* const s[3], float sigma_c,
                                           AbrBatch& out) {
  using B = simd::batch<float>;
  const B X = B::load_unaligned(x), Y = B::load_unaligned(y), Z = B::load_unaligned(z), zero(0.f);
  auto row = [&](int r) {  // t = R_w mu + t_w
    return simd::fma(B(C.R[3 * r]), X, simd::fma(B(C.R[3 * r + 1]), Y, simd::fma(B(C.R[3 * r + 2]), Z, B(C.t[r]))));
  };
  const B tx = row(0), ty = row(1), tz = row(2);
  simd::select((tz >= B(C.near_plane)) & (tz <= B(C.far_plane)), B(1.f), zero).store_aligned(out.front);
  const B mx = B(C.fx) * tx / tz + B(C.cx), my = B(C.fy) * ty / tz + B(C.cy);  // m = (fx x / z + cx, fy y / z + cy)
  mx.store_aligned(out.mx);
  my.store_aligned(out.my);
  // Perspective Jacobian (B.7), its rows (j0, 0, j2) and (0, j4, j5).
  const B rz = B(1.f) / tz, rz2 = rz * rz;
  const B cx = tz * simd::min(B(C.lim.x_pos), simd::max(-B(C.lim.x_neg), tx * rz));
  const B cy = tz * simd::min(B(C.lim.y_pos), simd::max(-B(C.lim.y_neg), ty * rz));
  const B j0 = B(C.fx) * rz, j2 = -(B(C.fx) * cx * rz2), j4 = B(C.fy) * rz, j5 = -(B(C.fy) * cy * rz2);
  // M = J R_w (2 x 3).
  B M0[3], M1[3];
  for (int k = 0; k < 3; ++k) {
    M0[k] = j0 * B(C.R[k]) + j2 * B(C.R[6 + k]);
    M1[k] = j4 * B(C.R[3 + k]) + j5 * B(C.R[6 + k]);
  }
  B a(C.eps2d), b(0.f), c(C.eps2d);
  for (int d = 0; d < 3; ++d) {
    const B r0 = B::load_unaligned(rot[3 * d]), r1 = B::load_unaligned(rot[3 * d + 1]), r2 = B::load_unaligned(rot[3 * d + 2]);
    const B qx = M0[0] * r0 + M0[1] * r1 + M0[2] * r2;  // q_d = M r_d (B.7)
    const B qy = M1[0] * r0 + M1[1] * r1 + M1[2] * r2;
    qx.store_aligned(out.qx[d]);
    qy.store_aligned(out.qy[d]);
    const B sd = B::load_unaligned(s[d]), s2 = sd * sd;
    a = a + s2 * qx * qx;  // Sigma2D = sum_d s_d^2 q_d q_d^T + eps2d I (Eq. 10)
    b = b + s2 * qx * qy;
    c = c + s2 * qy * qy;
  }
  (a * c - b * b).store_aligned(out.det);
  const detail::SymmetricEigen2Batch E = detail::symmetric_eigen2(a, b, c);  // Eq. 9
  E.lambda1.store_aligned(out.lambda1);
  E.lambda2.store_aligned(out.lambda2);
  E.e1x.store_aligned(out.e1x);
  E.e1y.store_aligned(out.e1y);
  const B a1 = B(sigma_c) * simd::sqrt(simd::max(E.lambda1, zero));  // Eq. 9: a, b
  const B b1 = B(sigma_c) * simd::sqrt(simd::max(E.lambda2, zero));
  a1.store_aligned(out.axis[0]);
  b1.store_aligned(out.axis[1]);
  const B ux[4] = {E.e1x, -E.e1x, -E.e1y, E.e1y}, uy[4] = {E.e1y, -E.e1y, E.e1x, -E.e1x};
  for (int k = 0; k < 4; ++k) {
    const B len = k < 2 ? a1 : b1;
    (mx + len * ux[k]).store_aligned(out.ex[k]);
    (my + len * uy[k]).store_aligned(out.ey[k]);
  }
}

}  // namespace vcar
