#pragma once
// The MultiSegmenter concept: a source of 2D masks of several objects at once, for
// vcar::segment_objects (algo/segment_objects.hpp), which asks it twice per run: once in the
// coarse round (every object about every frame) and once for the fine rounds of all objects
// (each object about its own frames, renders of its own G_coarse, one object after the other).
//
// `s.segment_objects(frames, requests, sink)`:
//  - `frames` as for a Segmenter (concepts/segmenter.hpp); `frames.drawn(k)` names what frame k
//    draws (each object's fine frames draw its own G_coarse);
//  - `requests[q]` asks about object `requests[q].object` (an index into the run's objects),
//    named `name`, prompted by `prompt` on frame `prompt.reference_view` of this call, on frames
//    [first_frame, first_frame + frames) only;
//  - the segmenter calls `sink(k, q, &mask)` (or `sink(k, q, nullptr)`: no mask) at most once per
//    frame k that request q covers; frames never reported count as "no mask". Masks as for a
//    Segmenter: the frame's width x height, one channel, nonzero = foreground.
// Errors: throw; the pipeline rethrows as vcar::Error naming the round.
//
// Models: io::ExternalSegmenter (one program run per call), a lambda (make_multi_segmenter), and
// EachObject below, which asks a single-object Segmenter per object about its frames.
#include <algorithm>
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vcar/concepts/segmenter.hpp"

namespace vcar {

struct ObjectRequest {
  static constexpr std::size_t all_frames = static_cast<std::size_t>(-1);
  std::string name;
  Prompt prompt;                    // reference_view: a frame of this call, inside the range
  std::size_t first_frame = 0;      // the frames asked about:
  std::size_t frames = all_frames;  //   [first_frame, first_frame + frames); all_frames: to the end
  std::size_t object = 0;           // which of the run's objects (an index into its prompts)
  bool covers(std::size_t k) const { return k >= first_frame && (frames == all_frames || k - first_frame < frames); }
};

// sink(frame, q, mask): the mask of requests[q] in that frame (null: no mask).
using ObjectMaskSink = std::function<void(std::size_t frame, std::size_t request, const Mask* mask)>;

template <class S>
concept MultiSegmenter = requires(S& s, const FrameSequence& f, const std::vector<ObjectRequest>& r,
                                  const ObjectMaskSink& sink) {
  { s.segment_objects(f, r, sink) };
};

// Adapter from a callable void(const FrameSequence&, const std::vector<ObjectRequest>&,
// const ObjectMaskSink&).
template <class F>
struct LambdaMultiSegmenter {
  F fn;
  void segment_objects(const FrameSequence& f, const std::vector<ObjectRequest>& r, const ObjectMaskSink& sink) {
    fn(f, r, sink);
  }
};
template <class F>
LambdaMultiSegmenter<std::decay_t<F>> make_multi_segmenter(F&& f) { return {std::forward<F>(f)}; }

// Several objects through single-object Segmenters, `per_object[o]` for object o: each request
// is one call of its object's segmenter on the request's frames, re-ordered so that the frame of
// its prompt comes first (a Segmenter's frame 0 is the prompt's), the others in their order.
template <Segmenter S>
class EachObject {
public:
  explicit EachObject(std::span<S> per_object) : per_object_(per_object) {}

  void segment_objects(const FrameSequence& f, const std::vector<ObjectRequest>& requests, const ObjectMaskSink& sink) {
    for (std::size_t q = 0; q < requests.size(); ++q) {
      const ObjectRequest& r = requests[q];
      if (r.object >= per_object_.size())
        throw Error("object " + std::to_string(r.object) + " has no segmenter (" + std::to_string(per_object_.size()) +
                        " given)", "EachObject");
      const std::size_t first = std::min(r.first_frame, f.size());
      const std::size_t end = r.frames == ObjectRequest::all_frames ? f.size() : std::min(f.size(), first + r.frames);
      std::vector<std::size_t> map;  // frame of the call -> frame of `f`
      if (r.prompt.reference_view >= first && r.prompt.reference_view < end) map.push_back(r.prompt.reference_view);
      for (std::size_t k = first; k < end; ++k)
        if (map.empty() || k != map.front()) map.push_back(k);
      std::vector<Camera> cameras;
      for (std::size_t k : map) cameras.push_back(f.cameras[k]);
      FrameSequence one;
      one.cameras = cameras;
      one.subset = f.subset;
      if (f.image) one.image = [&](std::size_t k) { return f.image(map.at(k)); };
      if (f.drawn) one.drawn = [&](std::size_t k) { return f.drawn(map.at(k)); };
      Prompt prompt = r.prompt;
      prompt.reference_view = 0;
      per_object_[r.object].segment(one, prompt, [&](std::size_t k, const Mask* m) { sink(map.at(k), q, m); });
    }
  }

private:
  std::span<S> per_object_;
};

}  // namespace vcar
