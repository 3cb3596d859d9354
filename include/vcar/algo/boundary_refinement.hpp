#pragma once
// Axis-aware Boundary Refinement, ABR (Sec. 3.4, Eq. 9-14; supplementary B.1-B.3).
//
// A streaming accumulator over a candidate set (typically G_fine): every training view with a
// mask from the latest segmentation round is added once (conventions §5); `finish` applies the
// gated, reconciled per-axis compression. Per candidate the state is O(1) in the number of views:
// n_vis, n_ovf (uint16) and the running minimum candidate factor of each of the 3 axes (with the
// view that set it, for the incremental updates that Reselection uses).
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
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/abr_geometry.hpp"
#include "vcar/algo/abr_params.hpp"
#include "vcar/algo/boundary_distance.hpp"
#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/column_block.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/morton_order.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/core/rle_mask.hpp"
#include "vcar/core/rotation.hpp"
#include "vcar/core/scratch_vector.hpp"

namespace vcar {

struct AbrResult {
  LogScales log_scale;           // refined log-scales, aligned with the candidates
  std::size_t flagged = 0;       // candidates with gamma = n_ovf / n_vis > rho
  std::size_t compressed = 0;    // flagged candidates with at least one axis scaled by f < 1
  std::vector<std::uint8_t> axis_compressed;  // bit d set: axis d of candidate k was compressed
  std::size_t retraced = 0;      // refine_deferred: flagged candidates refined once more, alone
};

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

class BoundaryRefinement {
 public:
  // Copies the candidates' means, rotations and log-scales (the scene need not outlive this), in
  // Morton order of the means so that neighbouring work reads neighbouring mask pixels.
  // Throws vcar::Error for a candidate index out of range or a parameter out of range.
  BoundaryRefinement(const GaussianScene& scene, std::vector<Index> candidates, AbrParams params = {})
      : candidates_(std::move(candidates)), params_(params) {
    params_.validate();
    const std::size_t n = candidates_.size();
    for (std::size_t k = 0; k < n; ++k)
      if (candidates_[k] >= scene.size())
        throw Error("candidate " + std::to_string(candidates_[k]) + " out of range (scene has " +
                    std::to_string(scene.size()) + " Gaussians)", "BoundaryRefinement");
    const auto order = [&] {  // the means' copy is given back before the state is allocated
      const auto means = detail::candidate_means(scene, candidates_);
      return morton_order(means[0].data(), means[1].data(), means[2].data(), n);
    }();
    // Geometry columns padded to whole chunk boxes: abr_geometry reads simd::width slots at a time.
    const std::size_t padded = (n + kBox - 1) / kBox * kBox;
    block_ = ColumnBlock(ColumnBlock::room<std::uint32_t>(n) + 15 * ColumnBlock::room<float>(padded) +
                         6 * ColumnBlock::room<float>(n) + 5 * ColumnBlock::room<std::uint16_t>(n));
    slot_ = block_.take<std::uint32_t>(n);
    auto column = [&]<class T>(std::span<T>& c, std::size_t size) {  // slots past n: 0
      c = block_.take<T>(size);
      std::fill(c.begin() + static_cast<std::ptrdiff_t>(n), c.end(), T{});
    };
    for (auto& c : mu_) column(c, padded);  // the fill below writes slots < n
    for (auto& c : rot_) column(c, padded);
    for (auto& c : s_) column(c, padded);
    for (auto& c : log_s_) column(c, n);
    for (auto& c : f_) column(c, n);
    for (auto& c : arg_) column(c, n);
    column(n_vis_, n);
    column(n_ovf_, n);
    for (std::size_t j = 0; j < n; ++j) slot_[order[j]] = static_cast<std::uint32_t>(j);  // slot j: candidate order[j]
    // In two passes. First in candidate order: the scene's columns are read in the candidates'
    // (usually ascending) order rather than gathered in Morton order, which misses the cache on
    // every read, and each candidate's 10 values go to its slot's record (40 bytes; records
    // aligned to a cache line each, 60% more memory, were no faster). Then
    // in slot order, each record's columns are written in sequence: 15 writes per candidate
    // scattered over 15 columns missed the cache on every write.
    struct Record {
      float mu[3], log_s[3], q[4];
    };
    scratch_vector<Record> record(n);  // every slot written below
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t kk) {
      const auto k = static_cast<std::size_t>(kk);
      const std::size_t i = candidates_[k];
      Record& r = record[slot_[k]];
      for (int d = 0; d < 3; ++d) r.mu[d] = scene.mean[d][i], r.log_s[d] = scene.log_scale[d][i];
      for (int e = 0; e < 4; ++e) r.q[e] = scene.rotation[e][i];
    });
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      const Record& r = record[j];
      for (int d = 0; d < 3; ++d) {
        mu_[d][j] = r.mu[d];
        log_s_[d][j] = r.log_s[d];
        s_[d][j] = std::exp(r.log_s[d]);
      }
      const Eigen::Matrix3f R = rotation_from_quaternion(r.q[0], r.q[1], r.q[2], r.q[3]);
      for (int e = 0; e < 9; ++e) rot_[e][j] = R(e % 3, e / 3);
      for (int d = 0; d < 3; ++d) f_[d][j] = std::numeric_limits<float>::infinity(), arg_[d][j] = no_view;  // no view yet
      n_vis_[j] = n_ovf_[j] = 0;
    });
    // Chunk boxes of the centres and the largest max_d s_d^2 per chunk (the bound of add_view).
    const std::size_t chunks = (n + kBox - 1) / kBox;
    box_.resize(chunks);
    parallel_for(static_cast<std::int64_t>(chunks), [&](std::int64_t cc) {
      const auto c = static_cast<std::size_t>(cc);
      const std::size_t j0 = c * kBox, j1 = std::min(n, (c + 1) * kBox);
      const std::array<float, 6> mb = detail::mean_box(mu_[0].data(), mu_[1].data(), mu_[2].data(), j0, j1);
      std::array<float, 7> b{mb[0], mb[1], mb[2], mb[3], mb[4], mb[5], 0.f};
      for (std::size_t j = j0; j < j1; ++j) {
        const float s2 = max_scale_squared(j);
        b[6] = std::isfinite(s2) ? std::max(b[6], s2) : INFINITY;
      }
      box_[c] = b;
    });
  }

  // One training view with its mask (B.3). Throws vcar::Error naming the view for a bad camera,
  // a mask of another size than the view, or more views than the uint16 counters hold. `view`
  // names the view for the incremental updates below (default: the number of views added so far).
  void add_view(const Camera& cam, const Mask& mask) { add_view(cam, mask, static_cast<std::uint16_t>(views_)); }
  void add_view(const Camera& cam, const Mask& mask, std::uint16_t view) { observe_added(cam, mask, view); }
  // The same with the mask run-length encoded (what the pipeline keeps of its views): the
  // mask's tiles are built from the runs, and the mask is decoded only when there are too few
  // candidates for the tiles to pay. The same result as the decoded mask (tested). Also throws
  // for runs that do not cover the image exactly.
  void add_view(const Camera& cam, const RleMask& mask) { add_view(cam, mask, static_cast<std::uint16_t>(views_)); }
  void add_view(const Camera& cam, const RleMask& mask, std::uint16_t view) { observe_added(cam, mask, view); }

  // Beyond the paper (the same result as add_view called for each view in turn): the views that
  // for_each_view(add) hands out, add(camera, mask) with a Mask or an RleMask, numbered on from
  // views(). They are observed kViewGroup at a time with the candidates outside and the views
  // inside, so that a run of candidates' state stays in cache across the views (add_view walks
  // every candidate once per view). Throws as add_view does; the views before a bad one stay
  // added.
  template <class ForEachView>
  void add_views(ForEachView&& for_each_view) {
    try {
      for_each_view([&](const Camera& cam, const auto& mask) {
        enqueue(cam, mask, static_cast<std::uint16_t>(views_));
        if (pending_count_ == kViewGroup) observe_pending();
      });
    } catch (...) {
      observe_pending();
      release_pending();
      throw;
    }
    observe_pending();
    release_pending();
  }
  static constexpr std::size_t kViewGroup = 16;  // views observed together by add_views

 private:
  // What observe_boxes reads of one view: the camera, its projection of means and chunk boxes,
  // and what abr_geometry reads of it.
  struct ViewContext {
    const Camera* cam;
    detail::ViewLanes lanes;
    AbrCamera C;
    static ViewContext of(const Camera& cam, const AbrParams& p) {
      return {&cam, detail::ViewLanes::of(detail::MeanProjection::from(cam)), AbrCamera::from(cam, p.projection)};
    }
  };

  struct PendingView {                       // a view added, not yet observed (enqueue)
    Camera cam;
    std::uint16_t id = 0;
    MaskTiles packed;                        // the mask in tiles, when they pay
    const Mask* pixels = nullptr;            // else its pixels (then `packed` is unused)
    std::vector<std::uint32_t> gate;         // expect_views: least n_ovf that can open the gate, by n_vis
  };

  template <class AnyMask>
  void observe_added(const Camera& cam, const AnyMask& mask, std::uint16_t view) {
    enqueue(cam, mask, view);
    observe_pending();
  }
  // A view to observe: counted now (views_), observed by observe_pending with the others queued.
  // Its mask is packed into tiles (or, when the tiles do not pay, read from its pixels, which stay
  // valid only until the next view: then it is observed at once).
  template <class AnyMask>
  void enqueue(const Camera& cam, const AnyMask& mask, std::uint16_t view) {
    check_view(cam, mask, view);
    if (expected_ && views_ >= expected_)
      throw Error("more views than expect_views announced (" + std::to_string(expected_) + ")", "view '" + cam.name + "'");
    enter_view(cam);
    if (pending_count_ == pending_.size()) pending_.emplace_back();
    PendingView& v = pending_[pending_count_++];
    v.cam = cam;
    v.id = view;
    const bool tiles = tiles_pay(size(), static_cast<std::size_t>(mask.width) * static_cast<std::size_t>(mask.height));
    v.pixels = nullptr;
    if (tiles) v.packed.build(mask);
    else v.pixels = &decoded(mask);
    // With expect_views: this view and those after it; a candidate whose gate cannot open even
    // if it overflows in all of them is not observed any more.
    if (expected_) fill_gate_table(expected_ - views_ + 1, v.gate);
    if (v.pixels) observe_pending();
  }
  // The queue's memory beyond one view (add_view's), given back after add_views.
  void release_pending() {
    if (pending_.size() <= 1) return;
    pending_.resize(1);
    pending_.shrink_to_fit();
  }
  // Observes the queued views, in order for each candidate (the chunk boxes outside, the views
  // inside).
  void observe_pending() {
    if (pending_count_ == 0) return;
    std::vector<ViewContext> context;
    for (std::size_t q = 0; q < pending_count_; ++q) context.push_back(ViewContext::of(pending_[q].cam, params_));
    // With expect_views a slot not wanted stays so (unobserved, its counts stay, and the least
    // n_ovf that opens its gate only grows as views pass): a chunk box without a wanted slot
    // is marked idle and left out of the views after this one (on bench_reselect's scene 39%
    // of the chunk-views, each a scan of 64 slots).
    const std::vector<std::uint32_t>* boxes = expected_ ? &live_boxes_ : nullptr;
    std::uint8_t* idle = expected_ ? idle_.data() : nullptr;
    const std::int64_t n_boxes = static_cast<std::int64_t>(boxes ? boxes->size() : box_.size());
    parallel_chunks(n_boxes, kChunk / kBox, [&](std::int64_t, std::int64_t b, std::int64_t e) {
      for (std::size_t q = 0; q < pending_count_; ++q) observe_added_boxes(pending_[q], context[q], b, e, boxes, idle);
    });
    pending_count_ = 0;
    if (expected_) std::erase_if(live_boxes_, [&](std::uint32_t c) { return idle_[c] != 0; });
  }
  // One queued view on the chunk boxes [b, e): every wanted slot's observation enters its counts
  // and minima (add_view's rules: expect_views' gate, defer_tracing).
  void observe_added_boxes(const PendingView& v, const ViewContext& vc, std::int64_t b, std::int64_t e,
                           const std::vector<std::uint32_t>* boxes, std::uint8_t* idle) {
    const std::uint32_t* gate = v.gate.data();
    const std::uint16_t view = v.id;
    const MaskTiles* tiles = v.pixels ? nullptr : &v.packed;
    GateWant want{*this, gate};
    if (!defer_) {
      auto add_one = [&](std::size_t k, const AbrObservation& obs) { add(k, obs, view); };
      CountInside<decltype(add_one)> apply{*this, add_one};
      Always trace;
      observe_boxes(vc, b, e, boxes, tiles, v.pixels, want, apply, trace, idle);
    } else {
      // defer_tracing: an overflowing endpoint is traced only while the slot's overflow ratio,
      // this view counted as overflowing, is above rho; the slots left untraced are marked.
      const float rho = params_.rho;
      auto trace = [&](std::size_t k) { return static_cast<float>(n_ovf_[k] + 1) > rho * static_cast<float>(n_vis_[k] + 1); };
      auto add_one = [&](std::size_t k, const AbrObservation& obs) {
        if (obs.overflow && !trace(k)) untraced_[k] = 1;  // before add(): the counts observe_boxes read
        add(k, obs, view);
      };
      CountInside<decltype(add_one)> apply{*this, add_one};
      observe_boxes(vc, b, e, boxes, tiles, v.pixels, want, apply, trace, idle);
    }
  }
  // observe_added_boxes' want: expect_views' gate can still open (every slot without it), slot
  // by slot or a whole batch at once (lanes: the gate table gathered at the batch's n_vis).
  struct GateWant {
    const BoundaryRefinement& r;
    const std::uint32_t* gate;
    bool operator()(std::size_t k) const { return !r.expected_ || r.n_ovf_[k] >= gate[r.n_vis_[k]]; }
    unsigned lanes(std::size_t j) const {  // bit l: operator()(j + l), l < simd::width
      constexpr std::size_t L = simd::width;
      if (!r.expected_) return static_cast<unsigned>((std::uint64_t{1} << L) - 1);
      using BI = simd::batch<std::int32_t>;
      alignas(64) std::int32_t vis[L], ovf[L];
      for (std::size_t l = 0; l < L; ++l) vis[l] = r.n_vis_[j + l], ovf[l] = r.n_ovf_[j + l];
      const BI opening = simd::gather(reinterpret_cast<const std::int32_t*>(gate), BI::load_aligned(vis));
      return simd::nonzero_lanes(simd::select(BI::load_aligned(ovf) >= opening, BI(1), BI(0)));
    }
  };
  // observe_added_boxes' apply: `one` per observation, and for a batch's lanes that are eligible
  // without overflow (add() counts n_vis only) one add over the batch.
  template <class One>
  struct CountInside {
    BoundaryRefinement& r;
    One& one;
    void operator()(std::size_t k, const AbrObservation& obs) const { one(k, obs); }
    void inside(std::size_t j, unsigned bits) const {  // bit l: slot j + l, l < simd::width
      std::uint16_t* v = r.n_vis_.data() + j;
      for (std::size_t l = 0; l < simd::width; ++l) v[l] = static_cast<std::uint16_t>(v[l] + ((bits >> l) & 1u));
    }
  };
  const Mask& decoded(const Mask& mask) { return mask; }
  const Mask& decoded(const RleMask& mask) { return decoder_.decode(mask); }

 public:
  // Beyond the paper (same result, less work): with defer_tracing, add_view traces a candidate's
  // overflowing endpoints (B.3, the march and Eq. 11-13) only while its overflow ratio, the view
  // counted as overflowing, is above rho, i.e. while it looks bound to be flagged; the counts
  // (n_vis, n_ovf) and so the gate stay exact. Most candidates of an object overflow in a few
  // views only and are never traced. flagged_untraced() then lists the flagged candidates
  // whose minima miss a view: a refinement of those alone over the same views gives their exact
  // factors (refine_deferred below does it), and the rest of finish() is exact.
  // Call before the first view.
  void defer_tracing() {
    if (views_ != 0) throw Error("defer_tracing is called before the first view", "BoundaryRefinement");
    if (!mode_.empty()) throw Error("defer_tracing does not combine with carry", "BoundaryRefinement");
    defer_ = true;
    untraced_.assign(size(), 0);
  }
  // Positions k (into candidates()) flagged by the gate (B.3) whose minima miss an overflowing
  // view (defer_tracing), ascending.
  std::vector<std::size_t> flagged_untraced() const {
    std::vector<std::size_t> out;
    if (!defer_) return out;
    for (std::size_t k = 0; k < size(); ++k) {
      const std::size_t j = slot_[k];
      if (untraced_[j] && n_vis_[j] > 0 &&
          static_cast<float>(n_ovf_[j]) / static_cast<float>(n_vis_[j]) > params_.rho)  // finish()'s gate
        out.push_back(k);
    }
    return out;
  }

  // Beyond the paper (same result, shorter marches): an upper bound on candidate k's running
  // minimum per axis (B.3, clamped below at f_min), e.g. min_factor() of an earlier refinement
  // of the same candidate over some of the same views with the same parameters. Observing every
  // view then ends at the same minimum (a minimum over views, and the bound is one of its
  // terms), while an endpoint whose factor cannot beat the bound is never traced
  // (trace_overflow's beat). refine_deferred bounds its second pass with the first pass's
  // minima. Call before the first view; not with carry (whose minima remember their views).
  void bound_minimum(std::size_t k, const std::array<float, 3>& bound) {
    if (views_ != 0) throw Error("bound_minimum is called before the first view", "BoundaryRefinement");
    if (!mode_.empty()) throw Error("bound_minimum does not combine with carry", "BoundaryRefinement");
    if (k >= size()) throw Error("bound_minimum: candidate position out of range", "BoundaryRefinement");
    const std::size_t j = slot_[k];
    for (int d = 0; d < 3; ++d) f_[d][j] = std::max(params_.f_min, std::min(f_[d][j], bound[d]));
  }

  // Announces that exactly `total` views will be added (add_view), which lets the refinement
  // skip a candidate once its gate (B.3: gamma = n_ovf / n_vis > rho) can no longer open: with
  // R views to come, gamma ends at most (n_ovf + R) / (n_vis + R). finish() is unchanged (a
  // skipped candidate is never flagged either way); n_vis, n_ovf and min_factor of a skipped
  // candidate stay where they were, and such a refinement cannot be carried (carry throws).
  // Call before the first view; 0 turns it off.
  void expect_views(std::size_t total) {
    if (views_ != 0) throw Error("expect_views is called before the first view", "BoundaryRefinement");
    if (!mode_.empty()) throw Error("expect_views does not combine with carry", "BoundaryRefinement");
    expected_ = total;
    live_boxes_.resize(box_.size());
    std::iota(live_boxes_.begin(), live_boxes_.end(), std::uint32_t{0});
    idle_.assign(box_.size(), 0);
  }
  // Chunk boxes (runs of 64 candidates) the next view observes: all of them, or with
  // expect_views those that still hold a candidate whose gate can open.
  std::size_t boxes_observed() const noexcept { return expected_ ? live_boxes_.size() : box_.size(); }

  // ---- Incremental refinement (beyond the paper; used by Reselection). Eq. 9-13 observe one
  // Gaussian in one view at a time: a candidate's state is a sum (n_vis, n_ovf) and a minimum
  // (f_d) over views. So a refinement whose candidates mostly match an earlier one's, under
  // masks of which few changed, can start from the earlier state:
  //  1. carry(previous): candidates that `previous` also held take its counts and minima
  //     ("carried"); the others start with no view ("fresh").
  //  2. change_view(cam, old_mask, new_mask, view) for each view whose mask changed since
  //     `previous` saw them (null: no mask): the carried candidates' observation with old_mask is
  //     taken back (counts exact in integers) and new_mask's added; a carried minimum that this
  //     view set is marked for recomputation (a minimum cannot be taken back).
  //  3. complete_view(cam, mask, view) for every view that has a mask now, when incomplete():
  //     fresh candidates get the whole observation, marked ones their minima.
  // finish() then equals a refinement that saw every current mask (tested bit for bit).
  void carry(const BoundaryRefinement& previous) {
    if (!mode_.empty()) throw Error("carry is called once, before any view", "BoundaryRefinement");
    if (previous.expected_ || expected_)
      throw Error("a refinement that skips candidates (expect_views) cannot be carried", "BoundaryRefinement");
    if (previous.defer_ || defer_)
      throw Error("a refinement that defers tracing cannot be carried", "BoundaryRefinement");
    if (views_ != 0) throw Error("carry needs a refinement that has seen no view yet", "BoundaryRefinement");
    const std::size_t n = size();
    mode_.assign(n, fresh);
    std::vector<std::pair<Index, std::uint32_t>> prev(previous.size()), next(n);
    for (std::size_t k = 0; k < previous.size(); ++k) prev[k] = {previous.candidates_[k], previous.slot_[k]};
    for (std::size_t k = 0; k < n; ++k) next[k] = {candidates_[k], slot_[k]};
    if (!std::is_sorted(prev.begin(), prev.end())) std::sort(prev.begin(), prev.end());
    if (!std::is_sorted(next.begin(), next.end())) std::sort(next.begin(), next.end());
    for (std::size_t a = 0, b = 0; a < prev.size() && b < n;) {
      if (prev[a].first < next[b].first) { ++a; continue; }
      if (next[b].first < prev[a].first) { ++b; continue; }
      const std::size_t i = prev[a++].second, j = next[b++].second;
      mode_[j] = carried;
      n_vis_[j] = previous.n_vis_[i];
      n_ovf_[j] = previous.n_ovf_[i];
      for (int d = 0; d < 3; ++d) f_[d][j] = previous.f_[d][i], arg_[d][j] = previous.arg_[d][i];
    }
    views_ = previous.views_;
    count_modes();
  }
  void change_view(const Camera& cam, const Mask* old_mask, const Mask* new_mask, std::uint16_t view) {
    if (mode_.empty()) throw Error("change_view needs carry first", "BoundaryRefinement");
    if (completing_) throw Error("change_view after complete_view", "BoundaryRefinement");
    auto is_carried = [&](std::size_t k) { return mode_[k] != fresh; };
    if (old_mask) {
      check_view(cam, *old_mask, view);
      if (views_ == 0) throw Error("change_view takes back a view that was never added", "view '" + cam.name + "'");
      --views_;
      tiles_.build(*old_mask);
      observe_view(cam, old_mask, true, is_carried, [&](std::size_t k, const AbrObservation& obs) {
        --n_vis_[k];
        if (obs.overflow) --n_ovf_[k];
        for (int d = 0; d < 3; ++d)
          if (arg_[d][k] == view) mode_[k] = stale;  // this view set a minimum
      }, nullptr, Never{});
    }
    if (new_mask) {
      check_view(cam, *new_mask, view);
      enter_view(cam);
      tiles_.build(*new_mask);
      observe_view(cam, new_mask, true, is_carried, [&](std::size_t k, const AbrObservation& obs) {
        add(k, obs, view);
      });
    }
    count_modes();
  }
  // True while some candidate still needs complete_view (fresh ones, or marked minima).
  bool incomplete() const noexcept { return wanted_ > 0; }
  void complete_view(const Camera& cam, const Mask& mask, std::uint16_t view) {
    if (mode_.empty()) throw Error("complete_view needs carry first", "BoundaryRefinement");
    check_view(cam, mask, view);
    if (!completing_) {  // marked minima start again from no view
      for (std::size_t k = 0; k < size(); ++k) {
        if (mode_[k] == stale)
          for (int d = 0; d < 3; ++d) f_[d][k] = std::numeric_limits<float>::infinity(), arg_[d][k] = no_view;
        if (mode_[k] != carried && (wanted_boxes_.empty() || wanted_boxes_.back() != k / kBox))
          wanted_boxes_.push_back(static_cast<std::uint32_t>(k / kBox));
      }
      completing_ = true;
    }
    if (wanted_ == 0) return;
    const bool tiles = tiles_pay(wanted_, mask.pixels());
    if (tiles) tiles_.build(mask);
    observe_view(cam, &mask, tiles, [&](std::size_t k) { return mode_[k] != carried; },
                 [&](std::size_t k, const AbrObservation& obs) {
                   if (mode_[k] == fresh) return add(k, obs, view);
                   if (obs.overflow) min_into(k, obs, view);  // stale: its counts are already right
                 }, &wanted_boxes_);
  }
  // Candidates carried / fresh / with minima to recompute (after carry and change_view).
  std::array<std::size_t, 3> carried_fresh_stale() const {
    std::array<std::size_t, 3> c{};
    for (std::uint8_t m : mode_) ++c[m];
    if (mode_.empty()) c[0] = size();
    return c;
  }

  // Gate gamma > rho (strict), clamp the per-axis minimum to [f_min, 1], log s_d += log f (Eq. 14).
  AbrResult finish() const {
    const std::size_t n = size();
    AbrResult r;
    r.log_scale = {std::vector<float>(n), std::vector<float>(n), std::vector<float>(n)};
    r.axis_compressed.assign(n, 0);
    std::vector<std::uint8_t> flagged(n, 0);  // per candidate: the counts below are sums of these
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t kk) {
      const auto k = static_cast<std::size_t>(kk);
      const std::size_t j = slot_[k];
      for (int d = 0; d < 3; ++d) r.log_scale[d][k] = log_s_[d][j];
      if (n_vis_[j] == 0) return;
      const float gamma = static_cast<float>(n_ovf_[j]) / static_cast<float>(n_vis_[j]);  // B.3
      if (!(gamma > params_.rho)) return;
      flagged[k] = 1;
      for (int d = 0; d < 3; ++d) {
        const float f = std::min(1.f, std::max(params_.f_min, f_[d][j]));  // B.3 reconciliation
        if (!(f < 1.f)) continue;
        r.log_scale[d][k] += std::log(f);  // Eq. 14
        r.axis_compressed[k] |= static_cast<std::uint8_t>(1u << d);
      }
    });
    r.flagged = static_cast<std::size_t>(std::count(flagged.begin(), flagged.end(), std::uint8_t{1}));
    r.compressed = static_cast<std::size_t>(
        std::count_if(r.axis_compressed.begin(), r.axis_compressed.end(), [](std::uint8_t c) { return c != 0; }));
    return r;
  }

  // Whether a slot with counts (n_ovf, n_vis) can still end with gamma > rho (B.3) when
  // `remaining` views are to come (this one included): (n_ovf + R) / (n_vis + R) against rho,
  // with a margin so that the float gate of finish() never decides otherwise.
  static bool gate_can_open(std::size_t n_ovf, std::size_t n_vis, std::size_t remaining, float rho) {
    const double o = static_cast<double>(n_ovf) + static_cast<double>(remaining);
    const double v = static_cast<double>(n_vis) + static_cast<double>(remaining);
    return o >= (static_cast<double>(rho) - 1e-6) * v;  // o / v >= rho - 1e-6, or v = 0 (then o = 0)
  }
  // The least n_ovf with which a slot of n_vis = v passes gate_can_open (the test grows with
  // n_ovf, and passes at n_ovf = v since rho < 1).
  static std::size_t least_opening_overflow(std::size_t v, std::size_t remaining, float rho) {
    // Start near the solution of o + R = (rho - 1e-6)(v + R), then step to the least passing count.
    const double guess = std::ceil((static_cast<double>(rho) - 1e-6) * static_cast<double>(v + remaining)) -
                         static_cast<double>(remaining);
    std::size_t o = guess <= 0.0 ? 0 : std::min(v, static_cast<std::size_t>(guess));
    while (o > 0 && gate_can_open(o - 1, v, remaining, rho)) --o;
    while (o < v && !gate_can_open(o, v, remaining, rho)) ++o;
    return o;
  }

  std::size_t size() const noexcept { return candidates_.size(); }
  const std::vector<Index>& candidates() const noexcept { return candidates_; }
  const AbrParams& params() const noexcept { return params_; }
  std::size_t views() const noexcept { return views_; }
  // Diagnostics of candidate k: eligible views, overflowing views, running minimum over views of
  // max(f_min, f) for axis d (+inf: no overflowing view named d*; finish() clamps it to 1).
  std::uint16_t n_vis(std::size_t k) const { return n_vis_[slot_[k]]; }
  std::uint16_t n_ovf(std::size_t k) const { return n_ovf_[slot_[k]]; }
  float min_factor(std::size_t k, int d) const { return f_[d][slot_[k]]; }

  // Bytes of state held per candidate (index, geometry copy, counters, running minima, and with
  // defer_tracing its untraced mark).
  static constexpr std::size_t bytes_per_candidate() {
    return 2 * sizeof(std::uint32_t) + (3 + 9 + 3 + 3) * sizeof(float) + 2 * sizeof(std::uint16_t) + 3 * sizeof(float) +
           3 * sizeof(std::uint16_t) + sizeof(std::uint8_t);
  }

 private:
  static constexpr std::uint16_t no_view = std::numeric_limits<std::uint16_t>::max();
  // Whether building the mask tiles for `observed` candidates pays: under one candidate per 256
  // pixels they are observed one by one on the mask itself (the same result either way).
  static bool tiles_pay(std::size_t observed, std::size_t pixels) { return observed * 256 >= pixels; }
  struct Always {  // trace every slot (a type, not a function pointer: inlined per lane)
    bool operator()(std::size_t) const { return true; }
  };
  struct Never {
    bool operator()(std::size_t) const { return false; }
  };
  enum : std::uint8_t { carried = 0, fresh = 1, stale = 2 };

  void check_view(const Camera& cam, const Mask& mask, std::uint16_t view) const {
    const std::string where = "view '" + cam.name + "'";
    cam.validate();
    if (mask.width != cam.width || mask.height != cam.height || mask.channels != 1 ||
        mask.data.size() != mask.pixels())
      throw Error("mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) + "x" +
                  std::to_string(mask.channels) + ", the view is " + std::to_string(cam.width) + "x" +
                  std::to_string(cam.height) + "x1", where);
    if (view == no_view) throw Error("view ids go up to 65534", where);
  }
  void check_view(const Camera& cam, const RleMask& mask, std::uint16_t view) const {
    const std::string where = "view '" + cam.name + "'";
    cam.validate();
    if (mask.width != cam.width || mask.height != cam.height)
      throw Error("mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) + ", the view is " +
                  std::to_string(cam.width) + "x" + std::to_string(cam.height), where);
    std::size_t covered = 0;
    for (std::uint32_t run : mask.runs) covered += run;
    if (covered != static_cast<std::size_t>(mask.width) * static_cast<std::size_t>(mask.height))
      throw Error("run-length mask covers " + std::to_string(covered) + " pixels, not its " + std::to_string(mask.width) +
                  "x" + std::to_string(mask.height), where);
    if (view == no_view) throw Error("view ids go up to 65534", where);
  }

  // Counts one more view (the uint16 counters hold at most 65535).
  void enter_view(const Camera& cam) {
    if (views_ == std::numeric_limits<std::uint16_t>::max())
      throw Error("more than 65535 views for ABR", "view '" + cam.name + "'");
    ++views_;
  }

  // gate_can_open as a table for a view (expect_views): gate[v] is least_opening_overflow(v), so
  // that the per-slot test is one integer comparison. n_vis < views_ here.
  void fill_gate_table(std::size_t remaining, std::vector<std::uint32_t>& gate) const {
    gate.resize(views_ + 1);
    for (std::size_t v = 0; v <= views_; ++v)
      gate[v] = static_cast<std::uint32_t>(least_opening_overflow(v, remaining, params_.rho));
  }

  // Slot k's observation in view `view` enters its counts and minima (B.3).
  void add(std::size_t k, const AbrObservation& obs, std::uint16_t view) {
    ++n_vis_[k];
    if (!obs.overflow) return;
    ++n_ovf_[k];
    min_into(k, obs, view);
  }
  // Multi-view minimum per axis (B.3) of the factors clamped below at f_min, remembering the view
  // that set it. finish() clamps the minimum to [f_min, 1]: max(f_min, min_v f_v) = min_v
  // max(f_min, f_v), so clamping each view's factor first changes nothing there, and it lets
  // trace_overflow skip every endpoint that cannot lower the minimum (its beat).
  void min_into(std::size_t k, const AbrObservation& obs, std::uint16_t view) {
    for (int d = 0; d < 3; ++d) {
      const float f = std::max(params_.f_min, obs.f[d]);
      if (f < f_[d][k]) f_[d][k] = f, arg_[d][k] = view;
    }
  }
  void count_modes() {
    wanted_ = 0;
    for (std::uint8_t m : mode_) wanted_ += m != carried;
  }

  // One view: apply(k, obs) for every slot k with want(k) whose centre is eligible (B.1), obs as
  // observe_gaussian gives it (abr_geometry and trace_overflow simd::width slots at a time).
  // With `tiles` (tiles_ built from this mask) whole chunks that the mask's tiles decide skip
  // the covariance (same counts and minima); `mask`, the mask's pixels, is read only without
  // tiles (with tiles it may be null).
  // `boxes` (optional) lists the chunk boxes that hold a wanted slot; the others are skipped.
  // `trace(k)` false: apply needs slot k's counts only (no endpoint is traced, obs.f stays +inf).
  // `idle` (optional, one byte per chunk box): set to 1 for each box visited without a wanted slot.
  template <class Want, class Apply, class Trace = Always>
  void observe_view(const Camera& cam, const Mask* mask, bool tiles, Want want, Apply apply,
                    const std::vector<std::uint32_t>* boxes = nullptr, Trace trace = {},
                    std::uint8_t* idle = nullptr) {
    const ViewContext vc = ViewContext::of(cam, params_);
    const std::int64_t n_boxes = static_cast<std::int64_t>(boxes ? boxes->size() : box_.size());
    parallel_chunks(n_boxes, kChunk / kBox, [&](std::int64_t, std::int64_t b, std::int64_t e) {
      observe_boxes(vc, b, e, boxes, tiles ? &tiles_ : nullptr, mask, want, apply, trace, idle);
    });
  }

  // observe_view's work on the chunk boxes [b, e) (positions into `boxes`, or box ids), with
  // the view's tiles (or null: its pixels `mask`). A box already marked in `idle` is skipped.
  template <class Want, class Apply, class Trace>
  void observe_boxes(const ViewContext& vc, std::int64_t b, std::int64_t e, const std::vector<std::uint32_t>* boxes,
                     const MaskTiles* tiles, const Mask* mask, Want& want, Apply& apply, Trace& trace,
                     std::uint8_t* idle) const {
    const AbrParams& p = params_;
    if (!(1.f >= p.projection.alpha_min)) return;  // rule (e): no Gaussian is eligible
    AbrObservation inside;  // eligible, no endpoint outside, no factor
    inside.eligible = true;
    const AbrCamera& C = vc.C;
    constexpr std::size_t L = simd::width;
    std::array<float, 7> group[L];  // the boxes of the next L chunks, projected together
    detail::BoxViewLanes projected;
    auto chunk_at = [&](std::int64_t at) {
      return boxes ? (*boxes)[static_cast<std::size_t>(at)] : static_cast<std::size_t>(at);
    };
    for (std::int64_t i = b; i < e; ++i) {
      const std::size_t c = chunk_at(i);
      if (tiles && (i - b) % static_cast<std::int64_t>(L) == 0) {
        const std::size_t count = static_cast<std::size_t>(std::min<std::int64_t>(static_cast<std::int64_t>(L), e - i));
        for (std::size_t l = 0; l < count; ++l) group[l] = box_[chunk_at(i + static_cast<std::int64_t>(l))];
        detail::project_boxes(vc.lanes, detail::BoxLanes::of(group, count), projected);
      }
      if (idle && idle[c]) continue;  // no wanted slot since an earlier view
      const std::size_t j0 = c * kBox, j1 = std::min(size(), j0 + kBox);
      bool any = false;
      for (std::size_t j = j0; j < j1 && !any; j += simd::width) any = wanted_lanes(want, j, std::min(simd::width, j1 - j)) != 0;
      if (!any) {
        if (idle) idle[c] = 1;  // this task's box only
        continue;
      }
      switch (tiles ? chunk_content(*tiles, projected[static_cast<std::size_t>(i - b) % L], C, *vc.cam, box_[c], p)
                    : MaskTiles::mixed) {
        case MaskTiles::background: continue;  // no centre on foreground: none eligible (B.1)
        case MaskTiles::foreground:            // every centre and endpoint on foreground
          for (std::size_t j = j0; j < j1; j += simd::width) {
            const std::size_t lanes = std::min(simd::width, j1 - j);
            apply_inside(apply, j, lanes, wanted_lanes(want, j, lanes), inside);
          }
          continue;
        case MaskTiles::mixed: break;
      }
      // observe_gaussian, simd::width slots at a time (kBox is a whole number of batches).
      AbrBatch g;
      AbrLanes a{};  // lanes not traced keep finite values from earlier batches (masked out)
      alignas(64) std::int32_t centre[simd::width];
      for (std::size_t j = j0; j < j1; j += simd::width) {
        const std::size_t lanes = std::min(simd::width, j1 - j);
        // Bit l: slot j + l is wanted; every lane tested without a branch (most are wanted).
        const unsigned wanted = wanted_lanes(want, j, lanes);
        if (!wanted) continue;
        geometry(C, j, g);
        // B.1 and rule (e) per lane: with the tiles every lane's centre and endpoint lookups at
        // once from the packed bits, else lane by lane on the mask (the same answers).
        if (tiles) {
          lane_tests(*tiles, g, centre, a.outside);
        } else {
          for (std::size_t l = 0; l < lanes; ++l) {
            centre[l] = g.front[l] > 0.f && g.det[l] > 0.f && mask_at(*mask, g.mx[l], g.my[l]);
            a.outside[l] = centre[l] ? outside_endpoints(*mask, g, l) : 0;
          }
        }
        // Bit l: eligible (B.1, rule (e)), and of those, some endpoint outside. A lane eligible
        // with every endpoint on foreground is "eligible, no overflow" without tracing; the
        // overflowing ones are traced together.
        using BI = simd::batch<std::int32_t>;
        const unsigned eligible = wanted & simd::nonzero_lanes(BI::load_aligned(centre));
        const unsigned overflowing = eligible & simd::nonzero_lanes(BI::load_aligned(a.outside));
        apply_inside(apply, j, lanes, eligible & ~overflowing, inside);
        unsigned traced = 0;
        for (unsigned m = overflowing; m; m &= m - 1) {
          const auto l = static_cast<std::size_t>(std::countr_zero(m));
          const std::size_t k = j + l;
          if (!trace(k)) continue;
          traced |= 1u << l;
          for (int d = 0; d < 3; ++d) a.s[d][l] = s_[d][k], a.beat[d][l] = f_[d][k];
        }
        if (traced) {
          if (tiles) trace_overflow(*tiles, g, traced, p, a);
          else trace_overflow(*mask, g, traced, p, a);
        }
        for (unsigned m = overflowing; m; m &= m - 1) {
          const auto l = static_cast<std::size_t>(std::countr_zero(m));
          AbrObservation obs;
          obs.eligible = obs.overflow = true;
          if ((traced >> l) & 1u)
            for (int d = 0; d < 3; ++d) obs.f[d] = a.f[d][l];
          apply(j + l, obs);
        }
      }
    }
  }

  // Bit l: want(j + l), for the `lanes` slots from j; want.lanes(j) for a whole batch when Want
  // has it.
  template <class Want>
  static unsigned wanted_lanes(Want& want, std::size_t j, std::size_t lanes) {
    if constexpr (requires { want.lanes(j); })
      if (lanes == simd::width) return want.lanes(j);
    unsigned bits = 0;
    for (std::size_t l = 0; l < lanes; ++l) bits |= static_cast<unsigned>(want(j + l)) << l;
    return bits;
  }
  // apply(j + l, inside) for each bit l of `bits` (l < lanes); apply.inside(j, bits) for a whole
  // batch when Apply has it.
  template <class Apply>
  static void apply_inside(Apply& apply, std::size_t j, std::size_t lanes, unsigned bits, const AbrObservation& inside) {
    if constexpr (requires { apply.inside(j, bits); })
      if (lanes == simd::width) return apply.inside(j, bits);
    for (unsigned m = bits; m; m &= m - 1) apply(j + static_cast<std::size_t>(std::countr_zero(m)), inside);
  }

  // Per lane of g, from `tiles` (the view's mask in bits): centre[l] = 1 when the centre lies
  // between the planes, inside the image, on foreground, and Sigma2D is not degenerate (B.1,
  // rule (e)); bit k of outside[l] set when 3-sigma endpoint k (Eq. 9) lies outside the image or
  // on background (B.1). The same answers as mask_at and outside_endpoints on the mask.
  static void lane_tests(const MaskTiles& tiles, const AbrBatch& g, std::int32_t* centre, std::int32_t* outside) {
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

  // abr_geometry of slots [j, j + simd::width) in the view C.
  void geometry(const AbrCamera& C, std::size_t j, AbrBatch& g) const {
    const float* const rot[9] = {rot_[0].data() + j, rot_[1].data() + j, rot_[2].data() + j,
                                 rot_[3].data() + j, rot_[4].data() + j, rot_[5].data() + j,
                                 rot_[6].data() + j, rot_[7].data() + j, rot_[8].data() + j};
    const float* const s[3] = {s_[0].data() + j, s_[1].data() + j, s_[2].data() + j};
    abr_geometry(C, mu_[0].data() + j, mu_[1].data() + j, mu_[2].data() + j, rot, s, params_.sigma_c, g);
  }

  // max_d s_d^2 of slot j: the largest eigenvalue of its 3D covariance R S^2 R^T; +inf when a
  // scale is not finite (no fast path).
  float max_scale_squared(std::size_t j) const {
    float m = 0.f;
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(s_[d][j])) return INFINITY;
      m = std::max(m, s_[d][j]);
    }
    return m * m;
  }

  // What one view says about a whole chunk of centres (a Morton run of kBox slots): background
  // when no centre can land on foreground (none eligible, B.1); foreground when every centre and
  // every 3-sigma endpoint lands on foreground inside the image (all eligible, none overflows:
  // Eq. 9's endpoints lie within sigma_c sqrt(lambda_1) of the centre, and by Eq. 10 lambda_1 <=
  // ||J||^2 max_d s_d^2 + eps2d); mixed otherwise (observed Gaussian by Gaussian).
  // `v`: the chunk's box in this view (detail::project_boxes).
  static MaskTiles::Content chunk_content(const MaskTiles& tiles, const detail::BoxView& v, const AbrCamera& C,
                                          const Camera& cam, const std::array<float, 7>& b, const AbrParams& p) {
    if (v.visibility == detail::BoxView::none_visible) return MaskTiles::background;
    const MaskTiles::Content centres = tiles.classify(v.x0, v.y0, v.x1, v.y1);
    if (centres == MaskTiles::background) return MaskTiles::background;
    if (v.visibility != detail::BoxView::all_visible || !(p.projection.eps2d > 0.f)) return MaskTiles::mixed;
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

  static constexpr std::size_t kBox = 64;  // slots per chunk box (a whole number of SIMD batches)
  static_assert(kBox % simd::width == 0);
  static constexpr std::int64_t kChunk = 2048;
  std::vector<Index> candidates_;
  AbrParams params_;
  ColumnBlock block_;                        // the per-slot columns below, one allocation
  std::span<std::uint32_t> slot_;            // internal slot of candidate position k
  std::array<std::span<float>, 3> mu_;       // candidate means
  std::array<std::span<float>, 9> rot_;      // candidate rotation matrices, column-major
  std::array<std::span<float>, 3> s_;        // candidate scales exp(log s)
  std::vector<std::array<float, 7>> box_;    // per kBox slots: centre box lo, hi, max max_d s_d^2
  MaskTiles tiles_;                          // the current view's mask in tiles (change_view, complete_view)
  std::vector<PendingView> pending_;         // up to kViewGroup views (one kept after add_views)
  std::size_t pending_count_ = 0;
  MaskDecoder decoder_;                      // a run-length encoded view's pixels, when no tiles
  std::array<std::span<float>, 3> log_s_;    // candidate log-scales before refinement (by slot)
  std::array<std::span<float>, 3> f_;        // running minimum candidate factor per axis
  std::span<std::uint16_t> n_vis_, n_ovf_;   // B.3 counts
  std::array<std::span<std::uint16_t>, 3> arg_;  // the view that set f_ (incremental updates)
  std::vector<std::uint8_t> mode_;           // carried / fresh / stale, after carry
  std::size_t wanted_ = 0;                   // slots not carried clean
  bool completing_ = false;                  // complete_view has started
  std::vector<std::uint32_t> wanted_boxes_;  // chunk boxes with fresh or stale slots (completion)
  std::size_t views_ = 0;
  std::size_t expected_ = 0;                 // expect_views (0: every candidate observed in every view)
  std::vector<std::uint32_t> live_boxes_;    // expect_views: chunk boxes that may hold a wanted slot
  std::vector<std::uint8_t> idle_;           // expect_views: per chunk box, none of its slots wanted
  bool defer_ = false;                       // defer_tracing
  std::vector<std::uint8_t> untraced_;       // defer_tracing: an overflowing view was not traced
};

// ABR (Eq. 9-14) of `candidates` over a sequence of views with the least tracing: one
// BoundaryRefinement with expect_views and defer_tracing, then the flagged candidates it left
// untraced once more, alone, their minima bounded by the first pass's (bound_minimum). The
// result equals one BoundaryRefinement that saw every view (bit for bit: the counts are exact in
// both, and each candidate's minima come from a refinement that traced all its overflowing
// views, or from the first pass's traced views). `for_each_view(add)` calls add(camera, mask)
// (a Mask or an RleMask) once per view, `views` of them, in the same order each time; it is called once, or twice when
// some flagged candidate was left untraced.
template <class ForEachView>
AbrResult refine_deferred(const GaussianScene& scene, const std::vector<Index>& candidates, const AbrParams& params,
                          std::size_t views, ForEachView&& for_each_view) {
  BoundaryRefinement abr(scene, candidates, params);
  abr.expect_views(views);  // candidates whose gate can no longer open are skipped (same result)
  abr.defer_tracing();
  abr.add_views(for_each_view);  // each view a Mask or an RleMask
  AbrResult a = abr.finish();
  const std::vector<std::size_t> again = abr.flagged_untraced();
  if (again.empty()) return a;
  std::vector<Index> sub(again.size());
  for (std::size_t i = 0; i < again.size(); ++i) sub[i] = candidates[again[i]];
  BoundaryRefinement exact(scene, std::move(sub), params);
  exact.expect_views(views);
  for (std::size_t i = 0; i < again.size(); ++i)  // the first pass's minima bound the exact ones
    exact.bound_minimum(i, {abr.min_factor(again[i], 0), abr.min_factor(again[i], 1), abr.min_factor(again[i], 2)});
  exact.add_views(for_each_view);
  const AbrResult b = exact.finish();
  for (std::size_t i = 0; i < again.size(); ++i) {
    for (int d = 0; d < 3; ++d) a.log_scale[d][again[i]] = b.log_scale[d][i];
    a.axis_compressed[again[i]] = b.axis_compressed[i];
  }
  a.compressed = static_cast<std::size_t>(
      std::count_if(a.axis_compressed.begin(), a.axis_compressed.end(), [](std::uint8_t c) { return c != 0; }));
  a.retraced = again.size();
  return a;
}

}  // namespace vcar
