#pragma once
// Visibility-based weighted voting (Eq. 1-3) as a streaming accumulator.
//
// Per candidate Gaussian i only two counters: F_i = #views with label 1 (Eq. 2: visible and in
// the mask), V_i = #views with label != -1 (visible by Eq. 1), both uint16_t, so 4 bytes per Gaussian (and
// 2 more per extra object in MultiObjectVoting), whatever the number of views.
// R_i = F_i / max(V_i, 1) (Eq. 3). A view without a mask is "no evidence" (conventions §4).
//
// Views are queued (camera + the mask packed to 1 bit per pixel, W H / 8 bytes) and voted in
// blocks of a few views per pass over the candidates, so the means are read once per block
// and the packed masks stay in cache. Queries flush the queue. Each candidate is written by
// one thread only: results are identical for any thread count. Not thread-safe to share.
//
// Beyond the paper (off by default), occlusion-aware visibility: with a rendered expected
// depth D = sum z alpha T and alpha A of the same view, a Gaussian visible by Eq. 1 at pixel p
// counts as visible only if A(p) < 0.5 (no surface there) or z <= D(p) / A(p) * (1 + tolerance).
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar {

namespace detail {

// Nonzero bytes of `m` to bits, bit p = row * W + col, LSB first (little-endian: bit p is also
// bit p % 32 of 32-bit word p / 32, which the gather in vote_range reads).
inline void pack_mask_bits(const Mask& m, std::uint8_t* bits) {
  const std::size_t n = m.pixels(), full = n / 8;
  const std::uint8_t* src = m.data.data();
  for (std::size_t w = 0; w < full; ++w) {
    std::uint64_t v;
    std::memcpy(&v, src + 8 * w, 8);
    // High bit of each byte set iff the byte is nonzero (no carry crosses a byte).
    std::uint64_t t = (v | ((v & 0x7f7f7f7f7f7f7f7fULL) + 0x7f7f7f7f7f7f7f7fULL)) & 0x8080808080808080ULL;
    // Gather the 8 high bits into the top byte: byte j -> bit 56 + j (distinct partial products).
    bits[w] = static_cast<std::uint8_t>(((t >> 7) * 0x0102040810204080ULL) >> 56);
  }
  if (full * 8 < n) {
    std::uint8_t b = 0;
    for (std::size_t p = full * 8; p < n; ++p) b |= static_cast<std::uint8_t>((src[p] != 0) << (p - full * 8));
    bits[full] = b;
  }
}

static_assert(std::endian::native == std::endian::little, "packed masks are read as little-endian words");

inline bool bit_at(const std::uint8_t* bits, std::int32_t p) { return (bits[p >> 3] >> (p & 7)) & 1; }

// One queued view: the projection and where its objects' packed masks start.
struct VoteView {
  MeanProjection P;
  std::size_t bits_offset = 0;      // object k's bits at bits_offset + k * bytes_per_mask
  std::size_t bytes_per_mask = 0;
  const float* depth = nullptr;     // occlusion-aware only (never queued)
  const float* alpha = nullptr;
  float tolerance = 0.f;

  static VoteView from(const Camera& c) {
    VoteView v;
    v.P = MeanProjection::from(c);
    v.bytes_per_mask = (static_cast<std::size_t>(c.width) * c.height + 31) / 32 * 4;  // whole 32-bit words
    return v;
  }
};

// Votes candidates [begin, end) in every queued view. fg has n_objects rows of stride `n`.
inline void vote_range_general(const float* x, const float* y, const float* z, std::size_t begin, std::size_t end,
                               std::span<const VoteView> views, const std::uint8_t* bits, int n_objects,
                               std::uint16_t* visible, std::uint16_t* fg, std::size_t n) {
  constexpr std::size_t L = mean_batch;
  alignas(64) std::int32_t pix[L], vis[L];
  alignas(64) float depth[L];
  for (const VoteView& w : views) {
    const std::uint8_t* wb = bits + w.bits_offset;
    for (std::size_t i0 = begin; i0 < end; i0 += L) {
      const std::size_t m = std::min(L, end - i0);
      if (m == L) project_batch(w.P, x + i0, y + i0, z + i0, pix, vis, depth);
      else project_tail(w.P, x + i0, y + i0, z + i0, m, pix, vis, depth);
      if (w.depth) {  // occlusion-aware rule (see top of file)
        for (std::size_t l = 0; l < m; ++l) {
          const float a = w.alpha[pix[l]];
          if (vis[l] && a >= 0.5f && !(depth[l] <= w.depth[pix[l]] / a * (1.f + w.tolerance))) vis[l] = 0;
        }
      }
      for (std::size_t l = 0; l < m; ++l) {
        const std::size_t i = i0 + l;
        const auto s = static_cast<std::uint16_t>(vis[l]);
        visible[i] = static_cast<std::uint16_t>(visible[i] + s);
        for (int k = 0; k < n_objects; ++k) {
          const std::uint8_t* kb = wb + static_cast<std::size_t>(k) * w.bytes_per_mask;
          fg[k * n + i] = static_cast<std::uint16_t>(fg[k * n + i] + (s & bit_at(kb, pix[l])));
        }
      }
    }
  }
}

// The hot path (no occlusion test, whole batches): for a slice of candidates, counts over the
// queued views in 32-bit arrays (SIMD adds, in L1), added to the uint16 counters once. One
// projection per (Gaussian, view) serves every object.
inline void vote_range(const float* x, const float* y, const float* z, std::size_t begin, std::size_t end,
                       std::span<const VoteView> views, const std::uint8_t* bits, int n_objects,
                       std::uint16_t* visible, std::uint16_t* fg, std::size_t n) {
  constexpr std::size_t L = mean_batch, S = 512;  // slice of candidates
  if (std::any_of(views.begin(), views.end(), [](const VoteView& w) { return w.depth != nullptr; }))
    return vote_range_general(x, y, z, begin, end, views, bits, n_objects, visible, fg, n);
  using BI = simd::batch<std::int32_t>;
  const std::size_t K = static_cast<std::size_t>(n_objects);
  std::vector<std::int32_t> acc((1 + K) * S);  // per call (a chunk of candidates), not per Gaussian
  std::int32_t* accV = acc.data();
  const std::size_t full_end = begin + (end - begin) / L * L;
  for (std::size_t s0 = begin; s0 < full_end; s0 += S) {
    const std::size_t s1 = std::min(full_end, s0 + S);
    std::fill(acc.begin(), acc.end(), 0);
    for (const VoteView& w : views) {
      for (std::size_t i0 = s0; i0 < s1; i0 += L) {
        const ProjectedBatch p = project(w.P, x + i0, y + i0, z + i0);
        std::int32_t* av = accV + (i0 - s0);
        (BI::load_unaligned(av) + p.vis).store_unaligned(av);
        const BI word_index = p.pix >> 5, shift = p.pix & BI(31);  // bit p is bit p % 32 of word p / 32
        for (std::size_t k = 0; k < K; ++k) {
          const auto* words = reinterpret_cast<const std::int32_t*>(bits + w.bits_offset + k * w.bytes_per_mask);
          const BI f = (simd::gather(words, word_index) >> shift) & p.vis;
          std::int32_t* af = accV + (1 + k) * S + (i0 - s0);
          (BI::load_unaligned(af) + f).store_unaligned(af);
        }
      }
    }
    for (std::size_t i = 0; i < s1 - s0; ++i) {
      visible[s0 + i] = static_cast<std::uint16_t>(visible[s0 + i] + accV[i]);
      for (std::size_t k = 0; k < K; ++k)
        fg[k * n + s0 + i] = static_cast<std::uint16_t>(fg[k * n + s0 + i] + accV[(1 + k) * S + i]);
    }
  }
  if (full_end < end) vote_range_general(x, y, z, full_end, end, views, bits, n_objects, visible, fg, n);
}

}  // namespace detail

// K objects voted in one pass over the views: one projection per (Gaussian, view), one visible
// counter and K foreground counters per Gaussian. VisibilityVoting is the K = 1 case.
class MultiObjectVoting {
public:
  static constexpr std::size_t max_views = 65535;  // uint16_t counters
  std::size_t block_views = 8;                     // views voted per pass over the candidates
  std::size_t chunk = 2048;                        // candidates per parallel task (fixed)

  // Every Gaussian of `scene` is a candidate; the scene's mean columns are referenced, so the
  // scene must outlive this object.
  MultiObjectVoting(const GaussianScene& scene, int n_objects)
      : MultiObjectVoting(std::span<const float>(scene.mean[0]), std::span<const float>(scene.mean[1]),
                          std::span<const float>(scene.mean[2]), n_objects) {}
  // The Gaussians `candidates` of `scene` (scene indices, any order); their means are copied.
  MultiObjectVoting(const GaussianScene& scene, std::vector<Index> candidates, int n_objects)
      : candidates_(std::move(candidates)) {
    own_ = detail::candidate_means(scene, candidates_);
    init(own_[0].data(), own_[1].data(), own_[2].data(), candidates_.size(), n_objects);
  }
  // Raw SoA means (referenced, not copied); candidate k has scene index k.
  MultiObjectVoting(std::span<const float> x, std::span<const float> y, std::span<const float> z, int n_objects) {
    if (x.size() != y.size() || x.size() != z.size()) throw Error("mean columns differ in length", "voting");
    init(x.data(), y.data(), z.data(), x.size(), n_objects);
  }

  // Not copyable (a subset's means are referenced by pointer); movable.
  MultiObjectVoting(const MultiObjectVoting&) = delete;
  MultiObjectVoting& operator=(const MultiObjectVoting&) = delete;
  MultiObjectVoting(MultiObjectVoting&&) noexcept = default;
  MultiObjectVoting& operator=(MultiObjectVoting&&) noexcept = default;

  int objects() const noexcept { return n_objects_; }
  std::size_t size() const noexcept { return n_; }
  // Scene index of candidate k.
  Index candidate(std::size_t k) const { return candidates_.empty() ? static_cast<Index>(k) : candidates_[k]; }
  // Views that carried evidence (a mask), queued ones included.
  std::size_t views() const noexcept { return views_; }

  // One view: masks[k] is object k's mask, or all null for "no evidence" (nothing counted).
  // A mix of null and non-null masks in one view is an error (the visible counter is shared).
  void add_view(const Camera& camera, std::span<const Mask* const> masks) {
    if (!enqueue(camera, masks)) return;
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
    if (!enqueue(camera, masks)) return;
    queue_.back().depth = expected_depth->data.data();
    queue_.back().alpha = alpha->data.data();
    queue_.back().tolerance = tolerance;
    flush();  // the images are only borrowed for this call
  }

  // Votes every queued view (queries call it).
  void flush() const {
    if (queue_.empty()) return;
    const std::int64_t n = static_cast<std::int64_t>(n_);
    parallel_chunks(n, static_cast<std::int64_t>(chunk), [&](std::int64_t, std::int64_t b, std::int64_t e) {
      detail::vote_range(x_, y_, z_, static_cast<std::size_t>(b), static_cast<std::size_t>(e), queue_,
                         bits_.data(), n_objects_, visible_.data(), fg_.data(), n_);
    });
    queue_.clear();
    bits_.clear();
  }

  // Counters of candidate k: views where it is visible (label != -1) / foreground for object o.
  std::uint16_t visible(std::size_t k) const { flush(); return visible_[k]; }
  std::uint16_t foreground(int o, std::size_t k) const { flush(); return fg_[o * n_ + k]; }
  // Eq. 3: R_k = F_k / max(V_k, 1).
  float ratio(int o, std::size_t k) const { flush(); return ratio_at(o, k); }
  // Eq. 3 by scene index (a candidate's); vcar::Error if it is not a candidate.
  float ratio_of(int o, Index scene_index) const { flush(); return ratio_at(o, position_of(scene_index)); }
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
    for (std::size_t k = 0; k < n_; ++k) y[k] = selected_at(o, k, tau);
    return y;
  }
  // Scene indices (ascending) of the candidates with R >= tau for object o.
  std::vector<Index> selected(int o, float tau) const {
    flush();
    std::vector<Index> out;
    for (std::size_t k = 0; k < n_; ++k)
      if (selected_at(o, k, tau)) out.push_back(candidate(k));
    std::sort(out.begin(), out.end());
    return out;
  }

private:
  // Queues one view (packing its masks); false when it carries no evidence.
  bool enqueue(const Camera& camera, std::span<const Mask* const> masks) {
    if (std::none_of(masks.begin(), masks.end(), [](const Mask* m) { return m != nullptr; }))
      return false;  // conventions §4: no evidence, nothing counted
    check_view(camera, masks);
    detail::VoteView w = detail::VoteView::from(camera);
    w.bits_offset = bits_.size();
    bits_.resize(bits_.size() + w.bytes_per_mask * n_objects_);
    for (int k = 0; k < n_objects_; ++k)
      detail::pack_mask_bits(*masks[k], bits_.data() + w.bits_offset + k * w.bytes_per_mask);
    queue_.push_back(w);
    ++views_;
    return true;
  }
  void init(const float* x, const float* y, const float* z, std::size_t n, int n_objects) {
    if (n_objects < 1) throw Error("need at least one object", "voting");
    x_ = x; y_ = y; z_ = z; n_ = n; n_objects_ = n_objects;
    visible_.assign(n, 0);
    fg_.assign(n * static_cast<std::size_t>(n_objects), 0);
  }
  void check_view(const Camera& camera, std::span<const Mask* const> masks) const {
    const std::string where = "view '" + camera.name + "'";
    if (masks.size() != static_cast<std::size_t>(n_objects_))
      throw Error("expected " + std::to_string(n_objects_) + " masks, got " + std::to_string(masks.size()), where);
    for (const Mask* m : masks) {
      if (!m) throw Error("some objects have a mask and some do not; vote them separately", where);
      if (m->width != camera.width || m->height != camera.height || m->channels != 1)
        throw Error("mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) + ", view is " +
                    std::to_string(camera.width) + "x" + std::to_string(camera.height), where);
    }
    if (views_ + 1 > max_views) throw Error("more than 65535 views with masks (uint16_t counters)", where);
  }
  float ratio_at(int o, std::size_t k) const {  // Eq. 3
    return static_cast<float>(fg_[o * n_ + k]) / static_cast<float>(std::max<std::uint16_t>(visible_[k], 1));
  }
  bool selected_at(int o, std::size_t k, float tau) const {
    return ratio_at(o, k) >= tau;
  }

  const float *x_ = nullptr, *y_ = nullptr, *z_ = nullptr;
  std::size_t n_ = 0;
  int n_objects_ = 1;
  std::vector<Index> candidates_;              // empty: candidate k is scene index k
  std::array<std::vector<float>, 3> own_;      // copied means of a subset
  mutable std::vector<std::pair<Index, std::size_t>> by_index_;  // (scene index, position), sorted
  std::size_t views_ = 0;
  mutable std::vector<std::uint16_t> visible_;  // V_i
  mutable std::vector<std::uint16_t> fg_;       // F_i per object, object-major
  mutable std::vector<detail::VoteView> queue_;
  mutable std::vector<std::uint8_t> bits_;
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
  // Tuning knobs of the underlying accumulator (block size, chunk).
  MultiObjectVoting& accumulator() noexcept { return v_; }

private:
  MultiObjectVoting v_;
};

}  // namespace vcar
