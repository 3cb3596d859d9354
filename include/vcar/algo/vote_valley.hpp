#pragma once
// Beyond the paper: the fine round's threshold read from its own vote (docs/robust.md, Eq. R14).
//
// Eq. 3 keeps a candidate when R_i >= tau_fine, one number for every scene. Masks fail in two
// opposite ways, and the fine vote shows which (docs/notes/field-valley-2026-12-06.md):
// - masks that take in a neighbour (GrabCut's colour leaks): the object is a spike of ratios
//   near 1 and the neighbour's Gaussians spread below it; a high threshold is right;
// - masks that miss part of the object on some frames (a wrong or drifting frame): the
//   object's ratios spread over [0.5, 1] around their mode and G_coarse holds little else; a
//   threshold as low as tau_coarse is right.
// Eq. R14 puts the threshold where the fine vote's ratio histogram is emptiest between
// tau_coarse and its fullest bin. With B = 20 bins of width w = 1 / B over [0, 1] (R_i = 1 in
// the last), h_b the number of candidates in bin b and s_b = h_{b-1} + h_b + h_{b+1} (the bins
// outside [0, B) empty), b_0 the first bin whose lower edge is at least tau_coarse:
//   m    = argmax_{b >= b_0} h_b                        (ties: the lowest b)
//   tau* = tau_coarse                                   if m = b_0
//   tau* = (v + 1/2) w,  v = argmin_{b_0 <= b < m} s_b  (ties: the lowest b)   otherwise
// and the fine round keeps R_i >= tau*, or R7's strict threshold where the vote is decisive
// against tau* (decisive_threshold.hpp). Only where the round's masks measurably undershoot
// (masks_undershoot, undershoot.hpp) or the vote is spread (vote_spread: most candidates above
// tau_coarse below the top bin, no spike at 1): a neighbour that masks take in on some frames
// and not on others spreads its ratios up to the object's spike as an undershoot spreads the
// object's own, and where the object is a spike only the masks' measured undershoot tells the
// two apart (ISNet's guitar, docs/notes/field-valley-2026-12-06.md); masks that drift leave no
// spike and a median undershoot of about 0 (docs/notes/field-stage-apart-2026-12-06.md). A bin
// at the valley's centre splits it: the histogram cannot place the threshold more finely than
// its bins. O(candidates) once.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "vcar/core/error.hpp"

namespace vcar {

// Eq. R14's B: bins of the ratio histogram over [0, 1].
inline constexpr std::size_t valley_bins = 20;

// Eq. R14's histogram of the ratios `r` (each in [0, 1]) and b_0, the first bin whose lower edge
// is at least `lo` (tau_coarse; b_0 = B when lo > (B - 1) / B).
struct VoteHistogram {
  std::array<std::size_t, valley_bins> h{};
  std::size_t b0 = 0;
  float lo = 0.f;
};
inline VoteHistogram vote_histogram(std::span<const float> r, float lo, const char* who) {
  if (!(lo >= 0.f && lo <= 1.f)) throw Error("the lower bound must be in [0, 1]", who);
  constexpr std::size_t B = valley_bins;
  VoteHistogram v;
  for (const float x : r) {
    if (!(x >= 0.f && x <= 1.f)) throw Error("a ratio outside [0, 1]", who);
    ++v.h[std::min(static_cast<std::size_t>(x * static_cast<float>(B)), B - 1)];
  }
  // The lower edge b_0 / B is at least lo (1e-4 absorbs lo * B's rounding: 0.5 -> bin 10).
  v.b0 = std::min(B, static_cast<std::size_t>(std::ceil(static_cast<double>(lo) * B - 1e-4)));
  v.lo = lo;
  return v;
}

// Eq. R14: the fine threshold of the ratios `r` (each in [0, 1]), at least `lo` (tau_coarse).
inline float vote_valley(const VoteHistogram& hist) {
  constexpr std::size_t B = valley_bins;
  const auto& h = hist.h;  // a reference, not a structured binding: lambdas capture it (clang)
  const std::size_t b0 = hist.b0;
  const float lo = hist.lo;
  if (b0 >= B) return lo;
  std::size_t m = b0;
  for (std::size_t b = b0 + 1; b < B; ++b)
    if (h[b] > h[m]) m = b;
  if (m == b0) return lo;
  auto s = [&](std::size_t b) { return (b > 0 ? h[b - 1] : 0) + h[b] + (b + 1 < B ? h[b + 1] : 0); };
  std::size_t v = b0;
  for (std::size_t b = b0 + 1; b < m; ++b)
    if (s(b) < s(v)) v = b;
  return (static_cast<float>(v) + 0.5f) / static_cast<float>(B);
}
inline float vote_valley(std::span<const float> r, float lo) { return vote_valley(vote_histogram(r, lo, "vote_valley")); }

// Eq. R14's second gate: the vote is spread when fewer than half of the candidates at or above
// bin b_0 lie in the top bin (the median of those ratios is below (B - 1) / B = 0.95):
//   2 h_{B-1} < sum_{b >= b_0} h_b                                               (R14's spread)
// False when no candidate reaches b_0.
inline bool vote_spread(const VoteHistogram& hist) {
  constexpr std::size_t B = valley_bins;
  const auto& h = hist.h;
  const std::size_t b0 = hist.b0;
  std::size_t above = 0;
  for (std::size_t b = b0; b < B; ++b) above += h[b];
  return b0 < B && 2 * h[B - 1] < above;
}
inline bool vote_spread(std::span<const float> r, float lo) { return vote_spread(vote_histogram(r, lo, "vote_spread")); }

}  // namespace vcar
