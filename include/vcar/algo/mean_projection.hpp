#pragma once
// Eq. 1 for a SIMD batch of Gaussian means (SoA x, y, z): the one projection that voting and
// the valid-camera filter (A.1) share, so both apply exactly the same visibility test.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/simd.hpp"

namespace vcar::detail {

// The means of `candidates` (scene indices, any order) as SoA columns, for a voter that
// projects a subset of the scene; an index outside the scene is an error.
inline std::array<std::vector<float>, 3> candidate_means(const GaussianScene& scene,
                                                         const std::vector<Index>& candidates) {
  std::array<std::vector<float>, 3> out;
  for (int d = 0; d < 3; ++d) {
    out[d].resize(candidates.size());
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      if (candidates[k] >= scene.size())
        throw Error("candidate index " + std::to_string(candidates[k]) + " out of range", "voting");
      out[d][k] = scene.mean[d][candidates[k]];
    }
  }
  return out;
}

// A camera reduced to what the projection of means needs.
struct MeanProjection {
  float R[9], t[3], fx, fy, cx, cy;
  int width, height;

  static MeanProjection from(const Camera& c) {
    MeanProjection p{};
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) p.R[3 * r + k] = c.R_w(r, k);
      p.t[r] = c.t_w[r];
    }
    p.fx = c.fx; p.fy = c.fy; p.cx = c.cx; p.cy = c.cy;
    p.width = c.width; p.height = c.height;
    return p;
  }
};

inline constexpr std::size_t mean_batch = simd::width;

// Eq. 1 for one batch of means, in registers: the containing pixel's column iu, row iv and index
// pix = iv * W + iu (all 0 when invisible), visibility (0/1) and camera depth z per lane.
struct ProjectedBatch {
  simd::batch<std::int32_t> pix, vis, iu, iv;
  simd::batch<float> z;
};

// Image point (u, v) and camera depth z of a batch of points (X, Y, Z): the arithmetic that
// project() and project_box share.
struct ImagePoints {
  simd::batch<float> u, v, z;
};
inline ImagePoints image_points(const MeanProjection& w, const simd::batch<float>& X, const simd::batch<float>& Y,
                                const simd::batch<float>& Z) {
  using B = simd::batch<float>;
  auto row = [&](int r) {  // t = R_w mu + t_w
    return simd::fma(B(w.R[3 * r]), X, simd::fma(B(w.R[3 * r + 1]), Y, simd::fma(B(w.R[3 * r + 2]), Z, B(w.t[r]))));
  };
  const B tx = row(0), ty = row(1), tz = row(2);
  return {(B(w.fx) * tx) / tz + B(w.cx), (B(w.fy) * ty) / tz + B(w.cy), tz};  // conventions §2: u = fx x / z + cx
}

inline ProjectedBatch project(const MeanProjection& w, const float* x, const float* y, const float* z) {
  using B = simd::batch<float>;
  using BI = simd::batch<std::int32_t>;
  const auto [u, v, tz] = image_points(w, B::load_unaligned(x), B::load_unaligned(y), B::load_unaligned(z));
  // Eq. 1: z > 0, 0 <= u < W, 0 <= v < H (NaN fails every comparison).
  const auto in = (tz > B(0.f)) & (u >= B(0.f)) & (u < B(static_cast<float>(w.width))) &
                  (v >= B(0.f)) & (v < B(static_cast<float>(w.height)));
  const BI iu = simd::to_int(simd::select(in, u, B(0.f)));  // truncation = floor for u >= 0
  const BI iv = simd::to_int(simd::select(in, v, B(0.f)));
  return {iv * BI(w.width) + iu, simd::to_int(simd::select(in, B(1.f), B(0.f))), iu, iv, tz};
}

// project() stored to arrays of mean_batch lanes.
inline void project_batch(const MeanProjection& w, const float* x, const float* y, const float* z,
                          std::int32_t* pix, std::int32_t* vis, float* depth) {
  const ProjectedBatch p = project(w, x, y, z);
  p.pix.store_unaligned(pix);
  p.vis.store_unaligned(vis);
  p.z.store_unaligned(depth);
}

// project_batch for the first m < mean_batch lanes (the tail); lanes >= m come out invisible.
inline void project_tail(const MeanProjection& w, const float* x, const float* y, const float* z, std::size_t m,
                         std::int32_t* pix, std::int32_t* vis, float* depth) {
  alignas(64) float px[mean_batch], py[mean_batch], pz[mean_batch];
  for (std::size_t l = 0; l < mean_batch; ++l) {
    px[l] = l < m ? x[l] : 0.f; py[l] = l < m ? y[l] : 0.f; pz[l] = l < m ? z[l] : 0.f;
  }
  project_batch(w, px, py, pz, pix, vis, depth);
  for (std::size_t l = m; l < mean_batch; ++l) { vis[l] = 0; pix[l] = 0; }
}

}  // namespace vcar::detail

namespace vcar::detail {

// Eq. 1 for a whole box of means at once. The camera depth is affine in the point and the
// projection of a box in front of the camera lies in the 2D bounding box of its 8 projected
// corners, so one view can decide a whole run of means (a Morton-ordered chunk) when the box
// is clearly on one side of every test; a margin far above float rounding keeps the decision
// equal to the per-mean test of project().
struct BoxView {
  enum Case : std::uint8_t { none_visible, all_visible, partial };
  Case visibility = partial;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixel rectangle holding every visible projected mean
  float zmin = 0.f;                    // smallest camera depth of the corners (when in front)
};

inline BoxView project_box(const MeanProjection& w, const float lo[3], const float hi[3]) {
  BoxView out;
  out.x1 = w.width - 1;  // until known: the whole image
  out.y1 = w.height - 1;
  float scale = 0;  // magnitude of the terms of t = R mu + t_w (rounding is relative to it)
  for (int r = 0; r < 3; ++r) {
    float s = std::abs(w.t[r]);
    for (int k = 0; k < 3; ++k) s += std::abs(w.R[3 * r + k]) * std::max(std::abs(lo[k]), std::abs(hi[k]));
    scale = std::max(scale, s);
  }
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(lo[k]) || !std::isfinite(hi[k])) return out;  // non-finite box: per-mean test
  if (!(scale < 1e30f)) return out;
  // The 8 corners in SIMD lanes (corner c = lane mod 8: bit d of c picks hi over lo on axis d),
  // projected with project()'s arithmetic; a 16-lane batch holds each corner twice.
  using B = simd::batch<float>;
  constexpr std::size_t L = simd::width, N = L > 8 ? L : 8;
  alignas(64) static constexpr auto corner_bit = [] {
    std::array<std::array<float, N>, 3> b{};
    for (std::size_t c = 0; c < N; ++c)
      for (int d = 0; d < 3; ++d) b[d][c] = static_cast<float>(((c % 8) >> d) & 1);
    return b;
  }();
  alignas(64) float us[N], vs[N], zs[N];
  for (std::size_t c0 = 0; c0 < N; c0 += L) {
    B p[3];
    for (int d = 0; d < 3; ++d) p[d] = simd::select(B::load_aligned(corner_bit[d].data() + c0) > B(0.5f), B(hi[d]), B(lo[d]));
    const ImagePoints q = image_points(w, p[0], p[1], p[2]);  // (u, v: unused where z <= 0)
    q.z.store_aligned(zs + c0);
    q.u.store_aligned(us + c0);
    q.v.store_aligned(vs + c0);
  }
  float zmin = zs[0], zmax = zs[0];
  for (std::size_t c = 1; c < 8; ++c) zmin = std::min(zmin, zs[c]), zmax = std::max(zmax, zs[c]);
  const float dz = 1e-5f * scale;
  if (zmax < -dz) { out.visibility = BoxView::none_visible; return out; }  // every z < 0
  if (!(zmin > dz)) return out;                                            // straddles z = 0
  out.zmin = zmin;
  float umin = us[0], umax = us[0], vmin = vs[0], vmax = vs[0];
  for (std::size_t c = 1; c < 8; ++c) {
    umin = std::min(umin, us[c]); umax = std::max(umax, us[c]);
    vmin = std::min(vmin, vs[c]); vmax = std::max(vmax, vs[c]);
  }
  // Rounding of u = fx x / z + cx per mean: well below this margin (pixels).
  const float m = 0.5f + 1e-5f * ((w.fx + w.fy) * scale / zmin + std::max(std::abs(umin), std::abs(umax)) +
                                  std::max(std::abs(vmin), std::abs(vmax)));
  umin -= m; umax += m; vmin -= m; vmax += m;
  const float W = static_cast<float>(w.width), H = static_cast<float>(w.height);
  if (umax < 0.f || vmax < 0.f || umin >= W || vmin >= H) { out.visibility = BoxView::none_visible; return out; }
  out.x0 = static_cast<int>(std::floor(std::max(umin, 0.f)));
  out.y0 = static_cast<int>(std::floor(std::max(vmin, 0.f)));
  out.x1 = static_cast<int>(std::floor(std::min(umax, W - 1.f)));
  out.y1 = static_cast<int>(std::floor(std::min(vmax, H - 1.f)));
  if (umin >= 0.f && vmin >= 0.f && umax < W && vmax < H) out.visibility = BoxView::all_visible;
  return out;
}

// Bounding box (lo x, y, z, hi x, y, z) of the means [begin, end) of SoA columns; a non-finite
// mean makes the box non-finite, which project_box answers with "partial" (per-mean test).
inline std::array<float, 6> mean_box(const float* x, const float* y, const float* z, std::size_t begin,
                                     std::size_t end) {
  const float* c[3] = {x, y, z};
  std::array<float, 6> b{INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
  for (std::size_t j = begin; j < end; ++j)
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(c[d][j])) b[d] = NAN;  // std::min keeps a NaN first argument
      b[d] = std::min(b[d], c[d][j]);
      b[3 + d] = std::max(b[3 + d], c[d][j]);
    }
  return b;
}

}  // namespace vcar::detail
