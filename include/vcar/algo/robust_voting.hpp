#pragma once
// Beyond the paper: visibility-based voting that weighs evidence by how reliable it is
// (docs/robust.md, Eq. R2-R13). With no depth images, gamma 0 and reliability off it is
// exactly Eq. 1-3 (VisibilityVoting).
//
// Per candidate i and view j where the centre is visible by Eq. 1 at pixel p, up to three nested
// kinds of evidence, each a pair of uint16 counters:
//   plain      (V_i,   F_i)    Eq. 2: visible; foreground if M(p) = 1
//   unoccluded (V^o_i, F^o_i)  Eq. R3: and not behind the view's rendered surface (only views
//                              voted with a depth image can occlude; the others count as is)
//   sure       (V^s_i, F^s_i)  Eq. R6: and p not in the outer band of a mask that undershoots
//                              the render of the candidates (held only when gamma > 0)
// Eq. R2: a level whose counts differ from the level below's is shrunk towards that level's
// ratio with a prior weight of kappa views, so a level seen from one or two views cannot
// overrule many views of the level below; a level that holds the same views adds no evidence
// and is not shrunk again:
//   R^0_i = F_i / max(V_i, 1)                                    (Eq. 3)
//   R^1_i = (F^o_i + kappa R^0_i) / (V^o_i + kappa)   if (V^o_i, F^o_i) != (V_i, F_i), else R^0_i
//   R^2_i = (F^s_i + kappa R^1_i) / (V^s_i + kappa)   if (V^s_i, F^s_i) != (V^o_i, F^o_i), else R^1_i
//   R_i = R^2_i,   y_i = 1[R_i >= tau].
// (kappa = 0: the most reliable level with a view decides alone.) With no depth images and
// gamma 0 every level holds the same counts and R_i = F_i / V_i exactly: Eq. 3.
// Two more mechanisms, each an option (RobustVoteOptions):
//   gamma (Eq. R6, undershoot.hpp): in a round whose frames are renders of the candidates, the
//                   background pixels within gamma e_j of the mask are unsure, e_j the mask's
//                   undershoot measured against the render's alpha. ratio(k, false) reads the
//                   vote without R6 (R^1: what R6's gate, Eq. R6c, decides on);
//   reliability (Eq. R13, view_reliability.hpp): after the round, weigh_views(tau) weighs each
//                   view by how its mask agrees with the round's consensus, and the unoccluded
//                   level sums r_j instead of counting views; two bits
//                   per candidate and view.
// Views are voted one at a time over all candidates in parallel chunks; each candidate is
// written by one thread, so results are identical for any thread count.
#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/mean_projection.hpp"
#include "vcar/algo/undershoot.hpp"
#include "vcar/algo/view_reliability.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar {

// The mechanisms of RobustVoting (each off by default; VcarParams carries them).
struct RobustVoteOptions {
  float kappa = 2.f;            // Eq. R2: prior weight in views
  float gamma = 0.f;            // Eq. R6: outer band reach factor on the undershoot (0 = off)
  bool reliability = false;     // Eq. R13: views weighted by their agreement with the consensus
};

class RobustVoting {
public:
  static constexpr std::size_t max_views = 65535;  // uint16_t counters
  std::size_t chunk = 4096;                        // candidates per parallel task (fixed)

  // Every Gaussian of `scene` is a candidate (means referenced: the scene must outlive this).
  explicit RobustVoting(const GaussianScene& scene, const RobustVoteOptions& o = {}) : o_(o) {
    init(scene.mean[0].data(), scene.mean[1].data(), scene.mean[2].data(), scene.size());
  }
  // The Gaussians `candidates` of `scene` (scene indices, any order; means copied).
  RobustVoting(const GaussianScene& scene, std::vector<Index> candidates, const RobustVoteOptions& o = {})
      : o_(o), candidates_(std::move(candidates)) {
    own_ = detail::candidate_means(scene, candidates_);
    init(own_[0].data(), own_[1].data(), own_[2].data(), candidates_.size());
  }
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
    if (!(o_.kappa >= 0.f)) throw Error("kappa must be >= 0", "voting");
    if (o_.reliability && chunk % 64 != 0) throw Error("chunk must be a multiple of 64 with reliability", "voting");
    ++views_;
    weighed_ = false;
    if (o_.reliability) rel_.add_view();
    const std::uint8_t* sure = nullptr;  // null: every pixel is sure
    if (sure_level() && alpha) {
      last_undershoot_ = undershoot_px(*mask, *alpha);                                     // Eq. R6a
      const double reach = o_.gamma * last_undershoot_;                                    // Eq. R6b
      if (reach > 0.0) {
        outer_.assign(mask->data.size(), 255);
        widen_outer_band(*mask, reach, outer_);
        sure = outer_.data();
      }
    }
    const bool sure_counts = sure_level();
    const detail::MeanProjection P = detail::MeanProjection::from(camera);
    const std::uint8_t* M = mask->data.data();
    const float* D = expected_depth ? expected_depth->data.data() : nullptr;
    const float* A = alpha ? alpha->data.data() : nullptr;
    const float scale = 1.f + tolerance;
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
          if (o_.reliability) rel_.see(i, f != 0);                                            // Eq. R13
          if (!sure_counts || (sure && !sure[p])) continue;                                    // Eq. R6b
          ++c_[4][i]; c_[5][i] = static_cast<std::uint16_t>(c_[5][i] + f);
        }
      }
    });
  }

  std::size_t size() const noexcept { return n_; }
  std::size_t views() const noexcept { return views_; }
  Index candidate(std::size_t k) const { return candidates_.empty() ? static_cast<Index>(k) : candidates_[k]; }
  // Counters of candidate k: level 0 plain (V, F), 1 unoccluded (V^o, F^o), 2 sure (V^s, F^s;
  // the unoccluded level's without R6).
  std::uint16_t visible(std::size_t k, int level = 0) const { return c_[2 * at(level)][k]; }
  std::uint16_t foreground(std::size_t k, int level = 0) const { return c_[2 * at(level) + 1][k]; }
  // V^o of every candidate (level 1), aligned with the candidates.
  std::span<const std::uint16_t> unoccluded_views() const { return c_[2]; }
  // Eq. R13: weighs the views voted so far by their agreement with the consensus at `tau`
  // (first the unweighted vote's, then the weighted one's, `iterations` times); the unoccluded
  // level then sums the weights. No effect without the reliability option. Returns r_j.
  const std::vector<float>& weigh_views(float tau, int iterations = 2) {
    if (!o_.reliability) return view_weights_;
    weighed_ = false;
    for (int it = 0; it < iterations; ++it) {
      const auto consensus = rel_.bits([&](std::size_t k) { return ratio(k) >= tau; });
      view_weights_ = rel_.agreement(consensus);                                             // Eq. R13a
      rel_.weighted(view_weights_, rv_, rf_);                                                // Eq. R13b
      weighed_ = true;
    }
    return view_weights_;
  }
  // Eq. R6a of the latest view voted with gamma > 0 and a render (px).
  double last_undershoot_px() const noexcept { return last_undershoot_; }

  // Eq. R2 (Eq. 3 at level 0), with Eq. R13b's sums at level 1 once the views are weighed.
  // undershoot = false: the vote without Eq. R6 (R^1, what R6's gate reads).
  float ratio(std::size_t k, bool undershoot = true) const {
    // A level with the same counts as the one below adds no evidence: R stays what it was, bit
    // for bit (so Eq. 3 comes out identical whenever the mechanisms add nothing). Once R13
    // weighed the views the unoccluded level always sums them, so it always shrinks.
    float R = static_cast<float>(foreground(k)) / static_cast<float>(std::max<std::uint16_t>(visible(k), 1));
    const int top = undershoot && sure_level() ? 2 : 1;
    for (int level = 1; level <= top; ++level) {
      const bool same = visible(k, level) == visible(k, level - 1) && foreground(k, level) == foreground(k, level - 1);
      const bool weighed = weighed_ && level == 1;  // Eq. R13b
      if (same && !weighed) continue;
      float V = static_cast<float>(visible(k, level));
      float F = static_cast<float>(foreground(k, level));
      if (weighed) V = rv_[k], F = rf_[k];
      if (V + o_.kappa > 0.f) R = (F + o_.kappa * R) / (V + o_.kappa);                    // Eq. R2
    }
    return R;
  }
  // Eq. 3 / R2 for candidate k (undershoot as in ratio()).
  bool kept(std::size_t k, float tau, bool undershoot = true) const { return ratio(k, undershoot) >= tau; }
  // Scene indices (ascending) of the kept candidates, and their R_i (undershoot as in ratio()).
  void selected(float tau, std::vector<Index>& indices, std::vector<float>& scores, bool undershoot = true) const {
    std::vector<std::pair<Index, float>> out;
    for (std::size_t k = 0; k < n_; ++k) {
      const float R = ratio(k, undershoot);
      if (R >= tau) out.push_back({candidate(k), R});
    }
    std::sort(out.begin(), out.end());
    indices.clear();
    scores.clear();
    for (const auto& [i, r] : out) { indices.push_back(i); scores.push_back(r); }
  }

private:
  bool sure_level() const noexcept { return o_.gamma > 0.f; }
  int at(int level) const noexcept { return level == 2 && !sure_level() ? 1 : level; }

  void init(const float* x, const float* y, const float* z, std::size_t n) {
    x_ = x; y_ = y; z_ = z; n_ = n;
    const std::size_t counters = sure_level() ? 6 : 4;
    for (std::size_t c = 0; c < counters; ++c) c_[c].assign(n, 0);
    if (o_.reliability) rel_ = ViewReliability(n);
  }

  RobustVoteOptions o_;
  const float *x_ = nullptr, *y_ = nullptr, *z_ = nullptr;
  std::size_t n_ = 0, views_ = 0;
  std::vector<Index> candidates_;
  std::array<std::vector<float>, 3> own_;
  std::array<std::vector<std::uint16_t>, 6> c_;  // V, F, V^o, F^o, V^s, F^s (the last two with R6)
  std::vector<std::uint8_t> outer_;      // Eq. R6b: the sure plane with the outer band
  double last_undershoot_ = 0;
  ViewReliability rel_;                  // Eq. R13: V_j, F_j per view
  std::vector<float> view_weights_, rv_, rf_;  // r_j; V^r, F^r per candidate
  bool weighed_ = false;
};

}  // namespace vcar
