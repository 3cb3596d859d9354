#pragma once
// The vote of one round (Eq. 1-3, or the robust vote of docs/robust.md) and the vote of one
// view with its mask edits (Eq. R11, R12).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "vcar/algo/decisive_threshold.hpp"
#include "vcar/algo/occlusion_growth.hpp"
#include "vcar/algo/overshoot.hpp"
#include "vcar/algo/params.hpp"
#include "vcar/algo/robust_voting.hpp"
#include "vcar/algo/round.hpp"
#include "vcar/algo/visibility_voting.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar::detail {

// What the fine vote decided (Eq. R7, R6c): the threshold applied (tau_fine or tau_strict),
// whether R7 found the vote split (tau_strict > tau_fine and it kept tau_fine), and whether
// Eq. R6 shaped it (on, and its gate R6c did not find the vote without it decisive).
struct FineVerdict {
  float tau = 0.f;
  bool split = false;
  bool undershoot = false;
};

// The vote of one round: the paper's VisibilityVoting (Eq. 1-3, and the occlusion_aware
// option), or RobustVoting when a mechanism beyond the paper is on (docs/robust.md).
class RoundVote {
public:
  RoundVote(const GaussianScene& scene, const std::vector<Index>* candidates, const VcarParams& p, bool fine)
      : occlusion_(p.occlusion_aware || p.evidence.occlusion),
        overshoot_(p.snap.enabled), grow_(!fine && p.snap.enabled), undershoot_(fine && p.undershoot.band > 0.f) {
    if (p.robust_vote()) {
      // Eq. R6 needs frames rendered from the candidates alone: the fine round's.
      const RobustVoteOptions o{p.evidence.kappa, undershoot_ ? p.undershoot.band : 0.f, p.reliability.enabled};
      if (candidates) robust_.emplace(scene, *candidates, o);
      else robust_.emplace(scene, o);
    } else if (candidates) {
      paper_.emplace(scene, *candidates);
    } else {
      paper_.emplace(scene);
    }
  }
  // The view's render is needed: depth and alpha for Eq. R3, R11 and R12 (wants_depth), alpha
  // for Eq. R6.
  bool wants_render() const { return wants_depth() || undershoot_; }
  bool wants_depth() const { return occlusion_ || overshoot_ || grow_; }
  RenderNeed render_need() const { return {wants_render(), wants_depth()}; }
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

  // One view; `render` when wants_render() (alpha, and depth when wants_depth()).
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
  // Every candidate's ratio (Eq. 3, or Eq. R2-R6 with R6), in candidate order: Eq. R14's histogram.
  void ratios(std::vector<float>& out) const {
    out.resize(robust_ ? robust_->size() : paper_->size());
    if (robust_) for (std::size_t k = 0; k < out.size(); ++k) out[k] = robust_->ratio(k);
    else for (std::size_t k = 0; k < out.size(); ++k) out[k] = paper_->ratio(k);
  }
  // The same with Eq. R7 choosing between tau and tau_strict (> tau; else tau): the verdict.
  // With R6's gate, R7 reads the vote without R6 first: when that vote is decisive it is the
  // result; when it splits, the vote with R6 decides as above (Eq. R6c).
  FineVerdict selected(float tau, float tau_strict, float split, std::vector<Index>& indices,
                       std::vector<float>& scores) const {
    if (undershoot_ && tau_strict > tau && decided(tau, tau_strict, split, indices, scores, false) == tau_strict)
      return {tau_strict, false, false};                                                     // Eq. R6c
    const float applied = decided(tau, tau_strict, split, indices, scores, true);
    return {applied, tau_strict > tau && applied == tau, undershoot_};
  }

private:
  float decided(float tau, float tau_strict, float split, std::vector<Index>& indices, std::vector<float>& scores,
                bool undershoot) const {
    selected(tau, indices, scores, undershoot);
    if (!(tau_strict > tau)) return tau;
    std::vector<Index> strict;
    std::vector<float> strict_scores;
    selected(tau_strict, strict, strict_scores, undershoot);
    if (!decisive_vote(strict.size(), indices.size(), split)) return tau;                   // Eq. R7
    if (robust_) {  // Eq. R7's seen candidates take tau_strict, the rest keep tau
      robust_->selected(tau, tau_strict, seen_fraction, undershoot, indices, scores);
    } else {
      indices = std::move(strict);
      scores = std::move(strict_scores);
    }
    return tau_strict;
  }

  bool occlusion_, overshoot_, grow_, undershoot_;
  std::size_t overshoot_eroded_ = 0, grown_ = 0;
  std::optional<VisibilityVoting> paper_;
  std::optional<RobustVoting> robust_;
};

// Eq. R11 and R12 on one view's mask m, from the view's render (alpha and depth): the mask
// voted, m or the edited copy in `scratch`. With `overshoot` (Eq. R11) a mask that overshoots the
// render's occlusion edges is eroded (an erosion that would take more than three quarters of the
// mask's foreground is not applied: structures thinner than the erosion, or a mask of scattered
// specks, are not what a dilated object looks like); with `grow` (Eq. R12, the coarse round) one
// that stops short of them is grown to them. `edit` says which happened.
enum class MaskEdit { none, eroded, grown };
inline const Mask* edit_mask(const Mask& m, const RenderOutput& render, bool overshoot, bool grow,
                             const VcarParams& params, Mask& scratch, MaskEdit& edit) {
  edit = MaskEdit::none;
  if (!(overshoot || grow) || render.depth.empty()) return &m;
  auto foreground = [](const Mask& x) {
    return static_cast<std::size_t>(std::count_if(x.data.begin(), x.data.end(), [](std::uint8_t v) { return v != 0; }));
  };
  OcclusionEdges edges(render.alpha, render.depth, params.depth_tolerance);  // Eq. R11a, over the boxes read
  const std::array<double, 3> q = overshoot_quartiles_px(m, edges);  // Eq. R11b
  const double o = q[1];
  const OvershootScale scale = OvershootScale::of(m.width, m.height);
  const SnapDirection dir = snap_direction(q, scale.min);
  if (overshoot && dir == SnapDirection::erode) {
    scratch = m;
    erode_by_overshoot(scratch, o + scale.margin);  // Eq. R11c
    if (4 * foreground(scratch) < foreground(m)) return &m;  // thin or scattered masks are kept as they are
    edit = MaskEdit::eroded;
    return &scratch;
  }
  if (grow && dir == SnapDirection::grow) {
    const int reach_px = growth_reach(o, foreground(m), m.width, m.height, grow_max_diagonal, grow_margin_px);  // Eq. R12c
    scratch = m;
    // Eq. R12 reads the edges within twice its reach of the mask (growth_seed_box).
    const std::vector<std::uint8_t>& e = edges.cover(growth_seed_box(m, reach_px));
    if (grow_to_occlusion_edges(scratch, e, render.alpha, render.depth, params.depth_tolerance, reach_px) > 0) {
      edit = MaskEdit::grown;  // Eq. R12b
      return &scratch;
    }
  }
  return &m;
}

// One vote of one view. With the occlusion test (or Eq. R11, R12) the view's expected depth (with
// Eq. R6 alone its alpha) comes from `render` when the round kept it, else it is rendered from
// the same Gaussians the segmenter saw; the mask is edited by Eq. R11, R12 (edit_mask) and the
// edits counted.
// Returns the mask voted (m, &scratch or null): the one the caller keeps for ABR.
template <Renderer R>
const Mask* vote(RoundVote& voting, const Camera& cam, const Mask* m, const RenderOutput* render,
                 const GaussianScene& scene, const std::vector<Index>* subset, R& renderer, const VcarParams& params,
                 Mask& scratch) {
  if (!voting.wants_render() || !m) {
    voting.add_view(cam, m, nullptr, params.depth_tolerance);
    return m;
  }
  RenderOutput own;
  if (!render || (voting.wants_depth() && render->depth.empty())) {
    own = render_view(renderer, scene, cam, subset, Eigen::Vector3f::Zero(), voting.wants_depth());
    render = &own;
  }
  if (render->depth.empty() && voting.occlusion())
    throw Error("the occlusion test needs a renderer that returns depth", "view '" + cam.name + "'");
  MaskEdit edit;
  m = edit_mask(*m, *render, voting.overshoot(), voting.grow(), params, scratch, edit);
  if (edit == MaskEdit::eroded) voting.count_overshoot_eroded();
  if (edit == MaskEdit::grown) voting.count_grown();
  voting.add_view(cam, m, render, params.depth_tolerance);
  return m;
}

}  // namespace vcar::detail
