#pragma once
// Stages 2 and 3 of one object from its coarse selection: the object sphere (Eq. 4-5), view
// completeness (Eq. 6, A.1-A.2), spherical spiral sampling and the fine round (Eq. 7-8), and ABR
// (Eq. 9-14, B) with the rule beyond the paper that runs before it (R8; docs/robust.md).
#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/decisive_threshold.hpp"
#include "vcar/algo/diagnostics.hpp"
#include "vcar/algo/params.hpp"
#include "vcar/algo/robust_sphere.hpp"
#include "vcar/algo/round.hpp"
#include "vcar/algo/round_vote.hpp"
#include "vcar/algo/spiral_sampler.hpp"
#include "vcar/algo/undershoot.hpp"
#include "vcar/algo/view_completeness.hpp"
#include "vcar/algo/vote_valley.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/rle_mask.hpp"

namespace vcar::detail {

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
//   has_round()  whether a fine round runs; then frames(), coarse_set(), render_need() and one
//                on_mask(frame, mask, render) per frame, then end_round();
//   finish()     R8 and ABR: fills the result.
// start() and end_round() return false when a stage selected nothing
// (diagnostics.note says which). `train_masks` holds the coarse round's training masks (indexed
// by training view) for ABR and takes the fine round's (keeps its own when no fine frame gets a mask).
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
    coarse_masks_ = std::move(train_masks_);  // ABR's again if no fine frame gets a mask
    train_masks_.assign(coarse_masks_.size(), std::nullopt);
    return true;
  }

  bool has_round() const { return fine_.has_value(); }
  const std::vector<Camera>& frames() const { return fine_frames_; }  // reference view first
  const std::vector<Index>& coarse_set() const { return coarse_set_; }
  RenderNeed render_need() const { return fine_ ? fine_->render_need() : RenderNeed{}; }

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
    if (m) round_undershoot_.push_back(fine_->last_undershoot_px());
  }

  // After the round: its timings (render, segmenter, voting) and the fine selection (Eq. 3, R14, R7).
  bool end_round(double render_s, double segment_s, double voting_s) {
    timing("fine_render", render_s);
    timing("fine_segment", segment_s);
    timing("fine_voting", voting_s);
    diag_.overshoot_eroded += fine_->overshoot_eroded();
    if (round_undershoot_.empty()) {  // no frame had a mask: G_coarse stands, ABR on the coarse round's masks
      fine_.reset();
      train_masks_ = std::move(coarse_masks_);
      diag_.note = "no frame of the fine round had a mask (a segmenter that does not answer renders of G_coarse, "
                   "such as a mask folder): the result is G_coarse";
      return true;
    }
    coarse_masks_ = {};  // the fine round's masks replace them
    fine_->weigh_views(params_.tau_fine);  // Eq. R13
    float tau = params_.tau_fine;
    if (params_.valley.enabled) {
      fine_->ratios(scores_);
      const VoteHistogram hist = vote_histogram(scores_, params_.tau_coarse, "the fine vote");
      if (masks_undershoot(std::move(round_undershoot_)) || vote_spread(hist))  // Eq. R14's gates
        tau = vote_valley(hist);  // Eq. R14
    }
    verdict_ = fine_->selected(tau, params_.strict.tau, split_fraction, selected_, scores_);  // Eq. 3, R7
    verdict_.split = verdict_.split || (verdict_.tau == tau && tau < params_.tau_fine);
    diag_.tau_fine_applied = verdict_.tau;
    diag_.undershoot_applied = verdict_.undershoot;
    diag_.fine_split = verdict_.split;
    diag_.n_fine = diag_.n_final = selected_.size();
    fine_.reset();
    if (selected_.empty()) {
      diag_.note = "the fine vote kept no Gaussian (tau_fine too high for these masks?)";
      return false;
    }
    return true;
  }

  void finish(const ProgressCallback& progress, Clock::time_point t_start) {
    // ---- Stage 3: ABR on the training views with masks from the latest round (Eq. 9-14, B).
    if (params_.enable_abr) stage(progress, t_start, "abr");
    // Eq. R8 after a split fine vote: each training mask widened by its undershoot, and the
    // Gaussians' own footprints (no low-pass: it would widen every ellipse past masks that are
    // already too small).
    const bool r8 = params_.undershoot.band > 0.f && params_.enable_abr && verdict_.split;
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
  std::vector<double> round_undershoot_;  // Eq. R6a of every masked fine frame (px), for R14's gate (one per mask)
  FineVerdict verdict_;             // the fine vote's (Eq. R7, R6c); none without a fine round
  std::vector<Index> coarse_set_;   // G_coarse, the fine round's renders
  std::vector<Camera> fine_frames_;
  std::vector<std::size_t> fine_train_;  // fine frame -> training frame k (npos: sampled)
  std::optional<RoundVote> fine_;
  std::vector<std::optional<RleMask>> coarse_masks_;  // the coarse round's training masks, during the fine round
  Mask scratch_;  // a mask eroded by Eq. R11
};

// Stages 2 and 3 for one object, its fine round asked of `segmenter` alone (ObjectRefinement).
template <Renderer R, Segmenter S>
bool refine(const GaussianScene& scene, const std::vector<Camera>& train_cameras, const Prompt& prompt, R& renderer,
            S& segmenter, const VcarParams& params, const ProgressCallback& progress, Clock::time_point t_start,
            std::vector<std::optional<RleMask>>& train_masks, std::vector<Index> selected, std::vector<float> scores,
            SegmentationResult& result, std::string_view fine_round = "fine round") {
  ObjectRefinement r(scene, train_cameras, prompt, params, train_masks, std::move(selected), std::move(scores), result);
  if (!r.start(renderer, progress, t_start)) return false;
  if (r.has_round()) {
    const RoundTimes t = run_round(
        fine_round, scene, &r.coarse_set(), r.frames(), prompt, renderer, segmenter, params, progress, t_start,
        [&](std::size_t k, const Mask* m, const RenderOutput* render) { r.on_mask(k, m, render, renderer); },
        result.diagnostics.masks_missing, r.render_need());
    if (!r.end_round(t.render, t.total - t.render - t.voting, t.voting)) return false;
  }
  r.finish(progress, t_start);
  return true;
}

}  // namespace vcar::detail
