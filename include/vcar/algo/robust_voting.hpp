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
// Views are voted one at a time. The candidates are kept in Morton order with their means copied
// (detail::ChunkedMeans, as VisibilityVoting) so that a view decides a whole chunk of 256 at once
// where the chunk's box projects clearly off the image (no evidence), or clearly inside it over
// mask tiles that are all background or all foreground, in front of the render's surface over
// the whole box (MinPyramid of D / A (1 + tolerance)), and over R6's sure plane uniformly; the
// other chunks are voted mean by mean. The counts are exactly those of the per-mean rules either
// way. Each chunk is written by one thread, so results are identical for any thread count.
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/chunked_means.hpp"
#include "vcar/algo/mean_projection.hpp"
#include "vcar/algo/undershoot.hpp"
#include "vcar/algo/view_reliability.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/min_pyramid.hpp"
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
  std::size_t chunk = 4096;  // candidates per parallel task (rounded to whole chunks of 256; fixed)

  // Every Gaussian of `scene` is a candidate (its means are copied).
  explicit RobustVoting(const GaussianScene& scene, const RobustVoteOptions& o = {}) : o_(o) {
    init(scene.mean[0].data(), scene.mean[1].data(), scene.mean[2].data(), scene.size());
  }
  // The Gaussians `candidates` of `scene` (scene indices, any order).
  RobustVoting(const GaussianScene& scene, std::vector<Index> candidates, const RobustVoteOptions& o = {})
      : o_(o), candidates_(std::move(candidates)) {
    const auto own = detail::candidate_means(scene, candidates_);
    init(own[0].data(), own[1].data(), own[2].data(), candidates_.size());
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
    ++views_;
    weighed_ = false;
    if (o_.reliability) rel_.add_view();
    View v;
    v.M = mask->data.data();
    if (sure_level() && alpha) {
      last_undershoot_ = undershoot_px(*mask, *alpha);                                     // Eq. R6a
      const double reach = o_.gamma * last_undershoot_;                                    // Eq. R6b
      if (reach > 0.0) {
        sure_ = Mask(mask->width, mask->height, 1, 255);
        widen_outer_band(*mask, reach, sure_.data);
        sure_tiles_.build(sure_);
        v.sure = sure_.data.data();
      }
    }
    tiles_.build(*mask);
    if (expected_depth) {
      v.D = expected_depth->data.data();
      v.A = alpha->data.data();
      v.scale = 1.f + tolerance;
      surface_.build(camera.width, camera.height, [&](std::size_t p) { return v.bound(p); });
    }
    v.P = detail::MeanProjection::from(camera);
    const detail::ViewLanes lanes = detail::ViewLanes::of(v.P);
    constexpr std::size_t C = detail::ChunkedMeans::chunk_size, VL = simd::width;
    const std::size_t per_task = (std::max<std::size_t>(1, chunk / C) + VL - 1) / VL * VL;
    parallel_chunks(static_cast<std::int64_t>(means_.chunks()), static_cast<std::int64_t>(per_task),
                    [&](std::int64_t, std::int64_t b, std::int64_t e) {
      detail::BoxViewLanes boxes;
      std::size_t whole = 0;
      for (std::size_t c0 = static_cast<std::size_t>(b); c0 < static_cast<std::size_t>(e); c0 += VL) {
        const std::size_t count = std::min(VL, static_cast<std::size_t>(e) - c0);
        detail::project_boxes(lanes, detail::BoxLanes::of(means_.box.data() + c0, count), boxes);
        for (std::size_t l = 0; l < count; ++l) whole += vote_chunk(v, c0 + l, boxes[l]);
      }
      whole_chunks_ += whole;
    });
  }

  std::size_t size() const noexcept { return n_; }
  std::size_t views() const noexcept { return views_; }
  Index candidate(std::size_t k) const { return candidates_.empty() ? static_cast<Index>(k) : candidates_[k]; }
  // (chunk, view) pairs decided whole (off the image, or from the chunk's box), and all of them.
  std::size_t whole_chunks() const noexcept { return whole_chunks_; }
  std::size_t chunk_views() const noexcept { return means_.chunks() * views_; }
  // Counters of candidate k: level 0 plain (V, F), 1 unoccluded (V^o, F^o), 2 sure (V^s, F^s;
  // the unoccluded level's without R6).
  std::uint16_t visible(std::size_t k, int level = 0) const { return c_[2 * at(level)][rank_[k]]; }
  std::uint16_t foreground(std::size_t k, int level = 0) const { return c_[2 * at(level) + 1][rank_[k]]; }
  // Eq. R13: weighs the views voted so far by their agreement with the consensus at `tau`
  // (first the unweighted vote's, then the weighted one's, `iterations` times); the unoccluded
  // level then sums the weights. No effect without the reliability option. Returns r_j.
  const std::vector<float>& weigh_views(float tau, int iterations = 2) {
    if (!o_.reliability) return view_weights_;
    weighed_ = false;
    for (int it = 0; it < iterations; ++it) {
      const auto consensus = rel_.bits([&](std::size_t j) { return ratio_at(j, true) >= tau; });
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
  float ratio(std::size_t k, bool undershoot = true) const { return ratio_at(rank_[k], undershoot); }
  // Eq. 3 / R2 for candidate k (undershoot as in ratio()).
  bool kept(std::size_t k, float tau, bool undershoot = true) const { return ratio(k, undershoot) >= tau; }
  // Scene indices (ascending) of the kept candidates, and their R_i (undershoot as in ratio()).
  void selected(float tau, std::vector<Index>& indices, std::vector<float>& scores, bool undershoot = true) const {
    collect(indices, scores, [&](std::size_t j) { return std::pair{ratio_at(j, undershoot), tau}; });
  }
  // Eq. R7 per candidate (decisive_threshold.hpp): tau_strict, on R_i read as ratio(k,
  // strict_undershoot), for a candidate seen unoccluded in at least a fraction `seen` of the
  // views that voted on it (V^o_i >= seen V_i); tau, on R_i with R6, for the others.
  void selected(float tau, float tau_strict, float seen, bool strict_undershoot, std::vector<Index>& indices,
                std::vector<float>& scores) const {
    collect(indices, scores, [&](std::size_t j) {
      return static_cast<float>(c_[2][j]) >= seen * static_cast<float>(c_[0][j])
                 ? std::pair{ratio_at(j, strict_undershoot), tau_strict}
                 : std::pair{ratio_at(j, true), tau};
    });
  }

private:
  // One view's images, as the per-mean rules read them (null: not given).
  struct View {
    detail::MeanProjection P;
    const std::uint8_t* M = nullptr;     // the mask
    const std::uint8_t* sure = nullptr;  // Eq. R6b's sure plane (null: every pixel is sure)
    const float *D = nullptr, *A = nullptr;  // Eq. R3's render
    float scale = 1.f;                   // 1 + tolerance
    // Eq. R3: the greatest depth at pixel p not behind the rendered surface (+inf: no surface).
    float bound(std::size_t p) const { return A[p] >= 0.5f ? D[p] / A[p] * scale : std::numeric_limits<float>::infinity(); }
  };

  bool sure_level() const noexcept { return o_.gamma > 0.f; }
  int at(int level) const noexcept { return level == 2 && !sure_level() ? 1 : level; }

  // Counters of sorted positions [j0, j0 + count) += (1, f) at `level`.
  void add_all(int level, std::size_t j0, std::size_t count, std::uint16_t f) {
    std::uint16_t* V = c_[2 * level].data() + j0;
    std::uint16_t* F = c_[2 * level + 1].data() + j0;
    for (std::size_t j = 0; j < count; ++j) V[j] = static_cast<std::uint16_t>(V[j] + 1);
    if (f)
      for (std::size_t j = 0; j < count; ++j) F[j] = static_cast<std::uint16_t>(F[j] + 1);
  }

  // The vote of chunk c in view v, whole when its box decides it (see the top of the file):
  // returns whether it did.
  bool vote_chunk(const View& v, std::size_t c, const detail::BoxView& b) {
    if (b.visibility == detail::BoxView::none_visible) return true;                         // Eq. 1: no evidence
    constexpr std::size_t C = detail::ChunkedMeans::chunk_size, L = detail::mean_batch;
    const std::size_t j0 = c * C;
    const bool sure_counts = sure_level();
    if (b.visibility == detail::BoxView::all_visible) {
      const MaskTiles::Content content = tiles_.classify(b.x0, b.y0, b.x1, b.y1);
      const MaskTiles::Content sure = v.sure ? sure_tiles_.classify(b.x0, b.y0, b.x1, b.y1) : MaskTiles::foreground;
      const bool unoccluded = !v.D || b.zmax <= surface_.min_over(b.x0, b.y0, b.x1, b.y1);  // Eq. R3, whole
      if (content != MaskTiles::mixed && sure != MaskTiles::mixed && unoccluded) {
        const std::size_t count = std::min(n_, j0 + C) - j0;
        const std::uint16_t f = content == MaskTiles::foreground;
        add_all(0, j0, count, f);                                                          // Eq. 2
        add_all(1, j0, count, f);
        if (o_.reliability) rel_.see_all(j0, j0 + count, f != 0);                          // Eq. R13
        if (sure_counts && sure == MaskTiles::foreground) add_all(2, j0, count, f);        // Eq. R6b
        return true;
      }
    }
    const float* x = means_.xyz[0].data();
    const float* y = means_.xyz[1].data();
    const float* z = means_.xyz[2].data();
    alignas(64) std::int32_t pix[L], vis[L];
    alignas(64) float depth[L];
    for (std::size_t i0 = j0; i0 < j0 + C; i0 += L) {
      detail::project_batch(v.P, x + i0, y + i0, z + i0, pix, vis, depth);
      for (std::size_t l = 0; l < L; ++l) {
        if (!vis[l]) continue;
        const std::size_t j = i0 + l, p = static_cast<std::size_t>(pix[l]);
        const std::uint16_t f = v.M[p] != 0;
        ++c_[0][j]; c_[1][j] = static_cast<std::uint16_t>(c_[1][j] + f);                    // Eq. 2
        if (v.D && !(depth[l] <= v.bound(p))) continue;                                      // Eq. R3
        ++c_[2][j]; c_[3][j] = static_cast<std::uint16_t>(c_[3][j] + f);
        if (o_.reliability) rel_.see(j, f != 0);                                            // Eq. R13
        if (!sure_counts || (v.sure && !v.sure[p])) continue;                                // Eq. R6b
        ++c_[4][j]; c_[5][j] = static_cast<std::uint16_t>(c_[5][j] + f);
      }
    }
    return false;
  }

  // The candidates whose (R_i, threshold) = rule(sorted position) has R_i >= threshold: scene
  // indices ascending, and their R_i.
  template <class Rule>
  void collect(std::vector<Index>& indices, std::vector<float>& scores, Rule rule) const {
    std::vector<std::pair<Index, float>> out;
    for (std::size_t j = 0; j < n_; ++j) {
      const auto [R, t] = rule(j);
      if (R >= t) out.push_back({candidate(means_.order[j]), R});
    }
    std::sort(out.begin(), out.end());
    indices.clear();
    scores.clear();
    for (const auto& [i, r] : out) { indices.push_back(i); scores.push_back(r); }
  }

  // Eq. R2 by sorted position j.
  float ratio_at(std::size_t j, bool undershoot) const {
    // A level with the same counts as the one below adds no evidence: R stays what it was, bit
    // for bit (so Eq. 3 comes out identical whenever the mechanisms add nothing). Once R13
    // weighed the views the unoccluded level always sums them, so it always shrinks.
    auto V_at = [&](int level) { return c_[2 * at(level)][j]; };
    auto F_at = [&](int level) { return c_[2 * at(level) + 1][j]; };
    float R = static_cast<float>(F_at(0)) / static_cast<float>(std::max<std::uint16_t>(V_at(0), 1));
    const int top = undershoot && sure_level() ? 2 : 1;
    for (int level = 1; level <= top; ++level) {
      const bool same = V_at(level) == V_at(level - 1) && F_at(level) == F_at(level - 1);
      const bool weighed = weighed_ && level == 1;  // Eq. R13b
      if (same && !weighed) continue;
      float V = static_cast<float>(V_at(level));
      float F = static_cast<float>(F_at(level));
      if (weighed) V = rv_[j], F = rf_[j];
      if (V + o_.kappa > 0.f) R = (F + o_.kappa * R) / (V + o_.kappa);                    // Eq. R2
    }
    return R;
  }

  void init(const float* x, const float* y, const float* z, std::size_t n) {
    n_ = n;
    means_ = detail::ChunkedMeans(x, y, z, n);
    rank_.resize(n);
    for (std::size_t j = 0; j < n; ++j) rank_[means_.order[j]] = static_cast<std::uint32_t>(j);
    const std::size_t counters = sure_level() ? 6 : 4;
    for (std::size_t c = 0; c < counters; ++c) c_[c].assign(n, 0);
    if (o_.reliability) rel_ = ViewReliability(n);
  }

  RobustVoteOptions o_;
  std::size_t n_ = 0, views_ = 0;
  std::vector<Index> candidates_;        // empty: candidate k is scene index k
  detail::ChunkedMeans means_;           // Morton-sorted means and chunk boxes
  std::vector<std::uint32_t> rank_;      // candidate k -> sorted position
  std::array<std::vector<std::uint16_t>, 6> c_;  // V, F, V^o, F^o, V^s, F^s by sorted position (the last two with R6)
  MaskTiles tiles_, sure_tiles_;         // the view's mask and Eq. R6b's sure plane, summarised
  MinPyramid surface_;                   // Eq. R3's bound D / A (1 + tolerance) per pixel
  Mask sure_;                            // Eq. R6b: the sure plane with the outer band (255 = sure)
  double last_undershoot_ = 0;
  ViewReliability rel_;                  // Eq. R13: V_j, F_j per view, by sorted position
  std::vector<float> view_weights_, rv_, rf_;  // r_j; V^r, F^r by sorted position
  bool weighed_ = false;
  std::atomic<std::size_t> whole_chunks_{0};
};

}  // namespace vcar
