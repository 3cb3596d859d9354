#pragma once
// vcar::segment: the coarse-to-fine pipeline of Sec. 3.1. It only composes the stages:
//   coarse VWV on the training views (Eq. 1-3)
//   -> robust object sphere (Eq. 4-5) -> view completeness (Eq. 6, A.1-A.2)
//   -> if Delta_max > Delta_th: SSS views (Eq. 7-8) rendered from G_coarse only, segmented with
//      the training views rendered from G_coarse, fine VWV over V_train u V_sampled
//   -> ABR (Eq. 9-14, B) on the training views' masks of the latest round.
// Masks are streamed: each is voted on as the segmenter delivers it and then dropped; the
// training views' masks that ABR needs later are kept run-length encoded (O(boundary) bytes).
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "vcar/algo/diagnostics.hpp"
#include "vcar/algo/object_refinement.hpp"
#include "vcar/algo/params.hpp"
#include "vcar/algo/round.hpp"
#include "vcar/algo/round_vote.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/rle_mask.hpp"

namespace vcar {

namespace detail {  // vcar::detail
// The end of a coarse round, shared by vcar::segment and vcar::segment_objects: the round's mask
// edits counted (Eq. R11, R12), its views weighed by their agreement (Eq. R13), and G_coarse
// selected at tau_coarse (Eq. 3, or the robust vote's R2, R3, R13) with its scores.
inline void coarse_selection(RoundVote& coarse, const VcarParams& params, Diagnostics& diag,
                             std::vector<Index>& selected, std::vector<float>& scores) {
  diag.overshoot_eroded = coarse.overshoot_eroded();
  diag.masks_grown = coarse.grown();
  coarse.weigh_views(params.tau_coarse);  // Eq. R13
  coarse.selected(params.tau_coarse, selected, scores);
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
  // with the robust vote, Eq. R2, R3, R11-R13).
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
      }, diag.masks_missing, coarse.render_need());
  timing("coarse_render", t1.render);
  timing("coarse_segment", t1.total - t1.render - t1.voting);
  timing("coarse_voting", setup + t1.voting);
  std::vector<Index> selected;  // G_coarse (Eq. 3 at tau_coarse)
  std::vector<float> scores;
  detail::coarse_selection(coarse, params, diag, selected, scores);
  const bool complete = detail::refine(
      scene, train_cameras, prompt, renderer, segmenter, params, progress, t_start, train_masks, std::move(selected),
      std::move(scores), result, "fine round");
  timing("total", seconds_since(t_start));
  if (complete) stage("done");
  return result;
}

}  // namespace vcar
