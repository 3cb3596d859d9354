#pragma once
// Interactive re-selection (beyond the paper): the pipeline without rendering or a segmenter,
// for a viewer that re-selects after every click on masks it already holds.
//
// The training views' masks are set one at a time. Eq. 1-2 are sums over views, so the vote
// counters take back a replaced mask's votes and add the new mask's (MultiObjectVoting::
// remove_view): one more or one changed mask costs about 1/M of a full vote. select() reads
// Eq. 3 from the counters, assesses view completeness (Eq. 4-6; reported only: SSS needs a
// renderer and a segmenter, which vcar::segment has) and runs ABR (Eq. 9-14) on the views with
// masks. The result equals vcar::segment's with the same masks and SSS off.
//
// ABR is incremental too (IncrementalRefinement): select() keeps the refinement it ran, and
// the next select() carries the state of the Gaussians both selections hold, takes back and
// re-adds only the views whose masks changed, and observes every view only for the Gaussians
// that entered the selection (or whose minimum factor came from a changed view). When more than
// half the views changed it refines from scratch. Either way the result is the same, bit for bit.
//
// State: the voter (Morton-sorted means and counters, ~20 bytes per Gaussian), the masks
// run-length encoded (O(boundary) bytes each) and the last refinement (~90 bytes per selected
// Gaussian).
//
// The default preset (VcarParams::robust(), as vcar::segment) reads renders: the occlusion test
// (Eq. R3) and the mask edits (Eq. R11, R12) need each training view's alpha and depth over the
// whole scene. Given a renderer, the constructor renders
// every training view once and keeps its alpha and depth (8 bytes per pixel per view); a mask is
// edited (Eq. R11, R12) when it is set, and select() votes every view again (the robust vote's
// levels and view weights, Eq. R2, R13, are not taken back view by view), then the incremental
// ABR. The paper presets (Eq. 1-3) need no renderer and vote incrementally.
#include <algorithm>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/abr_state.hpp"
#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/incremental_refinement.hpp"
#include "vcar/algo/object_refinement.hpp"
#include "vcar/algo/pipeline.hpp"

namespace vcar {

// What the latest Reselection::select() did in ABR.
struct ReselectionStats {
  bool abr_incremental = false;  // started from the previous select()'s refinement
  std::size_t views_changed = 0; // views whose mask changed since then (set, replaced, cleared)
  std::size_t carried = 0;       // selected Gaussians whose state was carried over
  std::size_t fresh = 0;         // selected Gaussians observed in every view (new in the selection)
  std::size_t stale = 0;         // carried Gaussians whose minimum factor was recomputed
};

class Reselection {
public:
  // The scene is referenced (it must outlive this object); cameras and params are copied. The
  // renderer is used here only: every training view rendered once (alpha and depth) when the
  // preset reads renders (VcarParams::robust(), the default, does), none otherwise.
  template <Renderer R>
  Reselection(const GaussianScene& scene, std::vector<Camera> cameras, R& renderer,
              VcarParams params = VcarParams::robust())
      : Reselection(scene, std::move(cameras), params, true) {
    if (!reads_renders()) return;
    renders_.resize(cameras_.size());
    for (std::size_t j = 0; j < cameras_.size(); ++j) {
      RenderOutput r = detail::render_view(renderer, scene, cameras_[j], nullptr, params_.background, true);
      if (r.depth.empty()) throw Error("the renderer returned no depth: the robust vote needs it", "view '" + cameras_[j].name + "'");
      r.rgb = {};
      renders_[j] = std::move(r);
    }
  }
  // Without a renderer: presets that vote with Eq. 1-3 only (VcarParams::nvos(), lerf(),
  // reference_code()); a preset that reads renders (robust()) throws vcar::Error.
  Reselection(const GaussianScene& scene, std::vector<Camera> cameras, VcarParams params)
      : Reselection(scene, std::move(cameras), params, false) {}

  std::size_t views() const noexcept { return cameras_.size(); }
  // Views that currently have a mask.
  std::size_t masks() const noexcept {
    return static_cast<std::size_t>(std::count_if(masks_.begin(), masks_.end(), [](const MaskRef& m) { return m != nullptr; }));
  }

  // Sets, replaces or (mask null) clears the mask of training view `view`. A mask at or below
  // min_mask_fraction counts as none (conventions §7); with a robust preset the mask kept is the
  // one Eq. R11, R12 make of it against the view's render (as vcar::segment votes it). Throws
  // vcar::Error naming the view for an index out of range or a mask of another size.
  void set_mask(std::size_t view, const Mask* mask) {
    if (view >= cameras_.size())
      throw Error("view " + std::to_string(view) + " out of range (" + std::to_string(cameras_.size()) + " views)",
                  "Reselection");
    const Camera& cam = cameras_[view];
    detail::check_mask(mask, cam, "view '" + cam.name + "'");
    mask = detail::usable(mask, params_);
    if (robust()) {
      edits_[view] = detail::MaskEdit::none;
      if (mask) {
        Mask scratch;  // the coarse round's edits: Eq. R11 and R12
        mask = detail::edit_mask(*mask, renders_[view], params_.snap.enabled, params_.snap.enabled, params_,
                                 scratch, edits_[view]);
        masks_[view] = std::make_shared<const RleMask>(RleMask::encode(*mask));
      } else {
        masks_[view].reset();
      }
      return;
    }
    if (masks_[view]) {  // take back the old mask's votes
      vote_->remove_view(cam, &decoder_.decode(*masks_[view]));
      masks_[view].reset();
    }
    if (!mask) return;
    vote_->add_view(cam, mask);
    masks_[view] = std::make_shared<const RleMask>(RleMask::encode(*mask));
  }

  // The selection for the masks set so far (reference view: the sphere's fallback centre, A.1).
  SegmentationResult select(std::size_t reference_view = 0) {
    if (reference_view >= cameras_.size())
      throw Error("reference view " + std::to_string(reference_view) + " out of range", "Reselection");
    const auto t0 = detail::Clock::now();
    SegmentationResult result;
    Diagnostics& diag = result.diagnostics;
    diag.n_scene = scene_->size();
    diag.masks_missing = cameras_.size() - masks();
    auto tv = detail::Clock::now();
    std::vector<Index> selected;
    if (robust()) {  // the whole coarse round again
      detail::RoundVote coarse(*scene_, nullptr, params_, false);
      for (std::size_t j : detail::training_order(cameras_.size(), reference_view)) {
        if (edits_[j] == detail::MaskEdit::eroded) coarse.count_overshoot_eroded();
        if (edits_[j] == detail::MaskEdit::grown) coarse.count_grown();
        if (masks_[j]) coarse.add_view(cameras_[j], &decoder_.decode(*masks_[j]), &renders_[j], params_.depth_tolerance);
        else coarse.add_view(cameras_[j], nullptr, nullptr, params_.depth_tolerance);
      }
      detail::coarse_selection(coarse, params_, diag, selected, result.scores);  // Eq. R2-R3, R13
    } else {
      vote_->selected(params_.tau_coarse, selected, result.scores);  // Eq. 3
    }
    diag.timings_s.emplace_back("coarse_voting", detail::seconds_since(tv));
    diag.n_coarse = diag.n_fine = diag.n_final = selected.size();
    if (selected.empty()) {
      diag.note = "the vote selected no Gaussian (no mask set, or every mask is empty)";
      return result;
    }
    if (params_.enable_sss) {
      const AngularGap gap = detail::assess_completeness(*scene_, selected, cameras_, reference_view, params_, diag);
      if (params_.force_sss || gap.Delta_max_deg > params_.Delta_th_deg)
        diag.note = "the views leave a gap of " + std::to_string(gap.Delta_max_deg) +
                    " degrees: vcar::segment would add sampled views (SSS), re-selection does not";
    }
    result.log_scale = refine(selected, diag);
    result.indices = std::move(selected);
    diag.timings_s.emplace_back("total", detail::seconds_since(t0));
    return result;
  }

  // What the latest select() did in ABR.
  const ReselectionStats& last_stats() const noexcept { return stats_; }
  // Off: every select() refines from scratch (same result; for ablations and benchmarks).
  void set_incremental_abr(bool on) noexcept { incremental_abr_ = on; }

private:
  using MaskRef = std::shared_ptr<const RleMask>;

  Reselection(const GaussianScene& scene, std::vector<Camera> cameras, VcarParams params, bool renderer)
      : scene_(&scene), cameras_(std::move(cameras)), params_(params), masks_(cameras_.size()),
        abr_masks_(cameras_.size()), edits_(cameras_.size(), detail::MaskEdit::none) {
    params_.validate();
    if (!renderer && reads_renders())
      throw Error("this preset reads renders (the occlusion test, Eq. R3, R11-R12, or the robust vote's levels): "
                  "construct with a renderer, Reselection(scene, cameras, renderer, params), or use a paper preset "
                  "such as VcarParams::nvos()", "Reselection");
    if (params_.occlusion_aware) throw Error("occlusion_aware needs the fine round's renders (use vcar::segment)", "Reselection");
    if (scene.empty()) throw Error("the scene has no Gaussians", "scene");
    if (cameras_.empty()) throw Error("no training cameras", "cameras");
    if (cameras_.size() >= 65535) throw Error("more than 65534 views", "Reselection");
    for (const Camera& c : cameras_) c.validate();
    if (!reads_renders()) vote_.emplace(scene);
  }
  // The coarse round of this preset reads renders or votes with the robust vote (which needs
  // them for all but Eq. R2 and R13; they are cheap next to a segmenter, so any robust vote
  // takes the renderer path).
  bool reads_renders() const {
    return params_.robust_vote() || params_.snap.enabled;
  }
  bool robust() const { return !renders_.empty(); }


  // ABR (Eq. 9-14) of `selected` on the views with masks, from the previous refinement when
  // few views changed (see the top of this file). Fills diag like detail::refine_boundaries.
  LogScales refine(const std::vector<Index>& selected, Diagnostics& diag) {
    stats_ = {};
    if (!params_.enable_abr) {
      abr_.reset();
      return detail::refine_boundaries(*scene_, selected, cameras_, {}, params_, diag);
    }
    const auto ta = detail::Clock::now();
    std::vector<std::size_t> changed, with_mask;
    diag.mask_store_bytes = 0;
    for (std::size_t j = 0; j < cameras_.size(); ++j) {
      if (masks_[j] != abr_masks_[j]) changed.push_back(j);
      if (masks_[j]) with_mask.push_back(j), diag.mask_store_bytes += masks_[j]->bytes();
    }
    stats_.views_changed = changed.size();
    auto view_id = [](std::size_t j) { return static_cast<std::uint16_t>(j); };
    AbrResult a;
    if (incremental_abr_ && abr_ && 2 * changed.size() < std::max<std::size_t>(with_mask.size(), 1)) {
      stats_.abr_incremental = true;
      IncrementalRefinement abr(*scene_, selected, params_.abr(), *abr_);
      MaskDecoder old_decoder;
      for (std::size_t j : changed)
        abr.change_view(cameras_[j], abr_masks_[j] ? &old_decoder.decode(*abr_masks_[j]) : nullptr,
                        masks_[j] ? &decoder_.decode(*masks_[j]) : nullptr, view_id(j));
      const auto cfs = abr.carried_fresh_stale();
      stats_.carried = cfs[0] + cfs[2], stats_.fresh = cfs[1], stats_.stale = cfs[2];
      if (abr.incomplete())
        for (std::size_t j : with_mask) abr.complete_view(cameras_[j], decoder_.decode(*masks_[j]), view_id(j));
      a = abr.finish();
      abr_.emplace(std::move(abr));
    } else {
      stats_.fresh = selected.size();
      BoundaryRefinement abr(*scene_, selected, params_.abr());
      for (std::size_t j : with_mask) abr.add_view(cameras_[j], decoder_.decode(*masks_[j]), view_id(j));
      a = abr.finish();
      abr_.emplace(std::move(abr));
    }
    abr_masks_ = masks_;
    diag.abr_flagged = a.flagged;
    diag.abr_compressed = a.compressed;
    diag.timings_s.emplace_back("abr", detail::seconds_since(ta));
    return std::move(a.log_scale);
  }

  const GaussianScene* scene_;
  std::vector<Camera> cameras_;
  VcarParams params_;
  std::optional<VisibilityVoting> vote_;  // paper presets: the incremental vote (Eq. 1-3)
  std::vector<MaskRef> masks_;      // the masks set, run-length encoded (shared, never changed)
  std::vector<MaskRef> abr_masks_;  // the masks that abr_ saw
  std::optional<AbrState> abr_;  // the latest select()'s refinement (either driver's state)
  std::vector<RenderOutput> renders_;        // robust presets: each training view's render (alpha, depth)
  std::vector<detail::MaskEdit> edits_;      // robust presets: Eq. R11, R12 on each view's mask
  ReselectionStats stats_;
  bool incremental_abr_ = true;
  MaskDecoder decoder_;
};

}  // namespace vcar
