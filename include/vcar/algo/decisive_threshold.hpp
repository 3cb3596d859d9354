#pragma once
// Beyond the paper: the fine round's threshold follows the split of its own vote (docs/robust.md,
// Eq. R7).
//
// The paper's tau_fine = 0.8 rejects the Gaussians that the masks of some views leave out: the
// background next to a contact with a neighbour, or under the object, which Eq. 1 lets through
// in the coarse round. It is also what empties the fine vote when the masks undershoot: then
// every surface Gaussian of the object is outside the mask in the views that see it edge-on and
// its ratio R_i spreads over [0.5, 1]. Which of the two a scene shows can be read off the vote:
// with N(t) the number of candidates kept at threshold t (Eq. 3),
//   tau* = tau_strict   if N(tau_strict) >= (1 - s) N(tau_fine)                    (Eq. R7)
//   tau* = tau_fine     otherwise
// A decisive vote (at most a fraction s of the majority's Gaussians between the two thresholds:
// masks that agree across views) takes the strict threshold; a split vote (masks that disagree
// systematically, as an undershooting segmenter's do) keeps the majority. With
// tau_strict <= tau_fine (0 = off: every paper preset) tau* = tau_fine. O(candidates) once.
//
// In a decisive vote the strict threshold is for the candidates the round has seen: with V_i
// the views that voted on candidate i and V^o_i those of them that saw it unoccluded (Eq. R3),
//   tau*_i = tau_strict  if V^o_i >= f V_i,   tau_fine otherwise                  (Eq. R7)
// A neighbour's surface that some masks take in is seen from many views and sits between the
// two thresholds (the table inside a donut's hole, GrabCut's leaks); the object's own hidden
// back and underside, and its soft fringe, are seen from few views and sit there too (their
// R_i falls back on the plain level, Eq. R2). f = 0.2 (seen_fraction, a constant, chosen on
// the field's tuning seeds: docs/robust.md, R7). Without the occlusion test every candidate
// counts as seen (V^o_i = V_i): the global rule.
#include <cstddef>

namespace vcar {

// Eq. R7's s: the largest fraction of the majority's Gaussians between the two thresholds in a
// decisive vote.
inline constexpr float split_fraction = 0.1f;

// Eq. R7's f: the smallest fraction of a candidate's views that see it unoccluded for the strict
// threshold to apply to it in a decisive vote.
inline constexpr float seen_fraction = 0.2f;

// Eq. R7: true when the vote is decisive, i.e. n_strict (kept at tau_strict) >= (1 - split)
// n_majority (kept at tau_fine); split in [0, 1].
inline bool decisive_vote(std::size_t n_strict, std::size_t n_majority, float split) noexcept {
  return static_cast<double>(n_strict) >= (1.0 - static_cast<double>(split)) * static_cast<double>(n_majority);
}

}  // namespace vcar
