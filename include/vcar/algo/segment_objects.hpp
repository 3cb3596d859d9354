#pragma once
// vcar::segment_objects: several objects in one run. One coarse round serves every object: each
// training view is rendered once (with depth when the vote's occlusion test wants it), the
// segmenter (a MultiSegmenter, concepts/multi_segmenter.hpp) is asked once per frame for every
// object's mask, and each object's vote (Eq. 1-3, or the robust vote) takes its mask. Then each
// object goes on alone, exactly as vcar::segment (algo/pipeline.hpp) does after its coarse vote:
// its own sphere (Eq. 4-5), view completeness (Eq. 6), SSS and fine round (Eq. 7-8) and ABR
// (Eq. 9-14). The fine rounds of all objects go to the segmenter in one batched call: each
// object's frames (renders of its own G_coarse) one after the other, each object asked about its
// own frames only (ObjectRequest::first_frame, frames), so an external segmenter starts once for
// them all (two calls per run, not one per object and round).
// A Gaussian that two objects select goes to the one with the higher score (R_i of its last
// vote; ties to the earlier object): resolve_conflicts.
//
// The vote is one accumulator per object, not MultiObjectVoting: the robust vote and the
// occlusion test have no multi-object form; what the objects share is the rendering and the
// segmenter's calls. Each object's result equals vcar::segment's with the same masks
// (examples/vcar_cli/tests.cmake checks it through `vcar segment --prompts`).
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/concepts/multi_segmenter.hpp"

namespace vcar {

struct ObjectPrompt {
  std::string name;
  Prompt prompt;          // reference_view: index of the training view the prompt is on
  int object_id = -1;     // the synthetic world's object (for the oracle and eval), -1 unknown
};

// The segmenter behind a function, as segment_objects calls it.
using MultiSegmentFn = std::function<void(const FrameSequence&, const std::vector<ObjectRequest>&, const ObjectMaskSink&)>;

struct MultiSegmentation {
  std::vector<SegmentationResult> objects;   // aligned with the prompts; conflicts resolved
  std::size_t conflicts = 0;                 // Gaussians selected by more than one object
  std::vector<std::size_t> lost;             // per object: Gaussians it lost to another
  std::size_t segmenter_calls = 0;           // 2 with fine rounds (coarse, batched fine), 1 without
  std::vector<std::pair<std::string, double>> timings_s;  // the shared coarse round
};

namespace detail {

// One call of the segmenter; its failures other than vcar::Error become one naming the round.
inline void ask(const MultiSegmentFn& segmenter, const FrameSequence& seq, const std::vector<ObjectRequest>& requests,
                const ObjectMaskSink& sink, const char* round) {
  try {
    segmenter(seq, requests, sink);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(std::string("segmenter failed: ") + e.what(), round);
  }
}

// Stages 2 and 3 of every object (ObjectRefinement), their fine rounds in one
// segmenter call: the frames of object a, then of object b, ..., each frame rendered from its
// object's G_coarse; each object's request covers its own frames, its prompt on the first of
// them (the reference view). Timings per object: its renders and votes; the segmenter's own
// time of the call shared in proportion to the object's frames. "total": the object's share.
template <Renderer R>
void refine_objects(const GaussianScene& scene, const std::vector<Camera>& train_cameras,
                    const std::vector<ObjectPrompt>& objects, R& renderer, const MultiSegmentFn& segmenter,
                    const VcarParams& params, const ProgressCallback& progress, Clock::time_point t_start,
                    std::vector<std::unique_ptr<RoundVote>>& votes,
                    std::vector<std::vector<std::optional<RleMask>>>& train_masks,
                    std::vector<SegmentationResult>& results) {
  const std::size_t K = objects.size();
  std::vector<std::unique_ptr<ObjectRefinement>> refine(K);
  std::vector<bool> alive(K);
  std::vector<double> own_s(K, 0.0);  // each object's time outside the shared call's segmenter
  for (std::size_t o = 0; o < K; ++o) {
    const auto to = Clock::now();
    std::vector<Index> selected;
    std::vector<float> scores;
    coarse_selection(*votes[o], params, results[o].diagnostics, selected, scores);  // as vcar::segment
    refine[o] = std::make_unique<ObjectRefinement>(scene, train_cameras, objects[o].prompt, params,
                                                                 train_masks[o], std::move(selected), std::move(scores),
                                                                 results[o]);
    alive[o] = refine[o]->start(renderer, progress, t_start);
    own_s[o] += seconds_since(to);
  }

  // ---- the batched fine round
  std::vector<Camera> frames;
  std::vector<std::size_t> owner;  // frame -> object
  std::vector<ObjectRequest> requests;
  for (std::size_t o = 0; o < K; ++o) {
    if (!alive[o] || !refine[o]->has_round()) continue;
    ObjectRequest r{objects[o].name, objects[o].prompt, frames.size(), refine[o]->frames().size(), o};
    r.prompt.reference_view = frames.size();  // the object's first frame is its reference view
    for (const Camera& c : refine[o]->frames()) {
      frames.push_back(c);
      owner.push_back(o);
    }
    requests.push_back(std::move(r));
  }
  if (!requests.empty()) {
    std::vector<double> t_render(K, 0.0), t_vote(K, 0.0);
    std::vector<bool> seen(frames.size(), false);
    std::optional<std::pair<std::size_t, RenderOutput>> last;  // the latest render, when its object votes with depth
    FrameSequence seq;
    seq.cameras = frames;
    seq.subset = true;
    seq.drawn = [&](std::size_t k) -> const std::vector<Index>* {  // each frame its own object's G_coarse
      if (k >= frames.size()) throw Error("frame " + std::to_string(k) + " out of range", "fine round (all objects)");
      return &refine[owner[k]]->coarse_set();
    };
    seq.image = [&](std::size_t k) -> ImageRGB8 {
      if (k >= frames.size()) throw Error("frame " + std::to_string(k) + " out of range", "fine round (all objects)");
      const std::size_t o = owner[k];
      const auto tr = Clock::now();
      const RenderNeed need = refine[o]->render_need();
      RenderOutput r = render_view(renderer, scene, frames[k], &refine[o]->coarse_set(), params.background,
                                   need.kept && need.depth);
      ImageRGB8 img = to_8bit(r.rgb);
      if (need.kept) last.emplace(k, std::move(r));
      t_render[o] += seconds_since(tr);
      return img;
    };
    ObjectMaskSink sink = [&](std::size_t k, std::size_t q, const Mask* m) {
      if (q >= requests.size() || !requests[q].covers(k))
        throw Error("segmenter answered frame " + std::to_string(k) + " for request " + std::to_string(q) +
                        ", which does not cover it", "fine round (all objects)");
      const std::size_t o = requests[q].object;
      const Camera& cam = frames[k];
      const std::string where = "fine round (" + objects[o].name + "), view '" + cam.name + "'";
      if (seen[k]) throw Error("segmenter answered a frame twice", where);
      seen[k] = true;
      check_mask(m, cam, where);
      if (!m) ++results[o].diagnostics.masks_missing;
      const auto tv = Clock::now();
      refine[o]->on_mask(k - requests[q].first_frame, m, last && last->first == k ? &last->second : nullptr, renderer);
      t_vote[o] += seconds_since(tv);
      if (progress && !progress({"fine round (all objects)", k + 1, frames.size(), seconds_since(t_start)}))
        throw Cancelled("fine round (all objects)");
    };
    const auto t1 = Clock::now();
    ask(segmenter, seq, requests, sink, "fine round (all objects)");
    double segment_s = seconds_since(t1);
    for (std::size_t o = 0; o < K; ++o) segment_s -= t_render[o] + t_vote[o];
    for (const ObjectRequest& r : requests) {
      const std::size_t o = r.object;
      for (std::size_t k = r.first_frame; k < r.first_frame + r.frames; ++k)
        if (!seen[k]) ++results[o].diagnostics.masks_missing;
      const double share = segment_s * static_cast<double>(r.frames) / static_cast<double>(frames.size());
      const auto te = Clock::now();
      alive[o] = refine[o]->end_round(t_render[o], share, t_vote[o]);
      own_s[o] += t_render[o] + t_vote[o] + share + seconds_since(te);
    }
  }
  for (std::size_t o = 0; o < K; ++o) {
    const auto tf = Clock::now();
    if (alive[o]) refine[o]->finish(progress, t_start);
    refine[o].reset();
    votes[o].reset();  // its counters are not needed any more
    results[o].diagnostics.timings_s.emplace_back("total", own_s[o] + seconds_since(tf));
  }
}

}  // namespace detail

// A Gaussian selected by several objects stays with the highest score (ties: the earlier
// object); the others drop it (index, score and refined scale). Returns the number of such
// Gaussians; `lost[o]` counts what object o gave up.
inline std::size_t resolve_conflicts(std::vector<SegmentationResult>& objects, std::size_t scene_size,
                                     std::vector<std::size_t>& lost) {
  std::vector<std::int32_t> owner(scene_size, -1);
  std::vector<float> best(scene_size, 0.f);
  std::vector<std::uint8_t> claims(scene_size, 0);
  for (std::size_t o = 0; o < objects.size(); ++o) {
    const SegmentationResult& r = objects[o];
    for (std::size_t k = 0; k < r.indices.size(); ++k) {
      const Index i = r.indices[k];
      const float s = k < r.scores.size() ? r.scores[k] : 0.f;
      if (claims[i] < 255) ++claims[i];
      if (owner[i] < 0 || s > best[i]) {
        owner[i] = static_cast<std::int32_t>(o);
        best[i] = s;
      }
    }
  }
  lost.assign(objects.size(), 0);
  std::size_t conflicts = 0;
  for (std::size_t i = 0; i < scene_size; ++i) conflicts += claims[i] > 1;
  for (std::size_t o = 0; o < objects.size(); ++o) {
    SegmentationResult& r = objects[o];
    const bool scaled = !r.log_scale[0].empty();
    std::size_t w = 0;
    for (std::size_t k = 0; k < r.indices.size(); ++k) {
      if (owner[r.indices[k]] != static_cast<std::int32_t>(o)) {
        ++lost[o];
        continue;
      }
      r.indices[w] = r.indices[k];
      if (k < r.scores.size()) r.scores[w] = r.scores[k];
      if (scaled)
        for (int d = 0; d < 3; ++d) r.log_scale[d][w] = r.log_scale[d][k];
      ++w;
    }
    r.indices.resize(w);
    if (!r.scores.empty()) r.scores.resize(w);
    if (scaled)
      for (int d = 0; d < 3; ++d) r.log_scale[d].resize(w);
    r.diagnostics.n_final = w;
  }
  return conflicts;
}

// Segments every object of `objects` (see the top of this file). Throws like vcar::segment.
template <Renderer R, MultiSegmenter S>
MultiSegmentation segment_objects(const GaussianScene& scene, const std::vector<Camera>& train_cameras,
                                  const std::vector<ObjectPrompt>& objects, R& renderer, S& source,
                                  const VcarParams& params = VcarParams::robust(), const ProgressCallback& progress = {}) {
  params.validate();
  if (scene.empty()) throw Error("the scene has no Gaussians", "scene");
  if (train_cameras.empty()) throw Error("no training cameras", "cameras");
  if (objects.empty()) throw Error("no object to segment", "prompts");
  for (const ObjectPrompt& o : objects)
    if (o.prompt.reference_view >= train_cameras.size())
      throw Error("reference view " + std::to_string(o.prompt.reference_view) + " out of range", "object '" + o.name + "'");
  for (const Camera& c : train_cameras) c.validate();

  const auto t_start = detail::Clock::now();
  const std::size_t M = train_cameras.size(), K = objects.size();
  MultiSegmentation out;
  const MultiSegmentFn segmenter = [&](const FrameSequence& f, const std::vector<ObjectRequest>& r, const ObjectMaskSink& s) {
    ++out.segmenter_calls;
    source.segment_objects(f, r, s);
  };
  out.objects.resize(K);
  for (auto& r : out.objects) r.diagnostics.n_scene = scene.size();

  // ---- the shared coarse round: frames in the first object's order (its reference first).
  const std::vector<std::size_t> order = detail::training_order(M, objects[0].prompt.reference_view);
  std::vector<Camera> frames;
  std::vector<std::size_t> frame_of(M);
  for (std::size_t k = 0; k < M; ++k) {
    frames.push_back(train_cameras[order[k]]);
    frame_of[order[k]] = k;
  }
  std::vector<ObjectRequest> requests;
  for (std::size_t o = 0; o < K; ++o) {
    ObjectRequest r{objects[o].name, objects[o].prompt, 0, M, o};
    r.prompt.reference_view = frame_of[objects[o].prompt.reference_view];
    requests.push_back(std::move(r));
  }
  std::vector<std::unique_ptr<detail::RoundVote>> votes;
  for (std::size_t o = 0; o < K; ++o) votes.push_back(std::make_unique<detail::RoundVote>(scene, nullptr, params, false));
  const bool depth = votes[0]->wants_depth();
  std::vector<std::vector<std::optional<RleMask>>> train_masks(K, std::vector<std::optional<RleMask>>(M));
  std::vector<std::vector<bool>> seen(K, std::vector<bool>(M, false));
  std::optional<std::pair<std::size_t, RenderOutput>> last;  // one render per frame, shared by the objects
  double t_render = 0, t_vote = 0;
  auto render_frame = [&](std::size_t k, bool want_depth) {
    const auto tr = detail::Clock::now();
    RenderOutput r = detail::render_view(renderer, scene, frames[k], nullptr, params.background, want_depth);
    t_render += detail::seconds_since(tr);
    return r;
  };
  FrameSequence seq;
  seq.cameras = frames;
  seq.image = [&](std::size_t k) -> ImageRGB8 {
    if (k >= frames.size()) throw Error("frame " + std::to_string(k) + " out of range", "coarse round");
    RenderOutput r = render_frame(k, depth);
    ImageRGB8 img = to_8bit(r.rgb);
    if (depth) last.emplace(k, std::move(r));
    return img;
  };
  Mask scratch;  // a mask eroded by Eq. R11
  ObjectMaskSink sink = [&](std::size_t k, std::size_t q, const Mask* m) {
    if (k >= frames.size() || q >= K)
      throw Error("segmenter answered frame " + std::to_string(k) + " object " + std::to_string(q), "coarse round");
    const Camera& cam = frames[k];
    const std::string where = "coarse round, view '" + cam.name + "', object '" + objects[q].name + "'";
    if (seen[q][k]) throw Error("segmenter answered a frame twice", where);
    seen[q][k] = true;
    detail::check_mask(m, cam, where);
    if (!m) ++out.objects[q].diagnostics.masks_missing;
    m = detail::usable(m, params);
    const RenderOutput* render = last && last->first == k ? &last->second : nullptr;
    if (depth && m && !render) {  // rendered once for this frame, then shared by the other objects
      last.emplace(k, render_frame(k, true));
      render = &last->second;
    }
    const auto tv = detail::Clock::now();
    m = detail::vote(*votes[q], cam, m, render, scene, nullptr, renderer, params, scratch);
    train_masks[q][order[k]] = m && params.enable_abr ? std::optional<RleMask>(RleMask::encode(*m)) : std::nullopt;
    t_vote += detail::seconds_since(tv);
    if (q + 1 == K && progress && !progress({"coarse round (all objects)", k + 1, M, detail::seconds_since(t_start)}))
      throw Cancelled("coarse round");
  };
  if (progress && !progress({"coarse", 0, 0, 0.0})) throw Cancelled("coarse");
  const auto t1 = detail::Clock::now();
  detail::ask(segmenter, seq, requests, sink, "coarse round");
  for (std::size_t o = 0; o < K; ++o)
    for (std::size_t k = 0; k < M; ++k)
      if (!seen[o][k]) ++out.objects[o].diagnostics.masks_missing;
  const double t_total = detail::seconds_since(t1);
  out.timings_s = {{"coarse_render", t_render}, {"coarse_segment", t_total - t_render - t_vote}, {"coarse_voting", t_vote}};

  // ---- each object alone: sphere, view completeness, SSS cameras; one batched fine round;
  // then each object's fine selection and ABR (exactly as vcar::segment runs them).
  detail::refine_objects(scene, train_cameras, objects, renderer, segmenter, params, progress, t_start, votes,
                         train_masks, out.objects);
  out.conflicts = resolve_conflicts(out.objects, scene.size(), out.lost);
  out.timings_s.emplace_back("total", detail::seconds_since(t_start));
  return out;
}

}  // namespace vcar
