#pragma once
// The Segmenter concept: any source of 2D masks of one target (SAM 2/3, a mask folder, an
// oracle, a human).
//
// `s.segment(frames, prompt, sink)` is called once per segmentation round:
//  - `frames.cameras[k]` is the camera of frame k; frame 0 is always the reference view on
//    which the prompt was given (conventions §4), so video-mode segmenters can propagate.
//  - `frames.image(k)` renders frame k on demand as 8-bit RGB (width x height x 3). It renders
//    on every call: a segmenter that needs pixels calls it once per frame; one that does not
//    (an oracle, a mask folder) never pays for rendering.
//  - `frames.subset` is true when the frames render a subset of the scene (the fine round renders
//    G_coarse only); `frames.drawn(k)`, when the function is set, names the Gaussians frame k
//    draws (indices into the scene; null: the whole scene), for segmenters that model what a
//    render shows (the synthetic oracle's rendered mode). An empty function means the whole
//    scene where `subset` is false, unknown where it is true. A segmenter whose masks are of the
//    captured images rather than of the frames (a folder of precomputed masks) answers the frames
//    of a subset "no mask": the pipeline then keeps G_coarse.
//  - `prompt` is passed through unchanged: points (pixels of the reference view, label 1 =
//    positive, 0 = negative), an optional box (x0, y0, x1, y1) or text.
//  - the segmenter calls `sink(k, &mask)` for each frame k it has a mask for, or `sink(k,
//    nullptr)` for "no mask" (the frame then counts as no evidence). Each frame at most once;
//    frames never reported count as "no mask". A mask must be the frame's width x height, one
//    channel, nonzero = foreground; the pipeline rejects any other size with an error naming
//    the view. The sink copies what it needs: the mask may be freed right after the call, so
//    masks can be streamed and never all held at once.
// Errors: throw; the pipeline rethrows as vcar::Error naming the round.
//
// Models: vcar::synth::OracleSegmenter, vcar::MaskFolderSegmenter (io), or a lambda:
//
//   auto s = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt& p) {
//     std::vector<std::optional<vcar::Mask>> masks(f.size()); /* fill */ return masks; });
//   static_assert(vcar::Segmenter<decltype(s)>);
#include <concepts>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar {

struct Prompt {
  std::vector<Eigen::Vector2f> points;  // pixels of the reference view
  std::vector<int> point_labels;        // 1 positive, 0 negative (same length as points)
  std::optional<Eigen::Vector4f> box;   // x0, y0, x1, y1 in pixels
  std::string text;
  std::size_t reference_view = 0;       // index of the reference camera among the training views
};

struct FrameSequence {
  std::span<const Camera> cameras;                  // frame k's camera; frame 0 = reference
  std::function<ImageRGB8(std::size_t)> image;      // renders frame k (8-bit RGB)
  // true when the frames render a subset of the scene (the fine round renders G_coarse only):
  // occluders outside the subset are not in the images, so masks should not be cut by them.
  bool subset = false;
  // The Gaussians frame k draws (null: the whole scene); empty: see the top of this file. The
  // vector pointed to lives at least as long as the call of segment().
  std::function<const std::vector<Index>*(std::size_t)> drawn;
  std::size_t size() const noexcept { return cameras.size(); }
};

using MaskSink = std::function<void(std::size_t frame, const Mask* mask)>;

template <class S>
concept Segmenter = requires(S& s, const FrameSequence& f, const Prompt& p, const MaskSink& sink) {
  { s.segment(f, p, sink) };
};

// Adapter from a callable returning all masks at once:
//   std::vector<std::optional<Mask>> f(const FrameSequence&, const Prompt&)
template <class F>
struct LambdaSegmenter {
  F fn;
  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    std::vector<std::optional<Mask>> masks = fn(frames, prompt);
    for (std::size_t k = 0; k < frames.size(); ++k)
      sink(k, k < masks.size() && masks[k] ? &*masks[k] : nullptr);
  }
};
template <class F>
LambdaSegmenter<std::decay_t<F>> make_segmenter(F&& f) { return {std::forward<F>(f)}; }

// Adapter from a streaming callable void(const FrameSequence&, const Prompt&, const MaskSink&).
template <class F>
struct StreamingLambdaSegmenter {
  F fn;
  void segment(const FrameSequence& f, const Prompt& p, const MaskSink& sink) { fn(f, p, sink); }
};
template <class F>
StreamingLambdaSegmenter<std::decay_t<F>> make_streaming_segmenter(F&& f) { return {std::forward<F>(f)}; }

// Collects a segmenter's answer for every frame (convenience for tests and small scenes).
template <Segmenter S>
std::vector<std::optional<Mask>> segment_all(S& s, const FrameSequence& frames, const Prompt& prompt) {
  std::vector<std::optional<Mask>> out(frames.size());
  s.segment(frames, prompt, [&](std::size_t k, const Mask* m) {
    if (k < out.size() && m) out[k] = *m;
  });
  return out;
}

}  // namespace vcar
