#pragma once
// Beyond the paper: visibility-based voting that weighs evidence by how reliable it is
// (docs/robust.md, Eq. R1-R6). With edge_band = 0, no depth images and keep_unseen,
// foreshortening and gamma off it is exactly Eq. 1-3 (VisibilityVoting).
//
// Per candidate i and view j where the centre is visible by Eq. 1 at pixel p, three nested
// kinds of evidence, each a pair of uint16 counters (12 bytes per candidate, whatever the
// number of views):
//   plain      (V_i,   F_i)    Eq. 2: visible; foreground if M(p) = 1
//   unoccluded (V^o_i, F^o_i)  Eq. R3: and not behind the view's rendered surface (only views
//                              voted with a depth image can occlude; the others count as is)
//   sure       (V^s_i, F^s_i)  Eq. R1: and p outside the mask's edge band; foreground if p is
//                              sure foreground (with the band off every pixel is sure)
// Eq. R2: each level's ratio is shrunk towards the level below with a prior weight of kappa
// views, so a level seen from one or two views cannot overrule many views of the level below:
//   R^0_i = F_i / max(V_i, 1)                                    (Eq. 3)
//   R^1_i = (F^o_i + kappa R^0_i) / (V^o_i + kappa)
//   R^2_i = (F^s_i + kappa R^1_i) / (V^s_i + kappa),   R_i = R^2_i,   y_i = 1[R_i >= tau].
// (kappa = 0: the most reliable level with a view decides alone.) With the band off and no
// depth images all levels hold the same counts and R_i = F_i / V_i, Eq. 3.
// Two more mechanisms, each an option (RobustVoteOptions):
//   foreshortening (Eq. R5, foreshortening.hpp): the unoccluded and sure levels sum the weight
//                   omega_ij of each view (how face-on it sees the Gaussian) instead of counting
//                   views: V^o_i = sum omega_ij, F^o_i = sum omega_ij M(p), and so for the sure
//                   level; 16 more bytes per candidate for the sums, 16 for phi_i n_i, 1 - phi_i;
//   gamma (Eq. R6, undershoot.hpp): in a round whose frames are renders of the candidates, the
//                   background pixels within max(w_j, gamma e_j) of the mask are unsure, e_j the
//                   mask's undershoot measured against the render's alpha. Such a vote also
//                   holds its sure level without R6's widening (R1's band alone; the unoccluded
//                   level itself when the band is off, at no cost), so that Eq. R7 can read the
//                   vote as it would be without R6 (R6's gate, docs/robust.md): ratio(k, false);
//                   4 more bytes per candidate (12 with R5) when R1 and R6 are both on.
// Two exceptions, each a switch of selected():
//   undecided_kept: a Gaussian seen unoccluded but only inside bands (V^o > 0 = V^s) is kept
//                   (the coarse round passes it on to the fine round, which decides);
//   keep_unseen (Eq. R4): a candidate that no view of the round sees (V = 0) keeps the
//                   decision of the round that made it a candidate.
// Views are voted one at a time over all candidates in parallel chunks; each candidate is
// written by one thread, so results are identical for any thread count.
#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/edge_band.hpp"
#include "vcar/algo/foreshortening.hpp"
#include "vcar/algo/mean_projection.hpp"
#include "vcar/algo/undershoot.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar {

// The mechanisms of RobustVoting (each off by default; VcarParams carries them).
struct RobustVoteOptions {
  float beta = 0.f;             // Eq. R1a: band factor (0 = off)
  float kappa = 2.f;            // Eq. R2: prior weight in views
  bool foreshortening = false;  // Eq. R5: views weighted by how face-on they see the Gaussian
  float gamma = 0.f;            // Eq. R6: outer band reach factor on the undershoot (0 = off)
};

class RobustVoting {
public:
  static constexpr std::size_t max_views = 65535;  // uint16_t counters
  std::size_t chunk = 4096;                        // candidates per parallel task (fixed)

  // Every Gaussian of `scene` is a candidate (means referenced: the scene must outlive this).
  // The (beta, kappa) forms are the options with R5 and R6 off.
  RobustVoting(const GaussianScene& scene, const RobustVoteOptions& o) : o_(o) {
    init(scene, scene.mean[0].data(), scene.mean[1].data(), scene.mean[2].data(), scene.size());
  }
  RobustVoting(const GaussianScene& scene, float beta, float kappa = 2.f)
      : RobustVoting(scene, RobustVoteOptions{beta, kappa}) {}
  // The Gaussians `candidates` of `scene` (scene indices, any order; means copied).
  RobustVoting(const GaussianScene& scene, std::vector<Index> candidates, const RobustVoteOptions& o)
      : o_(o), candidates_(std::move(candidates)) {
    own_ = detail::candidate_means(scene, candidates_);
    init(scene, own_[0].data(), own_[1].data(), own_[2].data(), candidates_.size());
  }
  RobustVoting(const GaussianScene& scene, std::vector<Index> candidates, float beta, float kappa = 2.f)
      : RobustVoting(scene, std::move(candidates), RobustVoteOptions{beta, kappa}) {}
  RobustVoting(const RobustVoting&) = delete;
  RobustVoting& operator=(const RobustVoting&) = delete;

  // One view. mask null: no evidence (conventions §4). expected_depth and alpha (W x H, one
  // channel; the view's render of the Gaussians the segmenter saw): Eq. R3 with `tolerance`, and
  // Eq. R6 (gamma > 0) when that render is of the candidates alone.
  void add_view(const Camera& camera, const Mask* mask, const ImageF* expected_depth = nullptr,
                const ImageF* alpha = nullptr, float tolerance = 0.f) {
    if (!mask) return;
    const std::string where = "view '" + camera.name + "'";
    if (mask->width != camera.width || mask->height != camera.height || mask->channels != 1)
      throw Error("mask is " + std::to_string(mask->width) + "x" + std::to_string(mask->height) + ", view is " +
                  std::to_string(camera.width) + "x" + std::to_string(camera.height), where);
    if (expected_depth && !alpha) throw Error("the depth image needs the alpha image of the same render", where);
    for (const ImageF* im : {expected_depth, alpha})
      if (im && (im->width != camera.width || im->height != camera.height || im->channels != 1))
        throw Error("depth/alpha image is not the view's size with one channel", where);
    if (views_ + 1 > max_views) throw Error("more than 65535 views with masks (uint16_t counters)", where);
    ++views_;
    const std::uint8_t* sure_fg = mask->data.data();
    const std::uint8_t* sure = nullptr;  // null: every pixel is sure
    const std::uint8_t* sure_band = nullptr;  // R1's band alone, when R6 widens it (c1_ held)
    if (!(o_.kappa >= 0.f)) throw Error("kappa must be >= 0", "voting");
    int w = 0;
    if (o_.beta > 0.f) {
      std::size_t fg = 0;
      for (std::uint8_t b : mask->data) fg += b != 0;
      w = edge_band_width(fg, o_.beta);
      edge_band(*mask, w, band_, scratch_);
      sure_fg = band_.sure_foreground.data.data();
      sure = band_.sure.data.data();
    }
    const bool band_level = !c1_[0].empty();
    if (band_level) sure_band = sure;
    if (o_.gamma > 0.f && alpha) {
      last_undershoot_ = undershoot_px(*mask, *alpha);                                     // Eq. R6a
      const double reach = std::max<double>(w, o_.gamma * last_undershoot_);               // Eq. R6b
      if (reach > w) {
        if (sure) outer_.assign(sure, sure + mask->data.size());
        else outer_.assign(mask->data.size(), 255);
        widen_outer_band(*mask, reach, outer_);
        sure = outer_.data();
      }
    }
    const detail::MeanProjection P = detail::MeanProjection::from(camera);
    const std::uint8_t* M = mask->data.data();
    const float* D = expected_depth ? expected_depth->data.data() : nullptr;
    const float* A = alpha ? alpha->data.data() : nullptr;
    const float scale = 1.f + tolerance;
    const bool weighted = o_.foreshortening;
    const Eigen::Vector3f C = camera.position();
    parallel_chunks(static_cast<std::int64_t>(n_), static_cast<std::int64_t>(chunk),
                    [&](std::int64_t, std::int64_t b, std::int64_t e) {
      constexpr std::size_t L = detail::mean_batch;
      alignas(64) std::int32_t pix[L], vis[L];
      alignas(64) float z[L];
      for (std::size_t i0 = static_cast<std::size_t>(b); i0 < static_cast<std::size_t>(e); i0 += L) {
        const std::size_t m = std::min(L, static_cast<std::size_t>(e) - i0);
        if (m == L) detail::project_batch(P, x_ + i0, y_ + i0, z_ + i0, pix, vis, z);
        else detail::project_tail(P, x_ + i0, y_ + i0, z_ + i0, m, pix, vis, z);
        for (std::size_t l = 0; l < m; ++l) {
          if (!vis[l]) continue;
          const std::size_t i = i0 + l, p = static_cast<std::size_t>(pix[l]);
          const std::uint16_t f = M[p] != 0;
          ++c_[0][i]; c_[1][i] = static_cast<std::uint16_t>(c_[1][i] + f);                  // Eq. 2
          if (D && A[p] >= 0.5f && !(z[l] <= D[p] / A[p] * scale)) continue;                  // Eq. R3
          ++c_[2][i]; c_[3][i] = static_cast<std::uint16_t>(c_[3][i] + f);
          const float omega = weighted ? fs_.weight(i, x_[i], y_[i], z_[i], C) : 1.f;        // Eq. R5
          if (weighted) { w_[0][i] += omega; w_[1][i] += f ? omega : 0.f; }
          if (band_level && (!sure_band || sure_band[p])) {                                    // Eq. R1 alone
            const std::uint16_t g = sure_fg[p] != 0;
            ++c1_[0][i]; c1_[1][i] = static_cast<std::uint16_t>(c1_[1][i] + g);
            if (weighted) { w1_[0][i] += omega; w1_[1][i] += g ? omega : 0.f; }
          }
          if (sure && !sure[p]) continue;                                                      // Eq. R1, R6b
          ++c_[4][i]; c_[5][i] = static_cast<std::uint16_t>(c_[5][i] + (sure_fg[p] != 0));
          if (weighted) { w_[2][i] += omega; w_[3][i] += sure_fg[p] != 0 ? omega : 0.f; }
        }
      }
    });
  }

  std::size_t size() const noexcept { return n_; }
  std::size_t views() const noexcept { return views_; }
  Index candidate(std::size_t k) const { return candidates_.empty() ? static_cast<Index>(k) : candidates_[k]; }
  // Counters of candidate k: level 0 plain (V, F), 1 unoccluded (V^o, F^o), 2 sure (V^s, F^s).
  std::uint16_t visible(std::size_t k, int level = 0) const { return c_[2 * level][k]; }
  std::uint16_t foreground(std::size_t k, int level = 0) const { return c_[2 * level + 1][k]; }
  // V^o of every candidate (level 1), aligned with the candidates.
  std::span<const std::uint16_t> unoccluded_views() const { return c_[2]; }
  // Eq. R5 sums of candidate k at level 1 (unoccluded) or 2 (sure); 0 without foreshortening.
  float weight(std::size_t k, int level) const { return o_.foreshortening ? w_[2 * level - 2][k] : 0.f; }
  float weighted_foreground(std::size_t k, int level) const { return o_.foreshortening ? w_[2 * level - 1][k] : 0.f; }
  // Eq. R6a of the latest view voted with gamma > 0 and a render (px).
  double last_undershoot_px() const noexcept { return last_undershoot_; }

  // Eq. R2 (Eq. 3 at level 0), with Eq. R5's sums at levels 1-2 when foreshortening is on.
  // undershoot = false: the sure level without Eq. R6's widening (the vote R6's gate reads).
  float ratio(std::size_t k, bool undershoot = true) const {
    float R = static_cast<float>(foreground(k)) / static_cast<float>(std::max<std::uint16_t>(visible(k), 1));
    // While R is the plain ratio of counts equal to this level's, the shrunk value equals R
    // exactly ((F + kappa F/V) / (V + kappa) = F/V): keep R bit for bit instead of rounding it
    // again (FMA or not), so Eq. 3 comes out identical whenever the mechanisms add nothing.
    bool plain = true;
    const float kappa = o_.kappa;
    for (int level = 1; level <= 2; ++level) {
      const bool own = level == 2 && !undershoot && o_.gamma > 0.f;  // R6 off: R1's band alone
      const int at = own && c1_[0].empty() ? 1 : level;                 // band off: level 1's counts
      if (o_.foreshortening) {
        const bool band = own && at == 2;
        const float V = band ? w1_[0][k] : weight(k, at), F = band ? w1_[1][k] : weighted_foreground(k, at);
        if (V + kappa > 0.f) R = (F + kappa * R) / (V + kappa);
        continue;
      }
      const std::uint16_t Vc = own && at == 2 ? c1_[0][k] : visible(k, at);
      const std::uint16_t Fc = own && at == 2 ? c1_[1][k] : foreground(k, at);
      if (plain && Vc == visible(k) && Fc == foreground(k)) continue;
      plain = false;
      const float V = static_cast<float>(Vc), F = static_cast<float>(Fc);
      if (V + kappa > 0.f) R = (F + kappa * R) / (V + kappa);
    }
    return R;
  }
  // Eq. 3 / R2 / R4 for candidate k (the switches as at the top of the file).
  // undershoot = false: as ratio(k, false).
  bool kept(std::size_t k, float tau, bool undecided_kept, bool keep_unseen, bool undershoot = true) const {
    if (keep_unseen && visible(k) == 0) return true;
    const bool own = !undershoot && o_.gamma > 0.f && !c1_[0].empty();
    if (undecided_kept && o_.beta > 0.f && (own ? c1_[0][k] : visible(k, 2)) == 0 && visible(k, 1) > 0) return true;
    return ratio(k, undershoot) >= tau;
  }
  // Scene indices (ascending) of the kept candidates, and their R_i (undershoot as in ratio()).
  void selected(float tau, bool undecided_kept, bool keep_unseen, std::vector<Index>& indices,
                std::vector<float>& scores, bool undershoot = true) const {
    std::vector<std::pair<Index, float>> out;
    for (std::size_t k = 0; k < n_; ++k)
      if (kept(k, tau, undecided_kept, keep_unseen, undershoot)) out.push_back({candidate(k), ratio(k, undershoot)});
    std::sort(out.begin(), out.end());
    indices.clear();
    scores.clear();
    for (const auto& [i, r] : out) { indices.push_back(i); scores.push_back(r); }
  }

private:
  void init(const GaussianScene& scene, const float* x, const float* y, const float* z, std::size_t n) {
    x_ = x; y_ = y; z_ = z; n_ = n;
    for (auto& c : c_) c.assign(n, 0);
    if (o_.foreshortening) {
      fs_ = Foreshortening::of(scene, candidates_);
      for (auto& c : w_) c.assign(n, 0.f);
    }
    if (o_.gamma > 0.f && o_.beta > 0.f) {  // R6 widens R1's band: keep R1's alone too
      for (auto& c : c1_) c.assign(n, 0);
      if (o_.foreshortening)
        for (auto& c : w1_) c.assign(n, 0.f);
    }
  }

  RobustVoteOptions o_;
  const float *x_ = nullptr, *y_ = nullptr, *z_ = nullptr;
  std::size_t n_ = 0, views_ = 0;
  std::vector<Index> candidates_;
  std::array<std::vector<float>, 3> own_;
  std::array<std::vector<std::uint16_t>, 6> c_;  // V, F, V^o, F^o, V^s, F^s
  Foreshortening fs_;
  std::array<std::vector<float>, 4> w_;  // Eq. R5: weighted V^o, F^o, V^s, F^s
  std::array<std::vector<std::uint16_t>, 2> c1_;  // V^s, F^s with R1's band alone (R6 on, band on)
  std::array<std::vector<float>, 2> w1_;          // their Eq. R5 sums
  EdgeBandMasks band_;
  std::vector<std::uint8_t> outer_;      // Eq. R6b: the sure plane with the widened outer band
  double last_undershoot_ = 0;
  std::vector<std::uint32_t> scratch_;
};

}  // namespace vcar
