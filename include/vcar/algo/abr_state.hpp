#pragma once
// Axis-aware Boundary Refinement, ABR (Sec. 3.4, Eq. 9-14; supplementary B.1-B.3): its state.
//
// A streaming accumulator over a candidate set (typically G_fine). Per candidate the state is
// O(1) in the number of views: n_vis, n_ovf (uint16) and the running minimum candidate factor of
// each of the 3 axes, with the view that set it (for IncrementalRefinement). finish() applies
// the gated, reconciled per-axis compression (B.3, Eq. 14). The sweep of one view over the
// candidates (observe_view, with the kernel of abr_kernel.hpp) lives here; which views are
// observed, and for which candidates, is the drivers': BoundaryRefinement (a sequence of views)
// and IncrementalRefinement (an earlier state under changed masks). Candidates are kept in
// Morton order of their means (rule (g), abr_kernel.hpp).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/abr_geometry.hpp"
#include "vcar/algo/abr_kernel.hpp"
#include "vcar/algo/abr_params.hpp"
#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/column_block.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/morton_order.hpp"
#include "vcar/core/parallel.hpp"
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

inline constexpr std::uint16_t abr_no_view = std::numeric_limits<std::uint16_t>::max();  // no view set it

// What observe_boxes reads of one view: the camera, its projection of means and chunk boxes,
// and what abr_geometry reads of it.
struct AbrViewContext {
  const Camera* cam;
  detail::ViewLanes lanes;
  AbrCamera C;
  static AbrViewContext of(const Camera& cam, const AbrParams& p) {
    return {&cam, detail::ViewLanes::of(detail::MeanProjection::from(cam)), AbrCamera::from(cam, p.projection)};
  }
};

// A view's camera and mask (or its runs) as the drivers take them: vcar::Error naming the view
// for a bad camera, a mask of another size, runs that do not cover the image, or an id past 65534.
inline void check_abr_view(const Camera& cam, const Mask& mask, std::uint16_t view) {
  const std::string where = "view '" + cam.name + "'";
  cam.validate();
  if (mask.width != cam.width || mask.height != cam.height || mask.channels != 1 ||
      mask.data.size() != mask.pixels())
    throw Error("mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) + "x" +
                std::to_string(mask.channels) + ", the view is " + std::to_string(cam.width) + "x" +
                std::to_string(cam.height) + "x1", where);
  if (view == abr_no_view) throw Error("view ids go up to 65534", where);
}
inline void check_abr_view(const Camera& cam, const RleMask& mask, std::uint16_t view) {
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
  if (view == abr_no_view) throw Error("view ids go up to 65534", where);
}

// Bit l: want(j + l), for the `lanes` slots from j; want.lanes(j) for a whole batch when Want
// has it.
template <class Want>
unsigned wanted_lanes(Want& want, std::size_t j, std::size_t lanes) {
  if constexpr (requires { want.lanes(j); })
    if (lanes == simd::width) return want.lanes(j);
  unsigned bits = 0;
  for (std::size_t l = 0; l < lanes; ++l) bits |= static_cast<unsigned>(want(j + l)) << l;
  return bits;
}
// apply(j + l, inside) for each bit l of `bits` (l < lanes); apply.inside(j, bits) for a whole
// batch when Apply has it.
template <class Apply>
void apply_inside(Apply& apply, std::size_t j, std::size_t lanes, unsigned bits, const AbrObservation& inside) {
  if constexpr (requires { apply.inside(j, bits); })
    if (lanes == simd::width) return apply.inside(j, bits);
  for (unsigned m = bits; m; m &= m - 1) apply(j + static_cast<std::size_t>(std::countr_zero(m)), inside);
}

}  // namespace detail

class IncrementalRefinement;

class AbrState {
 public:
  // Copies the candidates' means, rotations and log-scales (the scene need not outlive this), in
  // Morton order of the means so that neighbouring work reads neighbouring mask pixels.
  // Throws vcar::Error for a candidate index out of range or a parameter out of range.
  AbrState(const GaussianScene& scene, std::vector<Index> candidates, AbrParams params = {})
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
  AbrState(AbrState&&) = default;
  AbrState& operator=(AbrState&&) = default;

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

 protected:
  friend class IncrementalRefinement;  // carries an earlier state (any driver's)
  static constexpr std::uint16_t no_view = detail::abr_no_view;
  // Whether building the mask tiles for `observed` candidates pays: under one candidate per 256
  // pixels they are observed one by one on the mask itself (the same result either way).
  static bool tiles_pay(std::size_t observed, std::size_t pixels) { return observed * 256 >= pixels; }
  struct Always {  // trace every slot (a type, not a function pointer: inlined per lane)
    bool operator()(std::size_t) const { return true; }
  };
  struct Never {
    bool operator()(std::size_t) const { return false; }
  };



  // Counts one more view (the uint16 counters hold at most 65535).
  void enter_view(const Camera& cam) {
    if (views_ == std::numeric_limits<std::uint16_t>::max())
      throw Error("more than 65535 views for ABR", "view '" + cam.name + "'");
    ++views_;
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
    const detail::AbrViewContext vc = detail::AbrViewContext::of(cam, params_);
    const std::int64_t n_boxes = static_cast<std::int64_t>(boxes ? boxes->size() : box_.size());
    parallel_chunks(n_boxes, kChunk / kBox, [&](std::int64_t, std::int64_t b, std::int64_t e) {
      observe_boxes(vc, b, e, boxes, tiles ? &tiles_ : nullptr, mask, want, apply, trace, idle);
    });
  }

  // observe_view's work on the chunk boxes [b, e) (positions into `boxes`, or box ids), with
  // the view's tiles (or null: its pixels `mask`). A box already marked in `idle` is skipped.
  template <class Want, class Apply, class Trace>
  void observe_boxes(const detail::AbrViewContext& vc, std::int64_t b, std::int64_t e,
                     const std::vector<std::uint32_t>* boxes,
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
      for (std::size_t j = j0; j < j1 && !any; j += simd::width) any = detail::wanted_lanes(want, j, std::min(simd::width, j1 - j)) != 0;
      if (!any) {
        if (idle) idle[c] = 1;  // this task's box only
        continue;
      }
      switch (tiles ? detail::chunk_content(*tiles, projected[static_cast<std::size_t>(i - b) % L], C, *vc.cam, box_[c], p)
                    : MaskTiles::mixed) {
        case MaskTiles::background: continue;  // no centre on foreground: none eligible (B.1)
        case MaskTiles::foreground:            // every centre and endpoint on foreground
          for (std::size_t j = j0; j < j1; j += simd::width) {
            const std::size_t lanes = std::min(simd::width, j1 - j);
            detail::apply_inside(apply, j, lanes, detail::wanted_lanes(want, j, lanes), inside);
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
        const unsigned wanted = detail::wanted_lanes(want, j, lanes);
        if (!wanted) continue;
        geometry(C, j, g);
        // B.1 and rule (e) per lane: with the tiles every lane's centre and endpoint lookups at
        // once from the packed bits, else lane by lane on the mask (the same answers).
        if (tiles) {
          detail::lane_tests(*tiles, g, centre, a.outside);
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
        detail::apply_inside(apply, j, lanes, eligible & ~overflowing, inside);
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
  MaskTiles tiles_;                          // the current view's mask in tiles (observe_view)
  std::array<std::span<float>, 3> log_s_;    // candidate log-scales before refinement (by slot)
  std::array<std::span<float>, 3> f_;        // running minimum candidate factor per axis
  std::span<std::uint16_t> n_vis_, n_ovf_;   // B.3 counts
  std::array<std::span<std::uint16_t>, 3> arg_;  // the view that set f_ (incremental updates)
  std::size_t views_ = 0;
  // Some candidate's counts or minima miss a view (BoundaryRefinement's expect_views or
  // defer_tracing): finish() is exact, the state cannot be carried.
  bool partial_ = false;
};

}  // namespace vcar
