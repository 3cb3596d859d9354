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
// State: the voter (Morton-sorted means and counters, ~20 bytes per Gaussian) and the masks
// run-length encoded (O(boundary) bytes each). The vote is the paper's (Eq. 1-3): parameters
// whose vote needs renders (edge band, occlusion tests, keep_unseen) are refused.
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/pipeline.hpp"

namespace vcar {

class Reselection {
public:
  // The scene is referenced (it must outlive this object); cameras and params are copied.
  Reselection(const GaussianScene& scene, std::vector<Camera> cameras, VcarParams params = VcarParams::nvos())
      : scene_(&scene), cameras_(std::move(cameras)), params_(params), vote_(scene), masks_(cameras_.size()) {
    params_.validate();
    if (params_.robust_vote())
      throw Error("re-selection votes with Eq. 1-3 only; edge_band, coarse/fine_occlusion and keep_unseen need "
                  "renders (use a paper preset such as VcarParams::nvos(), or vcar::segment)", "Reselection");
    if (params_.occlusion_aware) throw Error("occlusion_aware needs renders (use vcar::segment)", "Reselection");
    if (scene.empty()) throw Error("the scene has no Gaussians", "scene");
    if (cameras_.empty()) throw Error("no training cameras", "cameras");
    for (const Camera& c : cameras_) c.validate();
  }

  std::size_t views() const noexcept { return cameras_.size(); }
  // Views that currently have a mask.
  std::size_t masks() const noexcept { return vote_.views(); }

  // Sets, replaces or (mask null) clears the mask of training view `view`. A mask at or below
  // min_mask_fraction counts as none (conventions §7). Throws vcar::Error naming the view for an
  // index out of range or a mask of another size.
  void set_mask(std::size_t view, const Mask* mask) {
    if (view >= cameras_.size())
      throw Error("view " + std::to_string(view) + " out of range (" + std::to_string(cameras_.size()) + " views)",
                  "Reselection");
    const Camera& cam = cameras_[view];
    if (mask && (mask->width != cam.width || mask->height != cam.height || mask->channels != 1))
      throw Error("mask is " + std::to_string(mask->width) + "x" + std::to_string(mask->height) + "x" +
                      std::to_string(mask->channels) + ", the view is " + std::to_string(cam.width) + "x" +
                      std::to_string(cam.height) + "x1", "view '" + cam.name + "'");
    mask = detail::usable(mask, params_);
    if (masks_[view]) {  // take back the old mask's votes
      masks_[view]->decode(scratch_);
      vote_.remove_view(cam, &scratch_);
      masks_[view].reset();
    }
    if (!mask) return;
    vote_.add_view(cam, mask);
    masks_[view] = RleMask::encode(*mask);
  }

  // The selection for the masks set so far (reference view: the sphere's fallback centre, A.1).
  SegmentationResult select(std::size_t reference_view = 0) const {
    if (reference_view >= cameras_.size())
      throw Error("reference view " + std::to_string(reference_view) + " out of range", "Reselection");
    const auto t0 = detail::Clock::now();
    SegmentationResult result;
    Diagnostics& diag = result.diagnostics;
    diag.n_scene = scene_->size();
    diag.masks_missing = cameras_.size() - vote_.views();
    auto tv = detail::Clock::now();
    std::vector<Index> selected = vote_.selected(params_.tau_coarse);  // Eq. 3
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
    result.log_scale = detail::refine_boundaries(*scene_, selected, cameras_, masks_, params_, diag);
    result.scores.reserve(selected.size());
    for (Index i : selected) result.scores.push_back(vote_.ratio_of(i));
    result.indices = std::move(selected);
    diag.timings_s.emplace_back("total", detail::seconds_since(t0));
    return result;
  }

private:
  const GaussianScene* scene_;
  std::vector<Camera> cameras_;
  VcarParams params_;
  VisibilityVoting vote_;
  std::vector<std::optional<RleMask>> masks_;  // the masks set, run-length encoded
  mutable Mask scratch_;
};

}  // namespace vcar
