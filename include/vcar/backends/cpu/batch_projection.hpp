#pragma once
// The renderer's projection of Lane::size Gaussians at once (SIMD over Gaussians): the same
// steps as core/projection.hpp's project_gaussian (B.6-B.7, Eq. 10, gsplat's near plane,
// Jacobian clamp, low-pass and opacity-aware extent), written for batches. Results equal
// project_gaussian's up to the last float bits (exp and log are xsimd's, multiply-adds fuse
// differently); every lane is computed alone, so the thread count changes nothing.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "vcar/backends/cpu/tile_binning.hpp"
#include "vcar/backends/cpu/tile_compositing.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/core/simd.hpp"

namespace vcar::cpu {

// Camera constants of the projection, computed once per call.
struct BatchCamera {
  float R[3][3], t[3];            // world to camera
  float fx, fy, cx, cy, W, H;     // intrinsics, image size (px)
  JacobianLimits lim;             // clamp on tx/tz, ty/tz (B.7, as perspective_jacobian)
  float tiles_x, tiles_y;

  BatchCamera(const Camera& cam, const ProjectionParams& p) : lim(JacobianLimits::of(cam, p.frustum_margin)) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R[r][c] = cam.R_w(r, c);
      t[r] = cam.t_w[r];
    }
    fx = cam.fx, fy = cam.fy, cx = cam.cx, cy = cam.cy;
    W = static_cast<float>(cam.width), H = static_cast<float>(cam.height);
    tiles_x = static_cast<float>((cam.width + tile_size - 1) / tile_size);
    tiles_y = static_cast<float>((cam.height + tile_size - 1) / tile_size);
  }
};

// One batch of Gaussians as the scene stores them: mean, log-scales, unnormalised quaternion
// (w, x, y, z), opacity logit.
struct GaussianBatch {
  Lane mu[3], log_s[3], q[4], logit;
};

// Drawn Gaussians k0 .. k0 + lanes - 1 of request q (1 <= lanes <= Lane::size): scene index
// subset[k] (or k), log-scales from q.log_scale (indexed by k) when given. Lanes past `lanes`
// repeat the last one.
inline GaussianBatch load_batch(const RenderRequest& q, std::size_t k0, int lanes) {
  constexpr int L = static_cast<int>(Lane::size);
  const GaussianScene& sc = *q.scene;
  const float* src[11] = {sc.mean[0].data(), sc.mean[1].data(), sc.mean[2].data(),
                          q.log_scale ? (*q.log_scale)[0].data() : sc.log_scale[0].data(),
                          q.log_scale ? (*q.log_scale)[1].data() : sc.log_scale[1].data(),
                          q.log_scale ? (*q.log_scale)[2].data() : sc.log_scale[2].data(),
                          sc.rotation[0].data(), sc.rotation[1].data(), sc.rotation[2].data(),
                          sc.rotation[3].data(), sc.opacity_logit.data()};
  GaussianBatch g;
  Lane* dst[11] = {&g.mu[0], &g.mu[1], &g.mu[2], &g.log_s[0], &g.log_s[1], &g.log_s[2],
                   &g.q[0], &g.q[1], &g.q[2], &g.q[3], &g.logit};
  if (!q.subset && lanes == L) {  // drawn index = scene index, log-scales indexed alike
    for (int c = 0; c < 11; ++c) *dst[c] = Lane::load_unaligned(src[c] + k0);
    return g;
  }
  alignas(64) float col[11][L];
  for (int l = 0; l < L; ++l) {
    const std::size_t k = k0 + static_cast<std::size_t>(std::min(l, lanes - 1));
    const std::size_t i = q.subset ? static_cast<std::size_t>((*q.subset)[k]) : k;
    for (int c = 0; c < 11; ++c) col[c][l] = src[c][(c >= 3 && c < 6 && q.log_scale) ? k : i];
  }
  for (int c = 0; c < 11; ++c) *dst[c] = Lane::load_aligned(col[c]);
  return g;
}

// Projects a batch; out_splat[l] / out_rect[l] for lanes l < lanes, rect 0 where culled (the
// splat is then left as it was). k0 + l is lane l's drawn index.
inline void project_batch(const BatchCamera& c, const ProjectionParams& p, const GaussianBatch& g,
                          std::uint32_t k0, int lanes, PackedSplat* out_splat, std::uint64_t* out_rect) {
  const Lane one(1.f), two(2.f), zero(0.f);
  const Lane op = one / (one + simd::exp(-g.logit));  // sigmoid(o)
  Lane s2[3];
  for (int d = 0; d < 3; ++d) {
    const Lane s = simd::exp(g.log_s[d]);
    s2[d] = s * s;
  }
  // Rotation from the normalised quaternion (core/rotation.hpp).
  const Lane n = simd::sqrt(g.q[0] * g.q[0] + g.q[1] * g.q[1] + g.q[2] * g.q[2] + g.q[3] * g.q[3]);
  const Lane w = g.q[0] / n, x = g.q[1] / n, y = g.q[2] / n, z = g.q[3] / n;
  const Lane R[3][3] = {{one - two * (y * y + z * z), two * (x * y - w * z), two * (x * z + w * y)},
                        {two * (x * y + w * z), one - two * (x * x + z * z), two * (y * z - w * x)},
                        {two * (x * z - w * y), two * (y * z + w * x), one - two * (x * x + y * y)}};
  // Camera-space mean t = R_w mu + t_w, projected mean (B.6).
  Lane t[3];
  for (int r = 0; r < 3; ++r) t[r] = Lane(c.R[r][0]) * g.mu[0] + Lane(c.R[r][1]) * g.mu[1] + Lane(c.R[r][2]) * g.mu[2] + Lane(c.t[r]);
  const auto in_depth = (t[2] >= Lane(p.near_plane)) && (t[2] <= Lane(p.far_plane));
  const Lane u = Lane(c.fx) * t[0] / t[2] + Lane(c.cx), v = Lane(c.fy) * t[1] / t[2] + Lane(c.cy);
  // Perspective Jacobian with tx/tz, ty/tz clamped (Eq. 10), M = J R_w.
  const Lane rz = one / t[2], rz2 = rz * rz;
  const Lane tx = t[2] * simd::min(Lane(c.lim.x_pos), simd::max(Lane(-c.lim.x_neg), t[0] * rz));
  const Lane ty = t[2] * simd::min(Lane(c.lim.y_pos), simd::max(Lane(-c.lim.y_neg), t[1] * rz));
  const Lane j00 = Lane(c.fx) * rz, j02 = -Lane(c.fx) * tx * rz2, j11 = Lane(c.fy) * rz, j12 = -Lane(c.fy) * ty * rz2;
  Lane M[2][3];
  for (int k = 0; k < 3; ++k) {
    M[0][k] = j00 * Lane(c.R[0][k]) + j02 * Lane(c.R[2][k]);
    M[1][k] = j11 * Lane(c.R[1][k]) + j12 * Lane(c.R[2][k]);
  }
  // Sigma2D = sum_d s_d^2 q_d q_d^T + eps2d I, q_d = M r_d (Eq. 10, B.7).
  Lane S00 = Lane(p.eps2d), S01 = zero, S11 = Lane(p.eps2d);
  for (int d = 0; d < 3; ++d) {
    const Lane q0 = M[0][0] * R[0][d] + M[0][1] * R[1][d] + M[0][2] * R[2][d];
    const Lane q1 = M[1][0] * R[0][d] + M[1][1] * R[1][d] + M[1][2] * R[2][d];
    S00 = S00 + s2[d] * q0 * q0;
    S01 = S01 + s2[d] * q0 * q1;
    S11 = S11 + s2[d] * q1 * q1;
  }
  const Lane det = S00 * S11 - S01 * S01;
  const auto valid = in_depth && (det > zero) && (op >= Lane(p.alpha_min));
  const Lane ln_op = simd::log(op / Lane(p.alpha_min));  // ln(opacity / alpha_min): sigma at alpha_min
  const Lane extend = simd::min(Lane(p.extend_max), simd::sqrt(two * ln_op));
  // Radii, capped so that they stay exact integers as floats.
  const Lane cap(1e7f);
  const Lane rx = simd::min(cap, simd::ceil(extend * simd::sqrt(S00)));
  const Lane ry = simd::min(cap, simd::ceil(extend * simd::sqrt(S11)));
  const auto on_screen = valid && ((rx > zero) || (ry > zero)) && (u + rx > zero) && (u - rx < Lane(c.W)) &&
                         (v + ry > zero) && (v - ry < Lane(c.H));
  // Touched tiles (tile_rect), clamped to the image.
  const Lane inv_ts(1.f / static_cast<float>(tile_size));  // a power of two: same bits as / tile_size
  auto clamp_tiles = [&](const Lane& a, float tiles) { return simd::min(Lane(tiles), simd::max(zero, a)); };
  const Lane tx0 = clamp_tiles(simd::floor((u - rx) * inv_ts), c.tiles_x), tx1 = clamp_tiles(simd::ceil((u + rx) * inv_ts), c.tiles_x);
  const Lane ty0 = clamp_tiles(simd::floor((v - ry) * inv_ts), c.tiles_y), ty1 = clamp_tiles(simd::ceil((v + ry) * inv_ts), c.tiles_y);

  constexpr int L = static_cast<int>(Lane::size);
  alignas(64) float a[17][L];
  const Lane keep = simd::select(on_screen, one, zero);
  // Extents of the exact ellipse sigma <= sigma_max + slack: min over x of sigma at height dy is
  // dy^2 / (2 S11), so no row beyond sqrt(2 s S11) has a pixel with alpha >= alpha_min.
  const Lane ln_slack = simd::max(zero, ln_op) + Lane(sigma_slack), margin(1e-2f);
  const Lane ex = simd::sqrt(two * ln_slack * S00) + margin, ey = simd::sqrt(two * ln_slack * S11) + margin;
  const Lane cols[17] = {u, v, rx, ry, S11 / det, -S01 / det, S00 / det, ln_op, op, t[2], keep, tx0, tx1, ty0, ty1, ex, ey};
  for (int i = 0; i < 17; ++i) cols[i].store_aligned(a[i]);
  for (int l = 0; l < lanes; ++l) {
    if (a[10][l] == 0.f) {
      out_rect[l] = 0;  // culled (gsplat)
      continue;
    }
    out_splat[l] = {a[0][l], a[1][l], a[2][l], a[3][l], a[4][l], a[5][l], a[6][l], a[7][l], a[8][l], a[9][l],
                    0.f, 0.f, 0.f, k0 + static_cast<std::uint32_t>(l), a[15][l], a[16][l]};
    out_rect[l] = pack_rect(static_cast<std::int32_t>(a[11][l]), static_cast<std::int32_t>(a[12][l]),
                            static_cast<std::int32_t>(a[13][l]), static_cast<std::int32_t>(a[14][l]));
  }
}

}  // namespace vcar::cpu
