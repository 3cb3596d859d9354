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
// The camera's values are floats (one camera, in every lane) or batches (one camera per lane,
// project_boxes); either way each lane runs the same operations.
template <class T>
inline ImagePoints image_points(const T (&R)[9], const T (&t)[3], const T& fx, const T& fy, const T& cx, const T& cy,
                                const simd::batch<float>& X, const simd::batch<float>& Y, const simd::batch<float>& Z) {
  using B = simd::batch<float>;
  auto row = [&](int r) {  // t = R_w mu + t_w
    return simd::fma(B(R[3 * r]), X, simd::fma(B(R[3 * r + 1]), Y, simd::fma(B(R[3 * r + 2]), Z, B(t[r]))));
  };
  const B tx = row(0), ty = row(1), tz = row(2);
  return {(B(fx) * tx) / tz + B(cx), (B(fy) * ty) / tz + B(cy), tz};  // conventions §2: u = fx x / z + cx
}
inline ImagePoints image_points(const MeanProjection& w, const simd::batch<float>& X, const simd::batch<float>& Y,
                                const simd::batch<float>& Z) {
  return image_points(w.R, w.t, w.fx, w.fy, w.cx, w.cy, X, Y, Z);
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
  float zmax = 0.f;                    // greatest, plus the rounding margin: every mean's depth as
                                       // project() computes it is at most this (when in front)
};

// Views in SIMD lanes (lane l: one view's projection), for project_boxes.
struct ViewLanes {
  using B = simd::batch<float>;
  B R[9], t[3], abs_R[9], abs_t[3], fx, fy, cx, cy, W, H;

  // Lane l: views[min(l, count - 1)] (count >= 1).
  static ViewLanes of(const MeanProjection* const* views, std::size_t count) {
    constexpr std::size_t L = simd::width;
    alignas(64) float lane[30][L];
    for (std::size_t l = 0; l < L; ++l) {
      const MeanProjection& w = *views[std::min(l, count - 1)];
      for (int i = 0; i < 9; ++i) lane[i][l] = w.R[i], lane[12 + i][l] = std::abs(w.R[i]);
      for (int i = 0; i < 3; ++i) lane[9 + i][l] = w.t[i], lane[21 + i][l] = std::abs(w.t[i]);
      lane[24][l] = w.fx, lane[25][l] = w.fy, lane[26][l] = w.cx, lane[27][l] = w.cy;
      lane[28][l] = static_cast<float>(w.width), lane[29][l] = static_cast<float>(w.height);
    }
    ViewLanes v;
    for (int i = 0; i < 9; ++i) v.R[i] = B::load_aligned(lane[i]), v.abs_R[i] = B::load_aligned(lane[12 + i]);
    for (int i = 0; i < 3; ++i) v.t[i] = B::load_aligned(lane[9 + i]), v.abs_t[i] = B::load_aligned(lane[21 + i]);
    v.fx = B::load_aligned(lane[24]), v.fy = B::load_aligned(lane[25]);
    v.cx = B::load_aligned(lane[26]), v.cy = B::load_aligned(lane[27]);
    v.W = B::load_aligned(lane[28]), v.H = B::load_aligned(lane[29]);
    return v;
  }
  static ViewLanes of(const MeanProjection& w) {
    const MeanProjection* p = &w;
    return of(&p, 1);
  }
};

// project_boxes' answers, lane by lane.
struct BoxViewLanes {
  static constexpr std::size_t L = simd::width;
  alignas(64) std::int32_t visibility[L], x0[L], y0[L], x1[L], y1[L];
  alignas(64) float zmin[L], zmax[L];
  BoxView operator[](std::size_t l) const {
    BoxView v;
    v.visibility = static_cast<BoxView::Case>(visibility[l]);
    v.x0 = x0[l], v.y0 = y0[l], v.x1 = x1[l], v.y1 = y1[l];
    v.zmin = zmin[l];
    v.zmax = zmax[l];
    return v;
  }
};

// Boxes in SIMD lanes (lane l: lo[d], hi[d] of one box), for project_boxes.
struct BoxLanes {
  using B = simd::batch<float>;
  B lo[3], hi[3];

  // The same box in every lane.
  static BoxLanes of(const float lo[3], const float hi[3]) {
    BoxLanes b;
    for (int d = 0; d < 3; ++d) b.lo[d] = B(lo[d]), b.hi[d] = B(hi[d]);
    return b;
  }
  // Lane l: boxes[min(l, count - 1)] (lo x, y, z, hi x, y, z first; count >= 1).
  template <std::size_t N>
  static BoxLanes of(const std::array<float, N>* boxes, std::size_t count) {
    static_assert(N >= 6);
    constexpr std::size_t L = simd::width;
    alignas(64) float lane[6][L];
    for (std::size_t l = 0; l < L; ++l)
      for (int i = 0; i < 6; ++i) lane[i][l] = boxes[std::min(l, count - 1)][static_cast<std::size_t>(i)];
    BoxLanes b;
    for (int d = 0; d < 3; ++d) b.lo[d] = B::load_aligned(lane[d]), b.hi[d] = B::load_aligned(lane[3 + d]);
    return b;
  }
};

// project_box lane by lane: box lane l in view lane l. The vote decides one chunk in several
// views with one call (the box in every lane), ABR several chunks in one view.
inline void project_boxes(const ViewLanes& w, const BoxLanes& b, BoxViewLanes& out) {
  using B = simd::batch<float>;
  const B zero(0.f), one(1.f);
  // Magnitude of the terms of t = R mu + t_w (rounding is relative to it), and whether the box
  // is finite (x - x is 0 exactly for finite x).
  auto magnitude = [](const B& p, const B& q) { return simd::max(simd::max(p, -p), simd::max(q, -q)); };
  const B extent[3] = {magnitude(b.lo[0], b.hi[0]), magnitude(b.lo[1], b.hi[1]), magnitude(b.lo[2], b.hi[2])};
  auto finite = (b.lo[0] - b.lo[0] >= zero) & (b.hi[0] - b.hi[0] >= zero);
  for (int k = 1; k < 3; ++k) finite = finite & (b.lo[k] - b.lo[k] >= zero) & (b.hi[k] - b.hi[k] >= zero);
  B scale = zero;
  for (int r = 0; r < 3; ++r) {
    B sr = w.abs_t[r];
    for (int k = 0; k < 3; ++k) sr = sr + w.abs_R[3 * r + k] * extent[k];
    scale = simd::max(scale, sr);
  }
  const auto ok = finite & (scale < B(1e30f));  // else: per-mean test
  // The 8 corners (bit d of c picks hi over lo on axis d), projected with project()'s
  // arithmetic; their least and greatest depth and image coordinates.
  B zmin, zmax, umin, umax, vmin, vmax;
  for (int c = 0; c < 8; ++c) {
    const B& X = (c & 1) ? b.hi[0] : b.lo[0];
    const B& Y = (c & 2) ? b.hi[1] : b.lo[1];
    const B& Z = (c & 4) ? b.hi[2] : b.lo[2];
    const auto [u, v, tz] = image_points(w.R, w.t, w.fx, w.fy, w.cx, w.cy, X, Y, Z);
    if (c == 0) {
      zmin = zmax = tz, umin = umax = u, vmin = vmax = v;
      continue;
    }
    zmin = simd::min(zmin, tz), zmax = simd::max(zmax, tz);
    umin = simd::min(umin, u), umax = simd::max(umax, u);
    vmin = simd::min(vmin, v), vmax = simd::max(vmax, v);
  }
  const B dz = B(1e-5f) * scale;
  const auto behind = ok & (zmax < -dz);  // every z < 0
  const auto front = ok & (zmin > dz);    // else straddles z = 0 (or not ok): per-mean test
  // Rounding of u = fx x / z + cx per mean: well below this margin (pixels).
  const B m = B(0.5f) + B(1e-5f) * ((w.fx + w.fy) * scale / zmin + magnitude(umin, umax) + magnitude(vmin, vmax));
  umin = umin - m, umax = umax + m, vmin = vmin - m, vmax = vmax + m;
  const auto outside = front & ((umax < zero) | (vmax < zero) | (umin >= w.W) | (vmin >= w.H));
  const auto inside = front & !outside;
  const auto all = inside & (umin >= zero) & (vmin >= zero) & (umax < w.W) & (vmax < w.H);
  // The rectangle where inside (clamped to the image, so every lane converts safely); the whole
  // image elsewhere.
  const B W1 = w.W - one, H1 = w.H - one;
  auto pixel = [&](const B& p, const B& hi_p, const B& fallback) {
    return simd::to_int(simd::floor(simd::select(inside, simd::min(simd::max(p, zero), hi_p), fallback)));
  };
  pixel(umin, W1, zero).store_aligned(out.x0);
  pixel(vmin, H1, zero).store_aligned(out.y0);
  pixel(umax, W1, W1).store_aligned(out.x1);
  pixel(vmax, H1, H1).store_aligned(out.y1);
  simd::select(inside, zmin, zero).store_aligned(out.zmin);
  simd::select(inside, zmax + dz, zero).store_aligned(out.zmax);
  const B none(static_cast<float>(BoxView::none_visible)), every(static_cast<float>(BoxView::all_visible)),
      partial(static_cast<float>(BoxView::partial));
  simd::to_int(simd::select(behind | outside, none, simd::select(all, every, partial))).store_aligned(out.visibility);
}

// project_boxes for one box in one view.
inline BoxView project_box(const MeanProjection& w, const float lo[3], const float hi[3]) {
  BoxViewLanes out;
  project_boxes(ViewLanes::of(w), BoxLanes::of(lo, hi), out);
  return out[0];
}

// Bounding box (lo x, y, z, hi x, y, z) of the means [begin, end) of SoA columns; a non-finite
// mean makes the box non-finite, which project_box answers with "partial" (per-mean test).
// Per axis: lo is NaN when some mean is not finite, else the least; hi is the greatest mean that
// is not NaN (-inf when none). simd::width means at a time, the rest one by one.
inline std::array<float, 6> mean_box(const float* x, const float* y, const float* z, std::size_t begin,
                                     std::size_t end) {
  using BF = simd::batch<float>;
  constexpr std::size_t L = simd::width;
  const float* c[3] = {x, y, z};
  std::array<float, 6> b{};
  for (int d = 0; d < 3; ++d) {
    BF lo(INFINITY), hi(-INFINITY), finite(0.f);  // finite: v - v stays 0 while every v is finite
    std::size_t j = begin;
    for (; j + L <= end; j += L) {
      const BF v = BF::load_unaligned(c[d] + j);
      lo = simd::min(lo, v);  // meaningless once a lane saw NaN, and then not used
      hi = simd::max(hi, simd::select(v >= BF(-INFINITY), v, BF(-INFINITY)));  // NaN: -inf
      finite = finite + (v - v);
    }
    alignas(64) float lo_l[L], hi_l[L], finite_l[L];
    lo.store_aligned(lo_l);
    hi.store_aligned(hi_l);
    finite.store_aligned(finite_l);
    float l = INFINITY, h = -INFINITY;
    bool all_finite = true;
    for (std::size_t i = 0; i < L; ++i) {
      l = std::min(l, lo_l[i]);
      h = std::max(h, hi_l[i]);
      all_finite = all_finite && finite_l[i] == 0.f;
    }
    for (; j < end; ++j) {
      const float v = c[d][j];
      all_finite = all_finite && std::isfinite(v);
      l = std::min(l, v);
      if (v == v) h = std::max(h, v);
    }
    b[d] = all_finite ? l : NAN;
    b[3 + d] = h;
  }
  return b;
}

}  // namespace vcar::detail
