#pragma once
// vcar::segment: the coarse-to-fine pipeline of Sec. 3.1. It only composes the stages:
//   coarse VWV on the training views (Eq. 1-3)
//   -> robust object sphere (Eq. 4-5) -> view completeness (Eq. 6, A.1-A.2)
//   -> if Delta_max > Delta_th: SSS views (Eq. 7-8) rendered from G_coarse only, segmented with
//      the training views rendered from G_coarse, fine VWV over V_train u V_sampled
//   -> ABR (Eq. 9-14, B) on the training views' masks of the latest round.
// Masks are streamed: each is voted on as the segmenter delivers it and then dropped; the
// training views' masks that ABR needs later are kept run-length encoded (O(boundary) bytes).
#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/robust_voting.hpp"
#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/coplanar_background.hpp"
#include "vcar/algo/decisive_threshold.hpp"
#include "vcar/algo/diagnostics.hpp"
#include "vcar/algo/occlusion_growth.hpp"
#include "vcar/algo/overshoot.hpp"
#include "vcar/algo/params.hpp"
#include "vcar/algo/robust_sphere.hpp"
#include "vcar/algo/spiral_sampler.hpp"
#include "vcar/algo/undershoot.hpp"
#include "vcar/algo/view_completeness.hpp"
#include "vcar/algo/visibility_voting.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/rle_mask.hpp"

namespace vcar {

// What the progress callback sees: the stage, and within a segmentation round the view.
struct Progress {
  std::string_view stage;
  std::size_t view = 0, views = 0;
  double elapsed_s = 0;
};
// Called between stages and between views; returning false cancels (vcar::Cancelled).
using ProgressCallback = std::function<bool(const Progress&)>;

struct Cancelled : Error {
  explicit Cancelled(const std::string& stage) : Error("cancelled by the caller", stage) {}
};

struct SegmentationResult {
  std::vector<Index> indices;  // G*, ascending scene indices
  std::vector<float> scores;   // R_i of the last vote, aligned with indices
  LogScales log_scale;         // refined log-scales, aligned with indices
  Diagnostics diagnostics;
};

namespace detail {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The one check of a segmenter's mask (every round, segment_objects, Reselection): null (no
// mask) or the view's width x height with one channel; otherwise vcar::Error naming `where`.
inline void check_mask(const Mask* m, const Camera& cam, const std::string& where) {
  if (m && (m->width != cam.width || m->height != cam.height || m->channels != 1))
    throw Error("mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) + "x" +
                    std::to_string(m->channels) + ", the view is " + std::to_string(cam.width) + "x" +
                    std::to_string(cam.height) + "x1", where);
}

// Frame order of a round: the reference view first (conventions §4), then the other training
// views in their order, then the sampled views.
inline std::vector<std::size_t> training_order(std::size_t n, std::size_t reference) {
  std::vector<std::size_t> order{reference};
  for (std::size_t j = 0; j < n; ++j)
    if (j != reference) order.push_back(j);
  return order;
}

// One render of `cam` from `subset` (null: the whole scene) over `background`, with depth when
// asked: every render the pipeline (and the CLI's several-objects run) asks for.
template <Renderer R>
RenderOutput render_view(R& renderer, const GaussianScene& scene, const Camera& cam, const std::vector<Index>* subset,
                         const Eigen::Vector3f& background = Eigen::Vector3f::Zero(), bool want_depth = false) {
  RenderRequest q;
  q.scene = &scene;
  q.camera = &cam;
  q.subset = subset;
  q.background = background;
  q.want_depth = want_depth;
  return renderer.render(q);
}

struct RoundTimes {
  double render = 0, voting = 0, total = 0;
};

// One segmentation round: renders frames on demand from `subset` (null = whole scene), streams
// each mask into `on_mask(frame, mask, render)`, validates sizes, maps segmenter failures to
// errors. With `keep_depth` the frame's render asks for depth too and the latest one is handed
// to on_mask when its mask arrives (else `render` is null): a segmenter that asks for a frame
// just before answering it costs one render per frame, depth included.
template <Renderer R, Segmenter S, class OnMask>
RoundTimes run_round(std::string_view round, const GaussianScene& scene,
                     const std::vector<Index>* subset, std::span<const Camera> frames,
                     const Prompt& prompt, R& renderer, S& segmenter, const VcarParams& params,
                     const ProgressCallback& progress, Clock::time_point t_start, OnMask&& on_mask,
                     std::size_t& masks_missing, bool keep_depth = false) {
  RoundTimes t;
  const auto t0 = Clock::now();
  std::vector<bool> seen(frames.size(), false);
  std::optional<std::pair<std::size_t, RenderOutput>> last;  // the latest render, when keep_depth
  FrameSequence seq;
  seq.cameras = frames;
  seq.subset = subset != nullptr;
  if (subset) seq.drawn = [subset](std::size_t) { return subset; };
  seq.image = [&](std::size_t k) -> ImageRGB8 {
    if (k >= frames.size()) throw Error("frame " + std::to_string(k) + " out of range", std::string(round));
    const auto tr = Clock::now();
    RenderOutput out = render_view(renderer, scene, frames[k], subset, params.background, keep_depth);
    ImageRGB8 img = to_8bit(out.rgb);
    if (keep_depth) last.emplace(k, std::move(out));
    t.render += seconds_since(tr);
    return img;
  };
  MaskSink sink = [&](std::size_t k, const Mask* m) {
    if (k >= frames.size())
      throw Error("segmenter answered frame " + std::to_string(k) + " of " +
                      std::to_string(frames.size()), std::string(round));
    const Camera& cam = frames[k];
    if (seen[k]) throw Error("segmenter answered a frame twice", std::string(round) + ", view '" + cam.name + "'");
    seen[k] = true;
    check_mask(m, cam, std::string(round) + ", view '" + cam.name + "'");
    if (!m) ++masks_missing;
    const auto tv = Clock::now();
    on_mask(k, m, last && last->first == k ? &last->second : nullptr);
    t.voting += seconds_since(tv);
    if (progress && !progress({round, k + 1, frames.size(), seconds_since(t_start)}))
      throw Cancelled(std::string(round));
  };
  try {
    segmenter.segment(seq, prompt, sink);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(std::string("segmenter failed: ") + e.what(), std::string(round));
  }
  for (std::size_t k = 0; k < frames.size(); ++k)
    if (!seen[k]) ++masks_missing;
  t.total = seconds_since(t0);
  return t;
}

// Fraction of a view's pixels that the Gaussians `subset` cover (alpha > 0.5).
template <Renderer R>
double content_fraction(const GaussianScene& scene, const std::vector<Index>& subset, const Camera& cam, R& renderer) {
  const RenderOutput out = render_view(renderer, scene, cam, &subset);
  std::size_t covered = 0;
  for (float a : out.alpha.data) covered += a > 0.5f;
  return out.alpha.data.empty() ? 0.0 : static_cast<double>(covered) / static_cast<double>(out.alpha.data.size());
}

// The vote of one round: the paper's VisibilityVoting (Eq. 1-3, and the occlusion_aware
// option), or RobustVoting when a mechanism beyond the paper is on (docs/robust.md).
class RoundVote {
public:
  RoundVote(const GaussianScene& scene, const std::vector<Index>* candidates, const VcarParams& p, bool fine)
      : occlusion_(p.occlusion_aware || (fine ? p.fine_occlusion : p.coarse_occlusion)),
        overshoot_(p.overshoot_min > 0.f), grow_(!fine && p.grow_max > 0.f), undershoot_(fine && p.undershoot_band > 0.f),
        gated_(undershoot_ && p.undershoot_gate) {
    if (p.robust_vote()) {
      // Eq. R6 needs frames rendered from the candidates alone: the fine round's.
      const RobustVoteOptions o{p.kappa, p.foreshortening, undershoot_ ? p.undershoot_band : 0.f, p.view_reliability};
      if (candidates) robust_.emplace(scene, *candidates, o);
      else robust_.emplace(scene, o);
    } else if (candidates) {
      paper_.emplace(scene, *candidates);
    } else {
      paper_.emplace(scene);
    }
  }
  // Eq. R3's unoccluded view count V^o of every candidate (empty without the robust vote).
  std::span<const std::uint16_t> unoccluded_views() const {
    return robust_ ? robust_->unoccluded_views() : std::span<const std::uint16_t>{};
  }
  // The view's render is needed: depth and alpha for Eq. R3, R11 and R12, alpha for Eq. R6.
  bool wants_depth() const { return occlusion_ || overshoot_ || grow_ || undershoot_; }
  bool occlusion() const { return occlusion_; }
  bool overshoot() const { return overshoot_; }
  bool grow() const { return grow_; }
  // Masks of this round eroded by Eq. R11 (vote() counts them).
  std::size_t overshoot_eroded() const { return overshoot_eroded_; }
  // Switches Eq. R11 off for this round (before its first view).
  void no_overshoot() { overshoot_ = false; }
  void count_overshoot_eroded() { ++overshoot_eroded_; }
  // Masks of this round grown by Eq. R12 (vote() counts them; the coarse round only).
  std::size_t grown() const { return grown_; }
  void count_grown() { ++grown_; }
  // Eq. R6a of the latest view (0 when R6 is off or the view had no mask or render).
  double last_undershoot_px() const { return robust_ && undershoot_ ? robust_->last_undershoot_px() : 0.0; }

  // One view; `render` (depth + alpha) when wants_depth().
  void add_view(const Camera& cam, const Mask* m, const RenderOutput* render, float tolerance) {
    const ImageF* depth = render && occlusion_ ? &render->depth : nullptr;
    const ImageF* alpha = render ? &render->alpha : nullptr;
    if (robust_) robust_->add_view(cam, m, depth, alpha, tolerance);
    else if (depth) paper_->add_view(cam, m, depth, alpha, tolerance);
    else paper_->add_view(cam, m);
  }
  // Eq. R13: the views weighted by their agreement with the vote at tau (after the last view;
  // nothing without view_reliability).
  void weigh_views(float tau) {
    if (robust_) robust_->weigh_views(tau);
  }
  // Eq. 3 (paper) or Eq. R2-R6 (robust): ascending scene indices and their scores.
  // undershoot = false: the vote without Eq. R6's widening (RobustVoting::ratio).
  void selected(float tau, std::vector<Index>& indices, std::vector<float>& scores, bool undershoot = true) const {
    if (robust_) return robust_->selected(tau, indices, scores, undershoot);
    paper_->selected(tau, indices, scores);
  }
  // The same with Eq. R7 choosing between tau and tau_strict (> tau; else tau); returns the
  // threshold applied. With R6's gate, R7 reads the vote without R6 first: when that vote is
  // decisive it is the result; when it splits, the vote with R6 decides as above (Eq. R6c).
  float selected(float tau, float tau_strict, float split, std::vector<Index>& indices, std::vector<float>& scores) const {
    undershoot_applied_ = undershoot_;
    if (gated_ && tau_strict > tau && decided(tau, tau_strict, split, indices, scores, false) == tau_strict) {
      undershoot_applied_ = false;                                                           // Eq. R6c
      return tau_strict;
    }
    return decided(tau, tau_strict, split, indices, scores, true);
  }
  // Whether Eq. R6 shaped the latest selected(tau, tau_strict, ...) (false when its gate found
  // the vote without it decisive).
  bool undershoot_applied() const { return undershoot_applied_; }

private:
  float decided(float tau, float tau_strict, float split, std::vector<Index>& indices, std::vector<float>& scores,
                bool undershoot) const {
    selected(tau, indices, scores, undershoot);
    if (!(tau_strict > tau)) return tau;
    std::vector<Index> strict;
    std::vector<float> strict_scores;
    selected(tau_strict, strict, strict_scores, undershoot);
    if (!decisive_vote(strict.size(), indices.size(), split)) return tau;                   // Eq. R7
    indices = std::move(strict);
    scores = std::move(strict_scores);
    return tau_strict;
  }

  bool occlusion_, overshoot_, grow_, undershoot_, gated_;
  std::size_t overshoot_eroded_ = 0, grown_ = 0;
  mutable bool undershoot_applied_ = false;
  std::optional<VisibilityVoting> paper_;
  std::optional<RobustVoting> robust_;
};

// One vote of one view. With the occlusion test (or Eq. R11, R12) the view's expected depth comes
// from `render` when the round kept it, else it is rendered from the same Gaussians the
// segmenter saw. With Eq. R11 a mask that overshoots the render's occlusion edges is voted
// eroded (a copy in `scratch`; an erosion that would take more than three quarters of the
// mask's foreground is not applied: structures thinner than the erosion, or a mask of scattered
// specks, are not what a dilated object looks like); with Eq. R12 (coarse round) one that stops
// short of them is voted grown to them.
// Returns the mask voted (m, &scratch or null): the one the caller keeps for ABR.
template <Renderer R>
const Mask* vote(RoundVote& voting, const Camera& cam, const Mask* m, const RenderOutput* render,
                 const GaussianScene& scene, const std::vector<Index>* subset, R& renderer, const VcarParams& params,
                 Mask& scratch) {
  if (!voting.wants_depth() || !m) {
    voting.add_view(cam, m, nullptr, params.depth_tolerance);
    return m;
  }
  RenderOutput own;
  if (!render || render->depth.empty()) {
    own = render_view(renderer, scene, cam, subset, Eigen::Vector3f::Zero(), true);
    render = &own;
  }
  if (render->depth.empty() && voting.occlusion())
    throw Error("the occlusion test needs a renderer that returns depth", "view '" + cam.name + "'");
  if ((voting.overshoot() || voting.grow()) && !render->depth.empty()) {
    auto foreground = [](const Mask& x) {
      return static_cast<std::size_t>(std::count_if(x.data.begin(), x.data.end(), [](std::uint8_t v) { return v != 0; }));
    };
    const std::vector<std::uint8_t> edges = occlusion_edges(render->alpha, render->depth, params.depth_tolerance);  // Eq. R11a
    const double o = overshoot_px(*m, edges);  // Eq. R11b
    if (voting.overshoot() && o >= static_cast<double>(params.overshoot_min)) {
      scratch = *m;
      erode_by_overshoot(scratch, o + static_cast<double>(params.overshoot_margin));  // Eq. R11c
      if (4 * foreground(scratch) >= foreground(*m)) {  // thin or scattered masks are kept as they are
        m = &scratch;
        voting.count_overshoot_eroded();
      }
    } else if (voting.grow() && o < static_cast<double>(params.overshoot_min)) {
      const int reach = growth_reach(o, foreground(*m), m->width, m->height, params.grow_max, params.grow_margin);  // Eq. R12c
      scratch = *m;
      if (grow_to_occlusion_edges(scratch, edges, render->alpha, render->depth, params.depth_tolerance, reach) > 0) {
        m = &scratch;  // Eq. R12b
        voting.count_grown();
      }
    }
  }
  voting.add_view(cam, m, render, params.depth_tolerance);
  return m;
}

// The mask, or null when it is below min_mask_fraction (conventions §7: the code drops tiny masks).
inline const Mask* usable(const Mask* m, const VcarParams& params) {
  if (!m || !(params.min_mask_fraction > 0.f)) return m;
  std::size_t fg = 0;
  for (std::uint8_t v : m->data) fg += v != 0;
  return static_cast<double>(fg) > params.min_mask_fraction * static_cast<double>(m->pixels()) ? m : nullptr;
}

// Sphere (Eq. 4-5) and view completeness (Eq. 6, A.1-A.2) of the selection `selected`, into
// diag (sphere, valid cameras, gap, timing "vca").
inline AngularGap assess_completeness(const GaussianScene& scene, const std::vector<Index>& selected,
                                      const std::vector<Camera>& train_cameras, std::size_t ref,
                                      const VcarParams& params, Diagnostics& diag) {
  const auto tv = Clock::now();
  diag.sphere = robust_sphere(scene, selected, train_cameras[ref].position(), params.eta);
  const auto valid = valid_cameras(scene, selected, train_cameras, params.rho_min);
  diag.valid_cameras = valid.size();
  std::vector<Eigen::Vector3f> positions;
  for (std::size_t j : valid) positions.push_back(train_cameras[j].position());
  const AngularGap gap = max_angular_gap(fibonacci_lattice(params.K), headings(diag.sphere.c, positions));
  diag.max_gap_deg = gap.Delta_max_deg;
  diag.gap_direction = gap.direction;
  diag.timings_s.emplace_back("vca", seconds_since(tv));
  return gap;
}

// ABR (Eq. 9-14, B) of `selected` on the training views that have a mask in `train_masks`
// (run-length encoded, indexed like train_cameras): the refined log-scales, aligned with
// `selected` (the scene's own when ABR is off). Fills diag's ABR counts, mask bytes and timing.
inline LogScales refine_boundaries(const GaussianScene& scene, const std::vector<Index>& selected,
                                   const std::vector<Camera>& train_cameras,
                                   const std::vector<std::optional<RleMask>>& train_masks, const VcarParams& params,
                                   Diagnostics& diag) {
  if (!params.enable_abr) {
    LogScales out{std::vector<float>(selected.size()), std::vector<float>(selected.size()),
                  std::vector<float>(selected.size())};
    for (std::size_t k = 0; k < selected.size(); ++k)
      for (int d = 0; d < 3; ++d) out[d][k] = scene.log_scale[d][selected[k]];
    return out;
  }
  const auto ta = Clock::now();
  std::size_t views = 0;
  for (const auto& m : train_masks) views += m.has_value();
  AbrResult a = refine_deferred(scene, selected, params.abr(), views, [&](auto&& add) {
    for (std::size_t j = 0; j < train_masks.size(); ++j)  // run-length encoded: ABR builds its tiles from the runs
      if (train_masks[j]) add(train_cameras[j], *train_masks[j]);
  });
  diag.mask_store_bytes = 0;
  for (const auto& m : train_masks)
    if (m) diag.mask_store_bytes += m->bytes();
  diag.abr_flagged = a.flagged;
  diag.abr_compressed = a.compressed;
  diag.abr_retraced = a.retraced;
  diag.timings_s.emplace_back("abr", seconds_since(ta));
  return std::move(a.log_scale);
}

// Stages 2 and 3 of vcar::segment for one object, from its coarse selection `selected`
// (scores: its R_i): sphere (Eq. 4-5), view completeness (Eq. 6), SSS and the fine round
// (Eq. 7-8), ABR (Eq. 9-14). In steps, so that several objects can share one segmenter call
// for their fine rounds (the CLI's several-objects run):
//   start()      sphere, view completeness, V_sampled and the fine round's frames;
//   has_round()  whether a fine round runs; then frames(), coarse_set(), wants_depth() and one
//                on_mask(frame, mask, render) per frame, then end_round();
//   finish()     Eq. R10, R8 and ABR: fills the result.
// start(), end_round() and finish() return false when a stage selected nothing
// (diagnostics.note says which). `train_masks` holds the coarse round's training masks (indexed
// by training view) for ABR and takes the fine round's.
class ObjectRefinement {
public:
  ObjectRefinement(const GaussianScene& scene, const std::vector<Camera>& train_cameras, const Prompt& prompt,
                   const VcarParams& params, std::vector<std::optional<RleMask>>& train_masks,
                   std::vector<Index> selected, std::vector<float> scores, SegmentationResult& result)
      : scene_(scene), train_(train_cameras), prompt_(prompt), params_(params), train_masks_(train_masks),
        selected_(std::move(selected)), scores_(std::move(scores)), result_(result), diag_(result.diagnostics),
        order_(training_order(train_cameras.size(), prompt.reference_view)),
        undershoot_(train_cameras.size(), 0.0) {}
  ObjectRefinement(const ObjectRefinement&) = delete;  // the fine vote points at coarse_set_
  ObjectRefinement& operator=(const ObjectRefinement&) = delete;

  template <Renderer R>
  bool start(R& renderer, const ProgressCallback& progress, Clock::time_point t_start) {
    diag_.n_coarse = diag_.n_fine = diag_.n_final = selected_.size();
    if (selected_.empty()) {
      diag_.note = "the coarse stage selected no Gaussian (no training view shows the target, or every mask is empty)";
      return false;
    }
    // ---- Stage 2: sphere (Eq. 4-5), view completeness (Eq. 6), SSS (Eq. 7-8), fine VWV. The
    // sphere and the gap only serve SSS: with SSS off they are not computed.
    const std::size_t ref = prompt_.reference_view;
    AngularGap gap;
    if (params_.enable_sss) {
      stage(progress, t_start, "view_completeness");
      gap = assess_completeness(scene_, selected_, train_, ref, params_, diag_);
    }
    diag_.sss_triggered = params_.enable_sss && (params_.force_sss || gap.Delta_max_deg > params_.Delta_th_deg);
    if (!diag_.sss_triggered && !params_.force_fine_round) return true;
    stage(progress, t_start, "sss");
    if (diag_.sss_triggered) {
      const Eigen::Vector3f up = estimate_scene_up(train_);
      const Intrinsics intr = sampled_view_intrinsics(train_[ref], params_.sampled_intrinsics, params_.sampled_fov_deg);
      diag_.sampled_cameras = params_.gap_directed
          ? gap_directed_cameras(diag_.sphere, up, gap.direction, intr, params_.gap_directed_views, params_.gap_directed_cone_deg)
          : spiral_cameras(diag_.sphere, up, intr, params_);
    }
    coarse_set_ = selected_;
    auto add_frame = [&](const Camera& c, std::size_t k) {
      // conventions §7: the code drops near-empty frames of this round, the prompt frame excepted.
      if (k != 0 && params_.min_frame_content > 0.f &&
          content_fraction(scene_, coarse_set_, c, renderer) < params_.min_frame_content)
        return;
      fine_frames_.push_back(c);
      fine_train_.push_back(k);
    };
    for (std::size_t k = 0; k < order_.size(); ++k) add_frame(train_[order_[k]], k);
    for (const Camera& c : diag_.sampled_cameras) add_frame(c, static_cast<std::size_t>(-1));
    fine_.emplace(scene_, &coarse_set_, params_, true);
    // Eq. R11 in the fine round only after the coarse round found masks overshooting the renders
    // of the whole scene: this round renders G_coarse, which the masks shaped, so masks that
    // undershoot would read as overshooting a G_coarse they eroded.
    if (diag_.overshoot_eroded == 0) fine_->no_overshoot();
    for (auto& m : train_masks_) m.reset();
    return true;
  }

  bool has_round() const { return fine_.has_value(); }
  const std::vector<Camera>& frames() const { return fine_frames_; }  // reference view first
  const std::vector<Index>& coarse_set() const { return coarse_set_; }
  bool wants_depth() const { return fine_ && fine_->wants_depth(); }

  // The mask of fine frame k (null: none); `render` of that frame (depth and alpha) when the
  // round kept it, else vote() renders it.
  template <Renderer R>
  void on_mask(std::size_t k, const Mask* m, const RenderOutput* render, R& renderer) {
    m = vote(*fine_, fine_frames_[k], usable(m, params_), render, scene_, &coarse_set_, renderer, params_, scratch_);
    const std::size_t t = fine_train_[k];
    if (t < order_.size()) {
      train_masks_[order_[t]] = m && params_.enable_abr ? std::optional<RleMask>(RleMask::encode(*m)) : std::nullopt;
      undershoot_[order_[t]] = m ? fine_->last_undershoot_px() : 0.0;
    }
  }

  // After the round: its timings (render, segmenter, voting) and the fine selection (Eq. 3, R7).
  bool end_round(double render_s, double segment_s, double voting_s) {
    timing("fine_render", render_s);
    timing("fine_segment", segment_s);
    timing("fine_voting", voting_s);
    diag_.overshoot_eroded += fine_->overshoot_eroded();
    fine_->weigh_views(params_.tau_fine);  // Eq. R13
    diag_.tau_fine_applied = fine_->selected(params_.tau_fine, params_.tau_strict, params_.split_fraction, selected_, scores_);
    split_ = diag_.tau_fine_applied < params_.tau_strict;  // R7 found the vote split
    diag_.undershoot_applied = fine_->undershoot_applied();
    diag_.n_fine = diag_.n_final = selected_.size();
    fine_.reset();
    if (selected_.empty()) {
      diag_.note = "the fine vote kept no Gaussian (tau_fine too high for these masks?)";
      return false;
    }
    return true;
  }

  bool finish(const ProgressCallback& progress, Clock::time_point t_start, std::span<const std::uint16_t> coarse_seen) {
    // ---- Beyond the paper: hidden candidates on a seen background plane (Eq. R10), from the
    // coarse round's occlusion test over the whole scene (coarse_seen: V^o per scene Gaussian).
    // Not after a split fine vote (Eq. R7): masks that undershoot label the object's own seen
    // rim background, and R10 would carry that label into the hidden part of its planes.
    if (params_.coplanar_radius > 0.f && !coarse_seen.empty() && !split_) {
      const auto tc = Clock::now();
      const CoplanarParams cp{params_.coplanar_radius, params_.coplanar_angle_deg, params_.coplanar_slab};
      const std::vector<std::size_t> drop =
          coplanar_background(scene_, selected_, [&](Index i) { return coarse_seen[i] > 0; }, cp);  // Eq. R10
      std::size_t w = 0;
      for (std::size_t k = 0, d = 0; k < selected_.size(); ++k) {
        if (d < drop.size() && drop[d] == k) { ++d; continue; }
        selected_[w] = selected_[k];
        scores_[w++] = scores_[k];
      }
      selected_.resize(w);
      scores_.resize(w);
      diag_.coplanar_dropped = drop.size();
      diag_.n_final = selected_.size();
      timing("coplanar", seconds_since(tc));
      if (selected_.empty()) {
        diag_.note = "Eq. R10 dropped every candidate (hidden on a background plane); set coplanar_radius=0";
        return false;
      }
    }

    // ---- Stage 3: ABR on the training views with masks from the latest round (Eq. 9-14, B).
    if (params_.enable_abr) stage(progress, t_start, "abr");
    // Eq. R8 after a split fine vote: each training mask widened by its undershoot, and the
    // Gaussians' own footprints (no low-pass: it would widen every ellipse past masks that are
    // already too small).
    const bool r8 = params_.abr_undershoot && params_.enable_abr && split_;
    VcarParams abr_params = params_;
    if (r8) abr_params.abr_lowpass = false;
    if (r8)
      for (std::size_t j = 0; j < train_.size(); ++j)
        if (train_masks_[j] && undershoot_[j] > 0.0) {
          Mask m = train_masks_[j]->decode();
          dilate_by_undershoot(m, undershoot_[j]);  // Eq. R8
          train_masks_[j] = RleMask::encode(m);
          ++diag_.abr_masks_widened;
        }
    result_.log_scale = refine_boundaries(scene_, selected_, train_, train_masks_, abr_params, diag_);
    result_.indices = std::move(selected_);
    result_.scores = std::move(scores_);
    diag_.n_final = result_.indices.size();
    return true;
  }

private:
  static void stage(const ProgressCallback& progress, Clock::time_point t_start, std::string_view name) {
    if (progress && !progress({name, 0, 0, seconds_since(t_start)})) throw Cancelled(std::string(name));
  }
  void timing(std::string name, double s) { diag_.timings_s.emplace_back(std::move(name), s); }

  const GaussianScene& scene_;
  const std::vector<Camera>& train_;
  const Prompt& prompt_;
  const VcarParams& params_;
  std::vector<std::optional<RleMask>>& train_masks_;
  std::vector<Index> selected_;
  std::vector<float> scores_;
  SegmentationResult& result_;
  Diagnostics& diag_;
  std::vector<std::size_t> order_;  // frame k of a round -> training view
  std::vector<double> undershoot_;  // Eq. R6a of each training view's fine-round mask (px)
  bool split_ = false;              // Eq. R7 kept the majority threshold
  std::vector<Index> coarse_set_;   // G_coarse, the fine round's renders
  std::vector<Camera> fine_frames_;
  std::vector<std::size_t> fine_train_;  // fine frame -> training frame k (npos: sampled)
  std::optional<RoundVote> fine_;
  Mask scratch_;  // a mask eroded by Eq. R11
};

// Stages 2 and 3 for one object, its fine round asked of `segmenter` alone (ObjectRefinement).
template <Renderer R, Segmenter S>
bool refine(const GaussianScene& scene, const std::vector<Camera>& train_cameras, const Prompt& prompt, R& renderer,
            S& segmenter, const VcarParams& params, const ProgressCallback& progress, Clock::time_point t_start,
            std::vector<std::optional<RleMask>>& train_masks, std::vector<Index> selected, std::vector<float> scores,
            SegmentationResult& result, std::string_view fine_round = "fine round",
            std::span<const std::uint16_t> coarse_seen = {}) {
  ObjectRefinement r(scene, train_cameras, prompt, params, train_masks, std::move(selected), std::move(scores), result);
  if (!r.start(renderer, progress, t_start)) return false;
  if (r.has_round()) {
    const RoundTimes t = run_round(
        fine_round, scene, &r.coarse_set(), r.frames(), prompt, renderer, segmenter, params, progress, t_start,
        [&](std::size_t k, const Mask* m, const RenderOutput* render) { r.on_mask(k, m, render, renderer); },
        result.diagnostics.masks_missing, r.wants_depth());
    if (!r.end_round(t.render, t.total - t.render - t.voting, t.voting)) return false;
  }
  return r.finish(progress, t_start, coarse_seen);
}

// Stages 2 and 3 (refine) from the coarse selection at tau_coarse: `coarse_selection(tau,
// indices, scores)` gives the coarse vote's selection at a threshold; `train_masks` holds the
// coarse round's training masks.
template <Renderer R, Segmenter S, class CoarseSelection>
bool refine_from_coarse(const GaussianScene& scene, const std::vector<Camera>& train_cameras, const Prompt& prompt,
                        R& renderer, S& segmenter, const VcarParams& params, const ProgressCallback& progress,
                        Clock::time_point t_start, std::vector<std::optional<RleMask>>& train_masks,
                        CoarseSelection&& coarse_selection, SegmentationResult& result,
                        std::string_view fine_round = "fine round", std::span<const std::uint16_t> coarse_seen = {}) {
  std::vector<Index> selected;
  std::vector<float> scores;
  coarse_selection(params.tau_coarse, selected, scores);
  return refine(scene, train_cameras, prompt, renderer, segmenter, params, progress, t_start, train_masks,
                std::move(selected), std::move(scores), result, fine_round, coarse_seen);
}

}  // namespace detail

// Segments the object prompted on train_cameras[prompt.reference_view].
// Throws vcar::Error for bad input (empty scene, no cameras, reference view out of range,
// invalid parameters, a failing segmenter or a wrong-size mask, naming the view) and
// vcar::Cancelled when `progress` returns false. An object that no view selects is not an
// error: the result is empty and diagnostics.note says why.
template <Renderer R, Segmenter S>
SegmentationResult segment(const GaussianScene& scene, const std::vector<Camera>& train_cameras,
                           const Prompt& prompt, R& renderer, S& segmenter,
                           const VcarParams& params = VcarParams::robust(), const ProgressCallback& progress = {}) {
  using detail::Clock;
  using detail::seconds_since;
  params.validate();
  if (scene.empty()) throw Error("the scene has no Gaussians", "scene");
  if (train_cameras.empty()) throw Error("no training cameras", "cameras");
  if (prompt.reference_view >= train_cameras.size())
    throw Error("reference view " + std::to_string(prompt.reference_view) + " out of range (" +
                    std::to_string(train_cameras.size()) + " training views)", "prompt");
  for (const Camera& c : train_cameras) c.validate();

  const auto t_start = Clock::now();
  SegmentationResult result;
  Diagnostics& diag = result.diagnostics;
  diag.n_scene = scene.size();
  auto stage = [&](std::string_view name) {
    if (progress && !progress({name, 0, 0, seconds_since(t_start)})) throw Cancelled(std::string(name));
  };
  auto timing = [&](std::string name, double s) { diag.timings_s.emplace_back(std::move(name), s); };

  const std::size_t M = train_cameras.size();
  const std::size_t ref = prompt.reference_view;
  const std::vector<std::size_t> order = detail::training_order(M, ref);
  std::vector<Camera> frames;
  for (std::size_t j : order) frames.push_back(train_cameras[j]);

  // Masks of the training views from the latest round, for ABR (B.3), run-length encoded.
  std::vector<std::optional<RleMask>> train_masks(M);
  auto keep_training_mask = [&](std::size_t k, const Mask* m) {
    if (k < M) train_masks[order[k]] = m && params.enable_abr ? std::optional<RleMask>(RleMask::encode(*m)) : std::nullopt;
  };
  auto usable = [&](const Mask* m) { return detail::usable(m, params); };

  // ---- Stage 1: coarse VWV on the training views, rendered from the whole scene (Eq. 1-3;
  // with the robust vote, Eq. R2-R5).
  stage("coarse");
  const auto t_setup = Clock::now();
  detail::RoundVote coarse(scene, nullptr, params, false);  // Morton order of the means: part of the vote
  const double setup = seconds_since(t_setup);
  Mask scratch;  // a mask eroded by Eq. R11
  const detail::RoundTimes t1 = detail::run_round(
      "coarse round", scene, nullptr, frames, prompt, renderer, segmenter, params, progress,
      t_start, [&](std::size_t k, const Mask* m, const RenderOutput* render) {
        m = detail::vote(coarse, frames[k], usable(m), render, scene, nullptr, renderer, params, scratch);
        keep_training_mask(k, m);
      }, diag.masks_missing, coarse.wants_depth());
  timing("coarse_render", t1.render);
  timing("coarse_segment", t1.total - t1.render - t1.voting);
  timing("coarse_voting", setup + t1.voting);
  diag.overshoot_eroded = coarse.overshoot_eroded();
  diag.masks_grown = coarse.grown();
  coarse.weigh_views(params.tau_coarse);  // Eq. R13
  const bool complete = detail::refine_from_coarse(
      scene, train_cameras, prompt, renderer, segmenter, params, progress, t_start, train_masks,
      [&](float tau, std::vector<Index>& selected, std::vector<float>& scores) { coarse.selected(tau, selected, scores); },
      result, "fine round", coarse.occlusion() ? coarse.unoccluded_views() : std::span<const std::uint16_t>{});
  timing("total", seconds_since(t_start));
  if (complete) stage("done");
  return result;
}

}  // namespace vcar
