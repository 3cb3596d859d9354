#pragma once
// One segmentation round of the pipeline (Sec. 3.1): the frames in order (the reference view
// first), each rendered when the segmenter asks for it, each mask checked and handed on as it
// arrives (streamed, never all held), the segmenter's failures turned into errors naming the
// round and view; progress and cancellation between views.
#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "vcar/algo/params.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar {

// What the progress callback sees: the stage, and within a segmentation round the view.
struct Progress {
  std::string_view stage;
  std::size_t view = 0, views = 0;
  double elapsed_s = 0;
};
// Called between stages and between views; returning false cancels (vcar::Cancelled).
using ProgressCallback = std::function<bool(const Progress&)>;

struct Cancelled : Error {
  explicit Cancelled(const std::string& stage) : Error("cancelled by the caller", stage) {}
};

namespace detail {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The one check of a segmenter's mask (every round, segment_objects, Reselection): null (no
// mask) or the view's width x height with one channel; otherwise vcar::Error naming `where`.
inline void check_mask(const Mask* m, const Camera& cam, const std::string& where) {
  if (m && (m->width != cam.width || m->height != cam.height || m->channels != 1))
    throw Error("mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) + "x" +
                    std::to_string(m->channels) + ", the view is " + std::to_string(cam.width) + "x" +
                    std::to_string(cam.height) + "x1", where);
}

// Frame order of a round: the reference view first (conventions §4), then the other training
// views in their order, then the sampled views.
inline std::vector<std::size_t> training_order(std::size_t n, std::size_t reference) {
  std::vector<std::size_t> order{reference};
  for (std::size_t j = 0; j < n; ++j)
    if (j != reference) order.push_back(j);
  return order;
}

// One render of `cam` from `subset` (null: the whole scene) over `background`, with depth when
// asked: every render the pipeline (and the CLI's several-objects run) asks for.
template <Renderer R>
RenderOutput render_view(R& renderer, const GaussianScene& scene, const Camera& cam, const std::vector<Index>* subset,
                         const Eigen::Vector3f& background = Eigen::Vector3f::Zero(), bool want_depth = false) {
  RenderRequest q;
  q.scene = &scene;
  q.camera = &cam;
  q.subset = subset;
  q.background = background;
  q.want_depth = want_depth;
  return renderer.render(q);
}

struct RoundTimes {
  double render = 0, voting = 0, total = 0;
};

// What a round's vote reads of each frame's render: kept (alpha, for Eq. R3, R6, R11, R12) and
// with depth (Eq. R3, R11, R12).
struct RenderNeed {
  bool kept = false;
  bool depth = false;
};

// One segmentation round: renders frames on demand from `subset` (null = whole scene), streams
// each mask into `on_mask(frame, mask, render)`, validates sizes, maps segmenter failures to
// errors. With `need.kept` the latest render (with depth when `need.depth`) is handed to on_mask
// when its mask arrives (else `render` is null): a segmenter that asks for a frame just before
// answering it costs one render per frame, depth included.
template <Renderer R, Segmenter S, class OnMask>
RoundTimes run_round(std::string_view round, const GaussianScene& scene,
                     const std::vector<Index>* subset, std::span<const Camera> frames,
                     const Prompt& prompt, R& renderer, S& segmenter, const VcarParams& params,
                     const ProgressCallback& progress, Clock::time_point t_start, OnMask&& on_mask,
                     std::size_t& masks_missing, RenderNeed need = {}) {
  RoundTimes t;
  const auto t0 = Clock::now();
  std::vector<bool> seen(frames.size(), false);
  std::optional<std::pair<std::size_t, RenderOutput>> last;  // the latest render, when need.kept
  FrameSequence seq;
  seq.cameras = frames;
  seq.subset = subset != nullptr;
  if (subset) seq.drawn = [subset](std::size_t) { return subset; };
  seq.image = [&](std::size_t k) -> ImageRGB8 {
    if (k >= frames.size()) throw Error("frame " + std::to_string(k) + " out of range", std::string(round));
    const auto tr = Clock::now();
    RenderOutput out = render_view(renderer, scene, frames[k], subset, params.background, need.kept && need.depth);
    ImageRGB8 img = to_8bit(out.rgb);
    if (need.kept) last.emplace(k, std::move(out));
    t.render += seconds_since(tr);
    return img;
  };
  MaskSink sink = [&](std::size_t k, const Mask* m) {
    if (k >= frames.size())
      throw Error("segmenter answered frame " + std::to_string(k) + " of " +
                      std::to_string(frames.size()), std::string(round));
    const Camera& cam = frames[k];
    if (seen[k]) throw Error("segmenter answered a frame twice", std::string(round) + ", view '" + cam.name + "'");
    seen[k] = true;
    check_mask(m, cam, std::string(round) + ", view '" + cam.name + "'");
    if (!m) ++masks_missing;
    const auto tv = Clock::now();
    on_mask(k, m, last && last->first == k ? &last->second : nullptr);
    t.voting += seconds_since(tv);
    if (progress && !progress({round, k + 1, frames.size(), seconds_since(t_start)}))
      throw Cancelled(std::string(round));
  };
  try {
    segmenter.segment(seq, prompt, sink);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(std::string("segmenter failed: ") + e.what(), std::string(round));
  }
  for (std::size_t k = 0; k < frames.size(); ++k)
    if (!seen[k]) ++masks_missing;
  t.total = seconds_since(t0);
  return t;
}

// Fraction of a view's pixels that the Gaussians `subset` cover (alpha > 0.5).
template <Renderer R>
double content_fraction(const GaussianScene& scene, const std::vector<Index>& subset, const Camera& cam, R& renderer) {
  const RenderOutput out = render_view(renderer, scene, cam, &subset);
  std::size_t covered = 0;
  for (float a : out.alpha.data) covered += a > 0.5f;
  return out.alpha.data.empty() ? 0.0 : static_cast<double>(covered) / static_cast<double>(out.alpha.data.size());
}

// The mask, or null when it is below min_mask_fraction (conventions §7: the code drops tiny masks).
inline const Mask* usable(const Mask* m, const VcarParams& params) {
  if (!m || !(params.min_mask_fraction > 0.f)) return m;
  std::size_t fg = 0;
  for (std::uint8_t v : m->data) fg += v != 0;
  return static_cast<double>(fg) > params.min_mask_fraction * static_cast<double>(m->pixels()) ? m : nullptr;
}

}  // namespace detail

}  // namespace vcar
