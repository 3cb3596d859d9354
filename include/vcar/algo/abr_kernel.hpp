#pragma once
// The kernel of Axis-aware Boundary Refinement, ABR (Sec. 3.4, Eq. 9-13; supplementary B.1-B.3):
// what one view says about one Gaussian, simd::width Gaussians at a time: Eq. 11's axis
// contributions, the march to the mask boundary (B.3), Eq. 13's compression factor, and the
// per-view tests that decide whole chunks of candidates from a mask's tiles. AbrState keeps what
// the views say per candidate; BoundaryRefinement and IncrementalRefinement drive it.
//
// Rules where the paper leaves room (each is tested):
//  (a) Eq. 13 numerator (l/sigma_c)^2 - lambda + w_{d*} <= 0: the other axes (and eps2d) already
//      exceed the boundary, no factor in [f_min, 1] reaches it, the candidate is f_min (B.3).
//  (b) An observation is eligible (n_vis) only when the projected centre is inside the image and
//      on the mask foreground (B.1); a centre on background contributes nothing.
//  (c) w_{d*} == 0 (every axis projects to a point along u; lambda is eps2d only): no candidate.
//  (d) eps2d (conventions §3) is owned by no axis: lambda = sum_d w_d + eps2d u^T u, so it stays in
//      lambda - w_{d*} of Eq. 13.
//  (e) Geometry only: the projection is called with opacity 1 (ABR reads mean, scale, rotation);
//      a centre behind the near plane or beyond the far plane is not eligible.
//  (f) d* ties go to the lowest axis index.
//  (g) Candidates are processed internally in Morton order of their means (cache locality of
//      the mask lookups); every output stays aligned with the candidates as given.
// `reference_code_rules` (conventions §7) switches to the released code: a candidate only when
// (l/sigma_c)^2 < lambda, and the dominant share of lambda is lambda w_{d*} / sum_d w_d (eps2d
// spread over the axes in proportion) in place of w_{d*}.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Core>

#include "vcar/algo/abr_geometry.hpp"
#include "vcar/algo/abr_params.hpp"
#include "vcar/algo/boundary_distance.hpp"
#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"

namespace vcar {

namespace detail {

using FloatBatch = simd::batch<float>;

// Eq. 11 lane by lane: w_d = s_d^2 (u^T q_d)^2.
inline std::array<FloatBatch, 3> axis_contributions(const FloatBatch (&qx)[3], const FloatBatch (&qy)[3],
                                                    const FloatBatch (&s)[3], const FloatBatch& ux,
                                                    const FloatBatch& uy) {
  std::array<FloatBatch, 3> w;
  for (int d = 0; d < 3; ++d) {
    const FloatBatch uq = ux * qx[d] + uy * qy[d];
    w[d] = s[d] * s[d] * uq * uq;
  }
  return w;
}

// Eq. 13 lane by lane, rules (a) and (c) or the reference-code rules: w_star = w_{d*}, w_sum =
// w_0 + w_1 + w_2. The factor of the dominant axis, unclamped above; +inf: no candidate.
inline FloatBatch compression_factor(const FloatBatch& l_u, const FloatBatch& lambda, const FloatBatch& w_star,
                                     const FloatBatch& w_sum, const AbrParams& p) {
  const FloatBatch zero(0.f), r = l_u / FloatBatch(p.sigma_c);
  const FloatBatch target = r * r;  // (l_u / sigma_c)^2, px^2
  auto none = !(w_star > zero);     // rule (c)
  FloatBatch ws = w_star;
  if (p.reference_code_rules) {
    none = none | !(target < lambda);
    ws = lambda * w_star / w_sum;  // dominant share of lambda
  }
  const FloatBatch numerator = target - lambda + ws;  // Eq. 13
  const auto positive = numerator > zero;
  const FloatBatch f = simd::select(positive, simd::sqrt(simd::select(positive, numerator, zero) / ws),
                                    FloatBatch(p.f_min));  // Eq. 13; rule (a)
  return simd::select(none, FloatBatch(std::numeric_limits<float>::infinity()), f);
}

// Eq. 13 solved for l_u, lane by lane: an endpoint's factor (rules as compression_factor),
// clamped below at f_min, is below `beat` (> f_min) only where l_u < l*. Returns the march sample
// index sigma_c l* / step + 1/2 (the exit distance (k - 1/2) step < l*), or -inf where even
// l_u = 0 cannot beat it; last_sample turns it into the last sample a march must reach.
inline FloatBatch march_reach(const FloatBatch& beat, const FloatBatch& lambda, const FloatBatch& w_star,
                              const FloatBatch& w_sum, const FloatBatch& step, const AbrParams& p) {
  const FloatBatch ws = p.reference_code_rules ? lambda * w_star / w_sum : w_star;
  // f < beat  <=>  (l / sigma_c)^2 - lambda + w* < beat^2 w*  (Eq. 13, numerator > 0 or not)
  const FloatBatch l2 = lambda - ws + beat * beat * ws, zero(0.f);
  const auto can = l2 > zero;
  const FloatBatch k = FloatBatch(p.sigma_c) * simd::sqrt(simd::select(can, l2, zero)) / step + FloatBatch(0.5f);
  return simd::select(can, k, FloatBatch(-std::numeric_limits<float>::infinity()));
}
// The last sample (of `samples`) a march must reach to find every exit within `reach`, with a
// margin of two samples for rounding; -1: none can beat.
inline int last_sample(float reach, int samples) {
  if (reach == -std::numeric_limits<float>::infinity()) return -1;
  return reach < static_cast<float>(samples) ? std::min(samples - 1, static_cast<int>(reach) + 2) : samples - 1;
}

// Lane 0 of a batch.
inline float lane0(const FloatBatch& b) {
  alignas(64) float v[simd::width];
  b.store_aligned(v);
  return v[0];
}

}  // namespace detail

// Eq. 11: w_d = s_d^2 (u^T q_d)^2, the variance that axis d contributes along unit u (lane 0 of
// the batched form that BoundaryRefinement runs).
inline std::array<float, 3> axis_contributions(const std::array<Eigen::Vector2f, 3>& q,
                                               const Eigen::Vector3f& s, const Eigen::Vector2f& u) {
  using B = detail::FloatBatch;
  const B qx[3] = {B(q[0].x()), B(q[1].x()), B(q[2].x())}, qy[3] = {B(q[0].y()), B(q[1].y()), B(q[2].y())};
  const B sb[3] = {B(s[0]), B(s[1]), B(s[2])};
  const auto w = detail::axis_contributions(qx, qy, sb, B(u.x()), B(u.y()));
  return {detail::lane0(w[0]), detail::lane0(w[1]), detail::lane0(w[2])};
}

// Eq. 13 with the B.3 rules (a), (c) above, or the reference-code rules: the candidate factor of
// the dominant axis d_star for one overflowing endpoint, unclamped above; +inf means "no
// candidate" (lane 0 of the batched form).
inline float compression_factor(float l_u, float lambda, const std::array<float, 3>& w, int d_star,
                                const AbrParams& p) {
  using B = detail::FloatBatch;
  return detail::lane0(detail::compression_factor(B(l_u), B(lambda), B(w[d_star]), B(w[0] + w[1] + w[2]), p));
}

// Eq. 13 solved for l_u: the factor of an endpoint (rules as compression_factor), clamped below
// at f_min, is below `beat` (> f_min) only where l_u < l*. The factor grows with l_u, and so
// does the march's l_u with its exit sample: returns the last sample a march must reach to find
// every exit whose factor can be below `beat` (with a margin of two samples for rounding), -1
// when even l_u = 0 cannot beat it (lane 0 of the batched form).
inline int last_sample_that_can_beat(float beat, float lambda, const std::array<float, 3>& w, int d_star,
                                     float step, int samples, const AbrParams& p) {
  using B = detail::FloatBatch;
  return detail::last_sample(
      detail::lane0(detail::march_reach(B(beat), B(lambda), B(w[d_star]), B(w[0] + w[1] + w[2]), B(step), p)), samples);
}

// What one view says about one Gaussian (B.1-B.3).
struct AbrObservation {
  bool eligible = false;  // centre projected inside the image and on foreground (B.1)
  bool overflow = false;  // some endpoint outside the image or on background (B.1)
  // Smallest candidate factor per axis over this view's overflowing endpoints; +inf: none.
  std::array<float, 3> f{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                         std::numeric_limits<float>::infinity()};
};

// What the tracing of overflowing endpoints reads and writes for the simd::width Gaussians of
// one AbrBatch, lane by lane.
struct AbrLanes {
  static constexpr std::size_t L = simd::width;
  alignas(64) float s[3][L];            // scales s_d
  // The running minimum per axis, clamped below at f_min: an endpoint whose clamped factor
  // cannot be below it is not traced (its factor stays +inf); +inf traces every endpoint in full.
  alignas(64) float beat[3][L];
  alignas(64) std::int32_t outside[L];  // bit k: endpoint k (Eq. 9's order) outside the mask or image
  alignas(64) float f[3][L];            // out: smallest candidate factor per axis, +inf: none
};

// Bit k set when 3-sigma endpoint k (Eq. 9) of lane l lies outside the foreground or the image
// (B.1), looked up without a branch per endpoint: most Gaussians have none.
inline std::int32_t outside_endpoints(const Mask& mask, const AbrBatch& g, std::size_t l) {
  std::int32_t bits = 0;
  for (int k = 0; k < 4; ++k) bits |= static_cast<std::int32_t>(!mask_at_branchless(mask, g.ex[k][l], g.ey[k][l])) << k;
  return bits;
}

// B.3 for the lanes of g set in `lanes` (Gaussians whose centre lies on the mask's foreground and
// some of whose endpoints, a.outside, do not): for each such endpoint, u (Eq. 9), w_d (Eq. 11), d*
// (ties to the lowest axis, rule (f)), the march to the boundary l_u (B.3, at most to the last
// sample whose exit can beat a.beat[d*]), and the factor of Eq. 13 into a.f[d*] (the smallest over
// the endpoints). The arithmetic runs across lanes, once per ellipse axis (its two endpoints
// share d* and Eq. 13, and their minimum is the factor of the shorter l_u); the march, lane by
// lane, reads `march`, the Mask itself or its MaskTiles (the same answers). Lanes outside
// `lanes` get +inf.
template <class MarchMask>
inline void trace_overflow(const MarchMask& march, const AbrBatch& g, unsigned lanes, const AbrParams& p, AbrLanes& a) {
  using B = detail::FloatBatch;
  constexpr std::size_t W = simd::width;
  const B zero(0.f), inf(std::numeric_limits<float>::infinity());
  B F[3] = {inf, inf, inf};
  const int samples = p.boundary_samples;
  const B s[3] = {B::load_aligned(a.s[0]), B::load_aligned(a.s[1]), B::load_aligned(a.s[2])};
  const B beat[3] = {B::load_aligned(a.beat[0]), B::load_aligned(a.beat[1]), B::load_aligned(a.beat[2])};
  const B qx[3] = {B::load_aligned(g.qx[0]), B::load_aligned(g.qx[1]), B::load_aligned(g.qx[2])};
  const B qy[3] = {B::load_aligned(g.qy[0]), B::load_aligned(g.qy[1]), B::load_aligned(g.qy[2])};
  const B l1 = B::load_aligned(g.lambda1), l2 = B::load_aligned(g.lambda2);
  const B lam[2] = {simd::select(l1 < zero, zero, l1), simd::select(l2 < zero, zero, l2)};  // max(lambda, 0)
  const B e1x = B::load_aligned(g.e1x), e1y = B::load_aligned(g.e1y);
  const B axis[2] = {B::load_aligned(g.axis[0]), B::load_aligned(g.axis[1])};  // a, b (Eq. 9)
  const B steps[2] = {axis[0] / B(static_cast<float>(samples - 1)), axis[1] / B(static_cast<float>(samples - 1))};
  alignas(64) float ux_[W], uy_[W], step_[W], reach_[W], c_[W], L_[W], lu_[W], traced_[W];
  const simd::batch<std::int32_t> outside = simd::batch<std::int32_t>::load_aligned(a.outside);
  for (int ax = 0; ax < 2; ++ax) {  // the endpoints m + L u and m - L u of one ellipse axis (Eq. 9)
    const unsigned plus = lanes & simd::nonzero_lanes(outside & simd::batch<std::int32_t>(1 << (2 * ax)));
    const unsigned minus = lanes & simd::nonzero_lanes(outside & simd::batch<std::int32_t>(2 << (2 * ax)));
    if (!(plus | minus)) continue;
    // u = e1, or e2 = (-e1.y, e1.x) (Eq. 9's endpoint order: +e1, -e1, +e2, -e2). w_d (Eq. 11)
    // is even in u, so d*, the reach of the march and Eq. 13 are the same for u and -u.
    const B ux = ax ? -e1y : e1x, uy = ax ? e1x : e1y;
    const std::array<B, 3> w = detail::axis_contributions(qx, qy, s, ux, uy);  // Eq. 11
    const auto c10 = w[1] > w[0], c21 = w[2] > w[1], c20 = w[2] > w[0];  // d* = argmax w_d (Eq. 11)
    const auto is2 = (c10 & c21) | (!c10 & c20), is1 = c10 & !c21;
    const B w_star = simd::select(is2, w[2], simd::select(is1, w[1], w[0]));
    const B c = simd::select(is2, beat[2], simd::select(is1, beat[1], beat[0]));
    const B w_sum = w[0] + w[1] + w[2];
    const B lambda = lam[ax], step = steps[ax];
    ux.store_aligned(ux_);
    uy.store_aligned(uy_);
    step.store_aligned(step_);
    axis[ax].store_aligned(L_);
    c.store_aligned(c_);
    detail::march_reach(c, lambda, w_star, w_sum, step, p).store_aligned(reach_);
    unsigned traced = 0;
    for (unsigned m = plus | minus; m; m &= m - 1) {
      const int l = std::countr_zero(m);
      if (!(c_[l] > p.f_min)) continue;  // the minimum is already f_min
      int last = detail::last_sample(reach_[l], samples);
      // Eq. 13's factor grows with l_u: the smaller l_u of the pair gives the pair's minimum, so
      // the second march needs to reach only to just before the first one's exit.
      for (int side = 0; side < 2 && last >= 0; ++side) {
        if (!((((side ? minus : plus) >> l) & 1u))) continue;
        const Eigen::Vector2f u = side ? Eigen::Vector2f(-ux_[l], -uy_[l]) : Eigen::Vector2f(ux_[l], uy_[l]);
        const int e = first_exit_sample(march, g.m(static_cast<std::size_t>(l)), u, step_[l], last);  // B.3
        if (e > last && last < samples - 1) continue;  // no exit within reach
        const float lu = e <= last ? exit_distance(e, step_[l]) : L_[l];
        lu_[l] = (traced >> l) & 1u ? std::min(lu_[l], lu) : lu;
        traced |= 1u << l;
        if (e <= last) last = e - 1;
      }
    }
    if (!traced) continue;
    for (std::size_t l = 0; l < W; ++l) {
      traced_[l] = static_cast<float>((traced >> l) & 1u);
      if (!((traced >> l) & 1u)) lu_[l] = 0.f;
    }
    const B f = detail::compression_factor(B::load_aligned(lu_), lambda, w_star, w_sum, p);  // Eq. 13
    const auto on = B::load_aligned(traced_) > zero;
    const auto is0 = !is1 & !is2;
    F[0] = simd::select(on & is0 & (f < F[0]), f, F[0]);
    F[1] = simd::select(on & is1 & (f < F[1]), f, F[1]);
    F[2] = simd::select(on & is2 & (f < F[2]), f, F[2]);
  }
  for (int d = 0; d < 3; ++d) F[d].store_aligned(a.f[d]);
}

// One Gaussian (mean mu, rotation R with columns r_d, scales s) in one view with its mask: B.1
// (the centre between the near and far planes and on the mask's foreground, a covariance that is
// not degenerate, rule (e)), then trace_overflow with every endpoint traced in full. The
// reference that BoundaryRefinement equals; it computes as the refinement does (abr_geometry and
// trace_overflow, here with the Gaussian in every lane). Assumes a camera-sized mask.
inline AbrObservation observe_gaussian(const Camera& cam, const Mask& mask, const Eigen::Vector3f& mu,
                                       const Eigen::Matrix3f& R, const Eigen::Vector3f& s,
                                       const AbrParams& p) {
  constexpr std::size_t L = simd::width;
  alignas(64) float col[15][L];  // x, y, z, R column-major, s: each broadcast
  for (std::size_t l = 0; l < L; ++l) {
    for (int d = 0; d < 3; ++d) col[d][l] = mu[d], col[12 + d][l] = s[d];
    for (int e = 0; e < 9; ++e) col[3 + e][l] = R(e % 3, e / 3);
  }
  const float* const rot[9] = {col[3], col[4], col[5], col[6], col[7], col[8], col[9], col[10], col[11]};
  const float* const sc[3] = {col[12], col[13], col[14]};
  AbrBatch g;
  abr_geometry(AbrCamera::from(cam, p.projection), col[0], col[1], col[2], rot, sc, p.sigma_c, g);
  if (!(g.front[0] > 0.f) || !mask_at(mask, g.mx[0], g.my[0])) return {};  // B.1, rule (e)
  if (!(g.det[0] > 0.f) || !(1.f >= p.projection.alpha_min)) return {};    // degenerate: rule (e)
  AbrObservation obs;
  obs.eligible = true;
  AbrLanes a;
  const std::int32_t outside = outside_endpoints(mask, g, 0);
  if (!outside) return obs;
  for (std::size_t l = 0; l < L; ++l) {
    a.outside[l] = outside;
    for (int d = 0; d < 3; ++d) a.s[d][l] = s[d], a.beat[d][l] = std::numeric_limits<float>::infinity();
  }
  obs.overflow = true;
  trace_overflow(mask, g, 1u, p, a);
  for (int d = 0; d < 3; ++d) obs.f[d] = a.f[d][0];
  return obs;
}

namespace detail {

// Per lane of g, from `tiles` (the view's mask in bits): centre[l] = 1 when the centre lies
// between the planes, inside the image, on foreground, and Sigma2D is not degenerate (B.1,
// rule (e)); bit k of outside[l] set when 3-sigma endpoint k (Eq. 9) lies outside the image or
// on background (B.1). The same answers as mask_at and outside_endpoints on the mask.
inline void lane_tests(const MaskTiles& tiles, const AbrBatch& g, std::int32_t* centre, std::int32_t* outside) {
  using BF = simd::batch<float>;
  using BI = simd::batch<std::int32_t>;
  const BF zero(0.f);
  auto foreground = [&](const float* u, const float* v) { return mask_at(tiles, BF::load_aligned(u), BF::load_aligned(v)); };
  const BI ok = simd::to_int(simd::select((BF::load_aligned(g.front) > zero) & (BF::load_aligned(g.det) > zero),
                                          BF(1.f), zero));
  (foreground(g.mx, g.my) & ok).store_aligned(centre);
  BI bits = BI(1) - foreground(g.ex[0], g.ey[0]);
  for (int k = 1; k < 4; ++k) bits = bits | ((BI(1) - foreground(g.ex[k], g.ey[k])) << k);
  bits.store_aligned(outside);
}

// What one view says about a whole chunk of centres (a Morton run of kBox slots): background
// when no centre can land on foreground (none eligible, B.1); foreground when every centre and
// every 3-sigma endpoint lands on foreground inside the image (all eligible, none overflows:
// Eq. 9's endpoints lie within sigma_c sqrt(lambda_1) of the centre, and by Eq. 10 lambda_1 <=
// ||J||^2 max_d s_d^2 + eps2d); mixed otherwise (observed Gaussian by Gaussian).
// `v`: the chunk's box in this view (detail::project_boxes).
inline MaskTiles::Content chunk_content(const MaskTiles& tiles, const BoxView& v, const AbrCamera& C,
                                        const Camera& cam, const std::array<float, 7>& b, const AbrParams& p) {
  if (v.visibility == BoxView::none_visible) return MaskTiles::background;
  const MaskTiles::Content centres = tiles.classify(v.x0, v.y0, v.x1, v.y1);
  if (centres == MaskTiles::background) return MaskTiles::background;
  if (v.visibility != BoxView::all_visible || !(p.projection.eps2d > 0.f)) return MaskTiles::mixed;
  // Nearest camera depth over the box (affine in the point: at a corner), with margin.
  const float zmin = v.zmin * 0.999f;
  if (!(zmin >= p.projection.near_plane * 1.001f) || !(zmin < p.projection.far_plane * 0.999f)) return MaskTiles::mixed;
  // lambda_1 over the chunk (Eq. 10), from the rectangle of its centres (one pixel wider).
  const float lambda1 = lambda1_bound(C, static_cast<float>(v.x0), static_cast<float>(v.y0), static_cast<float>(v.x1 + 1),
                                      static_cast<float>(v.y1 + 1), zmin, b[6]) * 1.001f;
  const float reach = p.sigma_c * std::sqrt(lambda1) * 1.001f + 1.f;  // px, with margin
  if (!(reach < 1e6f)) return MaskTiles::mixed;
  const int r = static_cast<int>(std::ceil(reach));
  if (v.x0 - r < 0 || v.y0 - r < 0 || v.x1 + r >= cam.width || v.y1 + r >= cam.height) return MaskTiles::mixed;
  return tiles.classify(v.x0 - r, v.y0 - r, v.x1 + r, v.y1 + r) == MaskTiles::foreground ? MaskTiles::foreground
                                                                                          : MaskTiles::mixed;
}

}  // namespace detail

}  // namespace vcar
