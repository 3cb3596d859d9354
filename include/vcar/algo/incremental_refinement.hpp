#pragma once
// Axis-aware Boundary Refinement, ABR (Eq. 9-14), carried from an earlier refinement (beyond
// the paper; used by Reselection). Eq. 9-13 observe one Gaussian in one view at a time: a
// candidate's state is a sum (n_vis, n_ovf) and a minimum (f_d) over views. So a refinement
// whose candidates mostly match an earlier one's, under masks of which few changed, can start
// from the earlier state:
//  1. the constructor carries `previous`: candidates that it also held take its counts and
//     minima ("carried"); the others start with no view ("fresh");
//  2. change_view(cam, old_mask, new_mask, view) for each view whose mask changed since
//     `previous` saw them (null: no mask): the carried candidates' observation with old_mask is
//     taken back (counts exact in integers) and new_mask's added; a carried minimum that this
//     view set is marked for recomputation (a minimum cannot be taken back);
//  3. complete_view(cam, mask, view) for every view that has a mask now, when incomplete():
//     fresh candidates get the whole observation, marked ones their minima.
// finish() then equals a BoundaryRefinement that saw every current mask (tested bit for bit).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "vcar/algo/abr_kernel.hpp"
#include "vcar/algo/abr_params.hpp"
#include "vcar/algo/abr_state.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar {

class IncrementalRefinement : public AbrState {
 public:
  // `candidates` of `scene` (as AbrState), carrying `previous`, a state of the same scene and
  // parameters (any driver's, e.g. a finished BoundaryRefinement). Throws vcar::Error when
  // `previous` misses views (expect_views, defer_tracing or bound_minimum).
  IncrementalRefinement(const GaussianScene& scene, std::vector<Index> candidates, const AbrParams& params,
                        const AbrState& previous)
      : AbrState(scene, std::move(candidates), params) {
    if (previous.partial_)
      throw Error("a refinement that skips candidates or defers tracing (expect_views, defer_tracing, "
                  "bound_minimum) cannot be carried", "IncrementalRefinement");
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
    if (completing_) throw Error("change_view after complete_view", "IncrementalRefinement");
    auto is_carried = [&](std::size_t k) { return mode_[k] != fresh; };
    if (old_mask) {
      detail::check_abr_view(cam, *old_mask, view);
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
      detail::check_abr_view(cam, *new_mask, view);
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
    detail::check_abr_view(cam, mask, view);
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
  // Candidates carried / fresh / with minima to recompute (after the change_view calls).
  std::array<std::size_t, 3> carried_fresh_stale() const {
    std::array<std::size_t, 3> c{};
    for (std::uint8_t m : mode_) ++c[m];
    return c;
  }

 private:
  enum : std::uint8_t { carried = 0, fresh = 1, stale = 2 };
  void count_modes() {
    wanted_ = 0;
    for (std::uint8_t m : mode_) wanted_ += m != carried;
  }

  std::vector<std::uint8_t> mode_;           // carried / fresh / stale, per slot
  std::size_t wanted_ = 0;                   // slots not carried clean
  bool completing_ = false;                  // complete_view has started
  std::vector<std::uint32_t> wanted_boxes_;  // chunk boxes with fresh or stale slots (completion)
};

}  // namespace vcar
