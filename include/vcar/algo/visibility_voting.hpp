#pragma once
// Visibility-based weighted voting (Eq. 1-3) as a streaming accumulator.
//
// Per candidate Gaussian i only two counters: F_i = #views with label 1 (Eq. 2: visible and in
// the mask), V_i = #views with label != -1 (visible by Eq. 1), both uint16_t, so 4 bytes per Gaussian (and
// 2 more per extra object in MultiObjectVoting), whatever the number of views.
// R_i = F_i / max(V_i, 1) (Eq. 3). A view without a mask is "no evidence" (conventions §4).
//
// Views are queued (camera + the mask packed to 1 bit per pixel in 8 x 8 tiles, W H / 8 bytes,
// and summarised per tile: MaskTiles) and voted in blocks of a few views per pass over the
// candidates, so the means are read once per block and the packed masks stay in cache. The candidates are voted in
// Morton-ordered chunks: a view decides a whole chunk at once where the chunk's box projects
// clearly outside the image, or clearly inside it onto mask tiles that are all background or all
// foreground; the rest is voted mean by mean. The counts are exactly Eq. 1-2's either way.
// Queries flush the queue. Each candidate is written by one thread only: results are identical
// for any thread count. Not thread-safe to share.
//
// Beyond the paper (off by default), occlusion-aware visibility: with a rendered expected
// depth D = sum z alpha T and alpha A of the same view, a Gaussian visible by Eq. 1 at pixel p
// counts as visible only if A(p) < 0.5 (no surface there) or z <= D(p) / A(p) * (1 + tolerance).
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/chunked_means.hpp"
#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/radix_sort.hpp"
#include "vcar/core/scratch_vector.hpp"

namespace vcar {

namespace detail {

static_assert(std::endian::native == std::endian::little, "packed tiles are read as little-endian 32-bit words");

inline constexpr int max_vote_objects = 64;  // objects voted in one pass (MultiObjectVoting)

// One queued view: the projection, where its objects' packed masks (MaskTiles) are, and whether
// it adds (+1) or takes back (-1) its votes.
struct VoteView {
  MeanProjection P;
  std::size_t tiles_offset = 0;     // object k's MaskTiles at tiles_offset + k
  int sign = 1;
  const float* depth = nullptr;     // occlusion-aware only (voted alone)
  const float* alpha = nullptr;
  float tolerance = 0.f;

  static VoteView from(const Camera& c) {
    VoteView v;
    v.P = MeanProjection::from(c);
    return v;
  }
};

// out[j] += a[j] + c for j < count, wrapping as the uint16 counters do. Separate restrict
// pointers and, for a whole chunk, a constant trip count let the compiler vectorise it.
inline void fold_counts(std::uint16_t* __restrict out, const std::int32_t* __restrict a, std::int32_t c,
                        std::size_t count) {
  constexpr std::size_t C = ChunkedMeans::chunk_size;
  if (count == C) {
    for (std::size_t j = 0; j < C; ++j) out[j] = static_cast<std::uint16_t>(out[j] + a[j] + c);
    return;
  }
  for (std::size_t j = 0; j < count; ++j) out[j] = static_cast<std::uint16_t>(out[j] + a[j] + c);
}

// Votes chunks [c0, c1) in every queued view. Counters are by sorted position; fg has
// n_objects rows of stride `n`. Per chunk, counts over the queued views are summed in 32-bit
// arrays (SIMD adds, in L1) plus per-chunk constants, and added to the uint16 counters once.
// `lanes[g]` holds views g * simd::width onwards in its lanes (project_boxes).
inline void vote_chunks(const ChunkedMeans& cm, std::size_t c0, std::size_t c1, std::span<const VoteView> views,
                        std::span<const ViewLanes> lanes, const MaskTiles* tiles, int n_objects,
                        std::uint16_t* visible, std::uint16_t* fg, std::size_t n) {
  using BI = simd::batch<std::int32_t>;
  constexpr std::size_t L = mean_batch, C = ChunkedMeans::chunk_size;
  constexpr std::size_t max_objects = max_vote_objects;
  const std::size_t K = static_cast<std::size_t>(n_objects);
  alignas(64) std::int32_t acc[(1 + 4) * C];  // visible + up to 4 objects in one pass
  std::int32_t add[1 + max_objects];
  MaskTiles::Content content[max_objects];
  constexpr std::size_t VL = simd::width;
  BoxViewLanes box_views;
  const float* x = cm.xyz[0].data();
  const float* y = cm.xyz[1].data();
  const float* z = cm.xyz[2].data();
  for (std::size_t o0 = 0; o0 < K; o0 += 4) {  // objects in groups of 4 (acc stays in L1)
    const std::size_t k1 = std::min(K, o0 + 4);
    for (std::size_t c = c0; c < c1; ++c) {
      const std::size_t j0 = c * C;
      std::fill(acc, acc + (1 + k1 - o0) * C, 0);
      std::fill(add, add + 1 + K, 0);
      const BoxLanes box = BoxLanes::of(cm.box[c].data(), cm.box[c].data() + 3);
      for (std::size_t i = 0; i < views.size(); ++i) {
        if (i % VL == 0) project_boxes(lanes[i / VL], box, box_views);  // the chunk in the next VL views
        const VoteView& w = views[i];
        const BoxView b = box_views[i % VL];
        if (b.visibility == BoxView::none_visible) continue;
        bool uniform = b.visibility == BoxView::all_visible && !w.depth;
        for (std::size_t k = o0; k < k1; ++k) {
          content[k] = tiles[w.tiles_offset + k].classify(b.x0, b.y0, b.x1, b.y1);
          uniform = uniform && content[k] != MaskTiles::mixed;
        }
        if (uniform) {  // every mean of the chunk visible, each object's mask constant over them
          add[0] += w.sign;
          for (std::size_t k = o0; k < k1; ++k) add[1 + k] += content[k] == MaskTiles::foreground ? w.sign : 0;
          continue;
        }
        const BI sign(w.sign);
        alignas(64) std::int32_t pix_l[L], vis_l[L];
        for (std::size_t i0 = j0; i0 < j0 + C; i0 += L) {
          ProjectedBatch p = project(w.P, x + i0, y + i0, z + i0);
          if (w.depth) {  // occlusion-aware rule (see top of file)
            alignas(64) float depth_l[L];
            p.pix.store_aligned(pix_l);
            p.vis.store_aligned(vis_l);
            p.z.store_aligned(depth_l);
            for (std::size_t l = 0; l < L; ++l) {
              const float a = w.alpha[pix_l[l]];
              if (vis_l[l] && a >= 0.5f && !(depth_l[l] <= w.depth[pix_l[l]] / a * (1.f + w.tolerance))) vis_l[l] = 0;
            }
            p.vis = BI::load_aligned(vis_l);
          }
          const BI sv = p.vis * sign;
          std::int32_t* av = acc + (i0 - j0);
          (BI::load_aligned(av) + sv).store_aligned(av);
          for (std::size_t k = o0; k < k1; ++k) {
            if (content[k] == MaskTiles::background) continue;
            std::int32_t* af = acc + (1 + k - o0) * C + (i0 - j0);
            if (content[k] == MaskTiles::foreground) {
              (BI::load_aligned(af) + sv).store_aligned(af);
              continue;
            }
            const BI f = tiles[w.tiles_offset + k].pixels(p.iu, p.iv) * sv;
            (BI::load_aligned(af) + f).store_aligned(af);
          }
        }
      }
      const std::size_t count = std::min(n, j0 + C) - j0;
      if (o0 == 0) fold_counts(visible + j0, acc, add[0], count);
      for (std::size_t k = o0; k < k1; ++k) fold_counts(fg + k * n + j0, acc + (1 + k - o0) * C, add[1 + k], count);
    }
  }
}

}  // namespace detail

// K objects voted in one pass over the views: one projection per (Gaussian, view), one visible
// counter and K foreground counters per Gaussian. VisibilityVoting is the K = 1 case.
//
// Candidates are kept in Morton order with their means copied (12 bytes per candidate, plus 4
// for the order) so that whole chunks of them are decided per view from their bounding box and
// the masks' tile summaries (detail::vote_chunks); the counters are exactly those of Eq. 1-2
// voted mean by mean. A view's votes can be taken back (remove_view) for incremental
// re-selection: the counters are sums over views.
class MultiObjectVoting {
public:
  static constexpr std::size_t max_views = 65535;  // uint16_t counters
  static constexpr int max_objects = detail::max_vote_objects;
  std::size_t block_views = 8;                     // views voted per pass over the candidates
  std::size_t chunk = 2048;                        // candidates per parallel task (fixed)

  // Every Gaussian of `scene` is a candidate (its means are copied).
  MultiObjectVoting(const GaussianScene& scene, int n_objects)
      : MultiObjectVoting(std::span<const float>(scene.mean[0]), std::span<const float>(scene.mean[1]),
                          std::span<const float>(scene.mean[2]), n_objects) {}
  // The Gaussians `candidates` of `scene` (scene indices, any order).
  MultiObjectVoting(const GaussianScene& scene, std::vector<Index> candidates, int n_objects)
      : candidates_(std::move(candidates)) {
    const auto own = detail::candidate_means(scene, candidates_);
    init(own[0].data(), own[1].data(), own[2].data(), candidates_.size(), n_objects);
  }
  // Raw SoA means (copied); candidate k has scene index k.
  MultiObjectVoting(std::span<const float> x, std::span<const float> y, std::span<const float> z, int n_objects) {
    if (x.size() != y.size() || x.size() != z.size()) throw Error("mean columns differ in length", "voting");
    init(x.data(), y.data(), z.data(), x.size(), n_objects);
  }

  MultiObjectVoting(const MultiObjectVoting&) = delete;
  MultiObjectVoting& operator=(const MultiObjectVoting&) = delete;
  MultiObjectVoting(MultiObjectVoting&&) noexcept = default;
  MultiObjectVoting& operator=(MultiObjectVoting&&) noexcept = default;

  int objects() const noexcept { return n_objects_; }
  std::size_t size() const noexcept { return n_; }
  // Scene index of candidate k.
  Index candidate(std::size_t k) const { return candidates_.empty() ? static_cast<Index>(k) : candidates_[k]; }
  // Views that carried evidence (a mask), queued ones included, less the ones taken back.
  std::size_t views() const noexcept { return views_; }

  // One view: masks[k] is object k's mask, or all null for "no evidence" (nothing counted).
  // A mix of null and non-null masks in one view is an error (the visible counter is shared).
  void add_view(const Camera& camera, std::span<const Mask* const> masks) {
    if (!enqueue(camera, masks, 1)) return;
    if (queue_.size() >= block_views) flush();
  }
  // Takes back the votes of a view added earlier with these same masks (Eq. 1-2 are sums over
  // views): the counters become those of a vote without it. Taking back a view that was never
  // added leaves meaningless counters; the caller keeps track (Reselection does).
  void remove_view(const Camera& camera, std::span<const Mask* const> masks) {
    if (std::none_of(masks.begin(), masks.end(), [](const Mask* m) { return m != nullptr; })) return;
    if (views_ == 0) throw Error("no view to take back", "view '" + camera.name + "'");
    if (!enqueue(camera, masks, -1)) return;
    if (queue_.size() >= block_views) flush();
  }

  // Occlusion-aware form: expected_depth and alpha (W x H, 1 channel) of this view's render;
  // see the rule at the top of the file. Null depth or alpha: plain Eq. 1.
  void add_view(const Camera& camera, std::span<const Mask* const> masks, const ImageF* expected_depth,
                const ImageF* alpha, float tolerance) {
    if (!expected_depth || !alpha) return add_view(camera, masks);
    if (std::none_of(masks.begin(), masks.end(), [](const Mask* m) { return m != nullptr; })) return;
    for (const ImageF* im : {expected_depth, alpha})
      if (im->width != camera.width || im->height != camera.height || im->channels != 1)
        throw Error("depth/alpha image is not the view's size with one channel", "view '" + camera.name + "'");
    flush();
    if (!enqueue(camera, masks, 1)) return;
    queue_.back().depth = expected_depth->data.data();
    queue_.back().alpha = alpha->data.data();
    queue_.back().tolerance = tolerance;
    flush();  // the images are only borrowed for this call
  }

  // Votes every queued view (queries call it).
  void flush() const {
    if (queue_.empty()) return;
    const std::size_t per_task = std::max<std::size_t>(1, chunk / detail::ChunkedMeans::chunk_size);
    const std::int64_t chunks = static_cast<std::int64_t>(means_.chunks());
    lanes_.clear();
    for (std::size_t i = 0; i < queue_.size(); i += simd::width) {
      const detail::MeanProjection* P[simd::width];
      const std::size_t count = std::min(simd::width, queue_.size() - i);
      for (std::size_t l = 0; l < count; ++l) P[l] = &queue_[i + l].P;
      lanes_.push_back(detail::ViewLanes::of(P, count));
    }
    parallel_chunks(chunks, static_cast<std::int64_t>(per_task), [&](std::int64_t, std::int64_t b, std::int64_t e) {
      detail::vote_chunks(means_, static_cast<std::size_t>(b), static_cast<std::size_t>(e), queue_, lanes_, tiles_.data(),
                          n_objects_, visible_.data(), fg_.data(), n_);
    });
    queue_.clear();
  }

  // Counters of candidate k: views where it is visible (label != -1) / foreground for object o.
  std::uint16_t visible(std::size_t k) const { flush(); return visible_[sorted(k)]; }
  std::uint16_t foreground(int o, std::size_t k) const { flush(); return fg_[o * n_ + sorted(k)]; }
  // Eq. 3: R_k = F_k / max(V_k, 1).
  float ratio(int o, std::size_t k) const { flush(); return ratio_at(o, sorted(k)); }
  // Eq. 3 by scene index (a candidate's); vcar::Error if it is not a candidate.
  float ratio_of(int o, Index scene_index) const { flush(); return ratio_at(o, sorted(position_of(scene_index))); }
  // Position among the candidates of a scene index; vcar::Error if it is not a candidate.
  std::size_t position_of(Index scene_index) const {
    if (candidates_.empty()) {
      if (scene_index >= n_) throw Error("Gaussian " + std::to_string(scene_index) + " is not a candidate", "voting");
      return scene_index;
    }
    if (by_index_.empty()) {  // built once, on first use
      by_index_.resize(candidates_.size());
      for (std::size_t k = 0; k < candidates_.size(); ++k) by_index_[k] = {candidates_[k], k};
      std::sort(by_index_.begin(), by_index_.end());
    }
    const auto it = std::lower_bound(by_index_.begin(), by_index_.end(), std::pair<Index, std::size_t>{scene_index, 0});
    if (it == by_index_.end() || it->first != scene_index)
      throw Error("Gaussian " + std::to_string(scene_index) + " is not a candidate", "voting");
    return it->second;
  }
  // Eq. 3: y_k = 1[R_k >= tau], per candidate (R_k in float, as ratio()).
  std::vector<std::uint8_t> labels(int o, float tau) const {
    flush();
    std::vector<std::uint8_t> y(n_);
    for (std::size_t j = 0; j < n_; ++j) y[means_.order[j]] = ratio_at(o, j) >= tau;
    return y;
  }
  // Scene indices (ascending) of the candidates with R >= tau for object o.
  std::vector<Index> selected(int o, float tau) const {
    std::vector<Index> out;
    std::vector<float> ratios;
    selected(o, tau, out, ratios);
    return out;
  }
  // The same with each one's R (Eq. 3), aligned: one pass over the counters in sorted order,
  // then a radix sort of (scene index, R) by index.
  void selected(int o, float tau, std::vector<Index>& indices, std::vector<float>& ratios) const {
    flush();
    // In fixed blocks of sorted positions, in parallel: each block counts its picks, then writes
    // them at its offset with its largest scene index (the same order for any thread count).
    constexpr std::size_t block = std::size_t{1} << 16;
    const std::size_t blocks = (n_ + block - 1) / block;
    std::vector<std::size_t> offset(blocks + 1, 0);
    std::vector<Index> largest(blocks, 0);
    auto picks = [&](std::size_t b, auto&& pick) {
      for (std::size_t j = b * block; j < std::min(n_, (b + 1) * block); ++j) {
        const float r = ratio_at(o, j);
        if (r >= tau) pick(j, r);
      }
    };
    parallel_for(static_cast<std::int64_t>(blocks), [&](std::int64_t bb) {
      const auto b = static_cast<std::size_t>(bb);
      picks(b, [&](std::size_t, float) { ++offset[b + 1]; });
    });
    for (std::size_t b = 0; b < blocks; ++b) offset[b + 1] += offset[b];
    scratch_vector<std::uint64_t> picked(offset[blocks]);  // scene index << 32 | bits of R (each written once)
    parallel_for(static_cast<std::int64_t>(blocks), [&](std::int64_t bb) {
      const auto b = static_cast<std::size_t>(bb);
      std::size_t at = offset[b];
      picks(b, [&](std::size_t j, float r) {
        const Index i = candidate(means_.order[j]);
        largest[b] = std::max(largest[b], i);
        picked[at++] = static_cast<std::uint64_t>(i) << 32 | std::bit_cast<std::uint32_t>(r);
      });
    });
    scratch_vector<std::uint64_t> tmp;
    sort_by_upper_word(picked, tmp, largest.empty() ? 0 : *std::max_element(largest.begin(), largest.end()));
    indices.resize(picked.size());
    ratios.resize(picked.size());
    for (std::size_t k = 0; k < picked.size(); ++k) {
      indices[k] = static_cast<Index>(picked[k] >> 32);
      ratios[k] = std::bit_cast<float>(static_cast<std::uint32_t>(picked[k]));
    }
  }

  // Bytes held: counters, sorted means and order, packed masks with their tile summaries.
  std::size_t bytes() const {
    std::size_t b = (visible_.capacity() + fg_.capacity()) * sizeof(std::uint16_t) + rank_.capacity() * 4 +
                    means_.order.capacity() * 4 + means_.box.capacity() * sizeof(means_.box[0]);
    for (const auto& c : means_.xyz) b += c.capacity() * sizeof(float);
    for (const auto& t : tiles_) b += t.bytes();
    return b;
  }

private:
  // Queues one view (packing its masks); false when it carries no evidence.
  bool enqueue(const Camera& camera, std::span<const Mask* const> masks, int sign) {
    if (std::none_of(masks.begin(), masks.end(), [](const Mask* m) { return m != nullptr; }))
      return false;  // conventions §4: no evidence, nothing counted
    check_view(camera, masks, sign);
    detail::VoteView w = detail::VoteView::from(camera);
    w.sign = sign;
    w.tiles_offset = queue_.size() * static_cast<std::size_t>(n_objects_);
    if (tiles_.size() < w.tiles_offset + n_objects_) tiles_.resize(w.tiles_offset + n_objects_);
    for (int k = 0; k < n_objects_; ++k) tiles_[w.tiles_offset + k].build(*masks[k]);
    queue_.push_back(w);
    views_ = sign > 0 ? views_ + 1 : views_ - 1;
    return true;
  }
  void init(const float* x, const float* y, const float* z, std::size_t n, int n_objects) {
    if (n_objects < 1 || n_objects > max_objects)
      throw Error("need 1 to " + std::to_string(max_objects) + " objects, got " + std::to_string(n_objects), "voting");
    n_ = n; n_objects_ = n_objects;
    means_ = detail::ChunkedMeans(x, y, z, n);
    // Zeroed in fixed blocks in parallel (a serial fill kept the other threads waiting).
    visible_.resize(n);
    fg_.resize(n * static_cast<std::size_t>(n_objects));
    for (auto* counters : {&visible_, &fg_})
      parallel_chunks(static_cast<std::int64_t>(counters->size()), std::int64_t{1} << 16,
                      [&](std::int64_t, std::int64_t b, std::int64_t e) {
                        std::fill(counters->data() + b, counters->data() + e, std::uint16_t{0});
                      });
  }
  void check_view(const Camera& camera, std::span<const Mask* const> masks, int sign) const {
    const std::string where = "view '" + camera.name + "'";
    if (masks.size() != static_cast<std::size_t>(n_objects_))
      throw Error("expected " + std::to_string(n_objects_) + " masks, got " + std::to_string(masks.size()), where);
    for (const Mask* m : masks) {
      if (!m) throw Error("some objects have a mask and some do not; vote them separately", where);
      if (m->width != camera.width || m->height != camera.height || m->channels != 1)
        throw Error("mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) + ", view is " +
                    std::to_string(camera.width) + "x" + std::to_string(camera.height), where);
    }
    if (sign > 0 && views_ + 1 > max_views) throw Error("more than 65535 views with masks (uint16_t counters)", where);
  }
  // Sorted position of candidate k (the inverse order, built on first use).
  std::size_t sorted(std::size_t k) const {
    if (rank_.empty() && n_ > 0) {
      rank_.resize(n_);
      for (std::size_t j = 0; j < n_; ++j) rank_[means_.order[j]] = static_cast<std::uint32_t>(j);
    }
    return rank_[k];
  }
  float ratio_at(int o, std::size_t j) const {  // Eq. 3, by sorted position
    return static_cast<float>(fg_[o * n_ + j]) / static_cast<float>(std::max<std::uint16_t>(visible_[j], 1));
  }

  std::size_t n_ = 0;
  int n_objects_ = 1;
  std::vector<Index> candidates_;              // empty: candidate k is scene index k
  detail::ChunkedMeans means_;                 // Morton-sorted means and chunk boxes
  mutable std::vector<std::uint32_t> rank_;    // candidate k -> sorted position (on first use)
  mutable std::vector<std::pair<Index, std::size_t>> by_index_;  // (scene index, position), sorted
  std::size_t views_ = 0;
  mutable scratch_vector<std::uint16_t> visible_;  // V_i, by sorted position
  mutable scratch_vector<std::uint16_t> fg_;       // F_i per object, object-major, by sorted position
  mutable std::vector<detail::VoteView> queue_;
  mutable std::vector<detail::ViewLanes> lanes_;  // the queued views' projections in SIMD lanes
  std::vector<MaskTiles> tiles_;                // per queued view and object: packed masks (capacity reused)
};

// Eq. 1-3 for one object.
class VisibilityVoting {
public:
  explicit VisibilityVoting(const GaussianScene& scene) : v_(scene, 1) {}
  VisibilityVoting(const GaussianScene& scene, std::vector<Index> candidates) : v_(scene, std::move(candidates), 1) {}
  VisibilityVoting(std::span<const float> x, std::span<const float> y, std::span<const float> z) : v_(x, y, z, 1) {}

  // mask null: no evidence in this view (conventions §4).
  void add_view(const Camera& camera, const Mask* mask) { v_.add_view(camera, std::span<const Mask* const>(&mask, 1)); }
  // Occlusion-aware visibility (beyond the paper), rule at the top of the file.
  void add_view(const Camera& camera, const Mask* mask, const ImageF* expected_depth, const ImageF* alpha,
                float tolerance) {
    v_.add_view(camera, std::span<const Mask* const>(&mask, 1), expected_depth, alpha, tolerance);
  }
  // Takes back a view added earlier with this same mask (MultiObjectVoting::remove_view).
  void remove_view(const Camera& camera, const Mask* mask) {
    v_.remove_view(camera, std::span<const Mask* const>(&mask, 1));
  }
  void flush() const { v_.flush(); }

  std::size_t size() const noexcept { return v_.size(); }
  std::size_t views() const noexcept { return v_.views(); }
  Index candidate(std::size_t k) const { return v_.candidate(k); }
  std::uint16_t visible(std::size_t k) const { return v_.visible(k); }
  std::uint16_t foreground(std::size_t k) const { return v_.foreground(0, k); }
  float ratio(std::size_t k) const { return v_.ratio(0, k); }                    // Eq. 3
  float ratio_of(Index scene_index) const { return v_.ratio_of(0, scene_index); }  // Eq. 3 by scene index
  std::vector<std::uint8_t> labels(float tau) const { return v_.labels(0, tau); }  // Eq. 3
  std::vector<Index> selected(float tau) const { return v_.selected(0, tau); }
  // The same with each one's R (Eq. 3), aligned.
  void selected(float tau, std::vector<Index>& indices, std::vector<float>& ratios) const {
    v_.selected(0, tau, indices, ratios);
  }
  // Tuning knobs of the underlying accumulator (block size, chunk).
  MultiObjectVoting& accumulator() noexcept { return v_; }

private:
  MultiObjectVoting v_;
};

}  // namespace vcar
