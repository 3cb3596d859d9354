#pragma once
// Axis-aware Boundary Refinement, ABR (Sec. 3.4, Eq. 9-14; supplementary B.1-B.3), over a
// sequence of views: every training view with a mask from the latest segmentation round is
// added once (conventions §5), then finish() applies the gated, reconciled per-axis compression.
// The kernel (Eq. 9-13) is abr_kernel.hpp, the per-candidate state abr_state.hpp; an earlier
// refinement under changed masks is IncrementalRefinement's (incremental_refinement.hpp).
// Beyond the paper, each the same result with less work (tested bit for bit): views observed
// kViewGroup at a time (add_views), candidates whose gate can no longer open skipped
// (expect_views), tracing deferred to the candidates bound to be flagged (defer_tracing,
// refine_deferred).
#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include "vcar/algo/abr_kernel.hpp"
#include "vcar/algo/abr_state.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/rle_mask.hpp"

namespace vcar {

class BoundaryRefinement : public AbrState {
 public:
  // Copies the candidates' means, rotations and log-scales (the scene need not outlive this).
  // Throws vcar::Error for a candidate index out of range or a parameter out of range.
  using AbrState::AbrState;

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
    detail::check_abr_view(cam, mask, view);
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
    std::vector<detail::AbrViewContext> context;
    for (std::size_t q = 0; q < pending_count_; ++q)
      context.push_back(detail::AbrViewContext::of(pending_[q].cam, params_));
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
  void observe_added_boxes(const PendingView& v, const detail::AbrViewContext& vc, std::int64_t b, std::int64_t e,
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
    defer_ = true;
    partial_ = true;
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
  // minima. Call before the first view; the state then cannot be carried (IncrementalRefinement's
  // minima remember the view that set them).
  void bound_minimum(std::size_t k, const std::array<float, 3>& bound) {
    if (views_ != 0) throw Error("bound_minimum is called before the first view", "BoundaryRefinement");
    if (k >= size()) throw Error("bound_minimum: candidate position out of range", "BoundaryRefinement");
    const std::size_t j = slot_[k];
    for (int d = 0; d < 3; ++d) f_[d][j] = std::max(params_.f_min, std::min(f_[d][j], bound[d]));
    partial_ = true;
  }

  // Announces that exactly `total` views will be added (add_view), which lets the refinement
  // skip a candidate once its gate (B.3: gamma = n_ovf / n_vis > rho) can no longer open: with
  // R views to come, gamma ends at most (n_ovf + R) / (n_vis + R). finish() is unchanged (a
  // skipped candidate is never flagged either way); n_vis, n_ovf and min_factor of a skipped
  // candidate stay where they were, and such a refinement cannot be carried (IncrementalRefinement
  // throws).
  // Call before the first view; 0 turns it off.
  void expect_views(std::size_t total) {
    if (views_ != 0) throw Error("expect_views is called before the first view", "BoundaryRefinement");
    expected_ = total;
    partial_ = total != 0;
    live_boxes_.resize(box_.size());
    std::iota(live_boxes_.begin(), live_boxes_.end(), std::uint32_t{0});
    idle_.assign(box_.size(), 0);
  }
  // Chunk boxes (runs of 64 candidates) the next view observes: all of them, or with
  // expect_views those that still hold a candidate whose gate can open.
  std::size_t boxes_observed() const noexcept { return expected_ ? live_boxes_.size() : box_.size(); }

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

 private:
  // gate_can_open as a table for a view (expect_views): gate[v] is least_opening_overflow(v), so
  // that the per-slot test is one integer comparison. n_vis < views_ here.
  void fill_gate_table(std::size_t remaining, std::vector<std::uint32_t>& gate) const {
    gate.resize(views_ + 1);
    for (std::size_t v = 0; v <= views_; ++v)
      gate[v] = static_cast<std::uint32_t>(least_opening_overflow(v, remaining, params_.rho));
  }

  std::vector<PendingView> pending_;         // up to kViewGroup views (one kept after add_views)
  std::size_t pending_count_ = 0;
  MaskDecoder decoder_;                      // a run-length encoded view's pixels, when no tiles
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
