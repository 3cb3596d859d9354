#pragma once
// Several objects in one run (`vcar segment --prompts`). One coarse round serves every object:
// each training view is rendered once (with depth when the vote's occlusion test wants it), the
// segmenter is asked once per frame for every object's mask, and each object's vote (Eq. 1-3, or
// the robust vote) takes its mask. Then each object goes on alone, exactly as vcar::segment
// (algo/pipeline.hpp) does after its coarse vote: its own sphere (Eq. 4-5), view completeness
// (Eq. 6), SSS and fine round (Eq. 7-8) and ABR (Eq. 9-14). A Gaussian that two objects select
// goes to the one with the higher score (R_i of its last vote; ties to the earlier object).
//
// The vote is one accumulator per object, not MultiObjectVoting: the default robust vote and the
// occlusion test have no multi-object form; what the objects share is the rendering and the
// segmenter's round. tests.cmake checks that each object's result equals a single run's.
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/pipeline.hpp"

namespace vcar::cli {

struct ObjectPrompt {
  std::string name;
  Prompt prompt;          // reference_view: index of the training view the prompt is on
  int object_id = -1;     // the synthetic world's object (for the oracle and eval), -1 unknown
};

// One object asked of the segmenter in a round; prompt.reference_view is a frame of the round.
struct ObjectRequest {
  std::size_t object = 0;  // index into the run's objects
  std::string name;
  Prompt prompt;
};
// sink(frame, k, mask): the mask of requests[k] in that frame (null: no mask).
using ObjectMaskSink = std::function<void(std::size_t frame, std::size_t k, const Mask* mask)>;
using MultiSegmentFn = std::function<void(const FrameSequence&, const std::vector<ObjectRequest>&, const ObjectMaskSink&)>;

struct MultiSegmentation {
  std::vector<SegmentationResult> objects;   // aligned with the prompts; conflicts resolved
  std::size_t conflicts = 0;                 // Gaussians selected by more than one object
  std::vector<std::size_t> lost;             // per object: Gaussians it lost to another
  std::vector<std::pair<std::string, double>> timings_s;  // the shared coarse round
};

namespace detail_multi {

// One object's segmenter for the rounds it has alone (the fine round).
struct OneObject {
  const MultiSegmentFn* fn;
  ObjectRequest request;
  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    ObjectRequest r = request;
    r.prompt = prompt;
    r.prompt.reference_view = 0;  // run_round's frame 0 is the reference view
    (*fn)(frames, {r}, [&](std::size_t k, std::size_t, const Mask* m) { sink(k, m); });
  }
};

// Stages 2 and 3 of vcar::segment for one object, from its coarse selection (the same code
// path: algo/pipeline.hpp, "Stage 2" and "Stage 3").
template <Renderer R>
void finish_object(const GaussianScene& scene, const std::vector<Camera>& train_cameras, const Prompt& prompt,
                   R& renderer, OneObject& segmenter, const VcarParams& params, const ProgressCallback& progress,
                   vcar::detail::Clock::time_point t_start, std::vector<std::optional<RleMask>>& train_masks,
                   std::vector<Index> selected, std::vector<float> scores, SegmentationResult& result) {
  using vcar::detail::Clock;
  using vcar::detail::seconds_since;
  Diagnostics& diag = result.diagnostics;
  auto stage = [&](std::string_view name) {
    if (progress && !progress({name, 0, 0, seconds_since(t_start)})) throw Cancelled(std::string(name));
  };
  auto timing = [&](std::string name, double s) { diag.timings_s.emplace_back(std::move(name), s); };
  const std::size_t M = train_cameras.size();
  const std::size_t ref = prompt.reference_view;
  const std::vector<std::size_t> order = vcar::detail::training_order(M, ref);
  std::vector<Camera> frames;
  for (std::size_t j : order) frames.push_back(train_cameras[j]);
  auto keep_training_mask = [&](std::size_t j, const Mask* m) {
    train_masks[j] = m && params.enable_abr ? std::optional<RleMask>(RleMask::encode(*m)) : std::nullopt;
  };
  auto usable = [&](const Mask* m) -> const Mask* {
    if (!m || !(params.min_mask_fraction > 0.f)) return m;
    std::size_t fg = 0;
    for (std::uint8_t v : m->data) fg += v != 0;
    return static_cast<double>(fg) > params.min_mask_fraction * static_cast<double>(m->pixels()) ? m : nullptr;
  };
  diag.n_coarse = diag.n_fine = diag.n_final = selected.size();
  if (selected.empty()) {
    diag.note = "the coarse stage selected no Gaussian (no training view shows the target, or every mask is empty)";
    return;
  }
  AngularGap gap;
  if (params.enable_sss) {
    stage("view_completeness");
    auto tv = Clock::now();
    diag.sphere = robust_sphere(scene, selected, train_cameras[ref].position(), params.eta);
    const auto valid = valid_cameras(scene, selected, train_cameras, params.rho_min);
    diag.valid_cameras = valid.size();
    std::vector<Eigen::Vector3f> positions;
    for (std::size_t j : valid) positions.push_back(train_cameras[j].position());
    gap = max_angular_gap(fibonacci_lattice(params.K), headings(diag.sphere.c, positions));
    diag.max_gap_deg = gap.Delta_max_deg;
    diag.gap_direction = gap.direction;
    timing("vca", seconds_since(tv));
  }
  diag.sss_triggered = params.enable_sss && (params.force_sss || gap.Delta_max_deg > params.Delta_th_deg);
  if (diag.sss_triggered || params.force_fine_round) {
    stage("sss");
    if (diag.sss_triggered) {
      const Eigen::Vector3f up = estimate_scene_up(train_cameras);
      const Intrinsics intr = sampled_view_intrinsics(train_cameras[ref], params.sampled_intrinsics, params.sampled_fov_deg);
      diag.sampled_cameras = params.gap_directed
          ? gap_directed_cameras(diag.sphere, up, gap.direction, intr, params.gap_directed_views, params.gap_directed_cone_deg)
          : spiral_cameras(diag.sphere, up, intr, params);
    }
    const std::vector<Index> coarse_set = selected;
    std::vector<Camera> fine_frames;
    std::vector<std::size_t> fine_train;
    auto add_frame = [&](const Camera& c, std::size_t k) {
      if (k != 0 && params.min_frame_content > 0.f &&
          vcar::detail::content_fraction(scene, coarse_set, c, renderer) < params.min_frame_content)
        return;
      fine_frames.push_back(c);
      fine_train.push_back(k);
    };
    for (std::size_t k = 0; k < frames.size(); ++k) add_frame(frames[k], k);
    for (const Camera& c : diag.sampled_cameras) add_frame(c, static_cast<std::size_t>(-1));
    vcar::detail::RoundVote fine(scene, &coarse_set, params, true);
    for (auto& m : train_masks) m.reset();
    const vcar::detail::RoundTimes t2 = vcar::detail::run_round(
        "fine round (" + segmenter.request.name + ")", scene, &coarse_set, fine_frames, prompt, renderer, segmenter, params,
        progress, t_start, [&](std::size_t k, const Mask* m, const RenderOutput* render) {
          m = usable(m);
          vcar::detail::vote(fine, fine_frames[k], m, render, scene, &coarse_set, renderer, params);
          if (fine_train[k] < M) keep_training_mask(order[fine_train[k]], m);
        }, diag.masks_missing, fine.wants_depth());
    timing("fine_render", t2.render);
    timing("fine_segment", t2.total - t2.render - t2.voting);
    timing("fine_voting", t2.voting);
    fine.selected(params.tau_fine, selected, scores);
    diag.n_fine = diag.n_final = selected.size();
    if (selected.empty()) {
      diag.note = "the fine vote kept no Gaussian (tau_fine too high for these masks?)";
      return;
    }
  }
  result.log_scale = {std::vector<float>(selected.size()), std::vector<float>(selected.size()),
                      std::vector<float>(selected.size())};
  for (std::size_t k = 0; k < selected.size(); ++k)
    for (int d = 0; d < 3; ++d) result.log_scale[d][k] = scene.log_scale[d][selected[k]];
  if (params.enable_abr) {
    stage("abr");
    auto ta = Clock::now();
    BoundaryRefinement abr(scene, selected, params.abr());
    Mask scratch;
    for (std::size_t j = 0; j < M; ++j) {
      if (!train_masks[j]) continue;
      diag.mask_store_bytes += train_masks[j]->bytes();
      train_masks[j]->decode(scratch);
      abr.add_view(train_cameras[j], scratch);
    }
    AbrResult a = abr.finish();
    result.log_scale = std::move(a.log_scale);
    diag.abr_flagged = a.flagged;
    diag.abr_compressed = a.compressed;
    timing("abr", seconds_since(ta));
  }
  result.indices = std::move(selected);
  result.scores = std::move(scores);
  diag.n_final = result.indices.size();
}

}  // namespace detail_multi

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
template <Renderer R>
MultiSegmentation segment_objects(const GaussianScene& scene, const std::vector<Camera>& train_cameras,
                                  const std::vector<ObjectPrompt>& objects, R& renderer, const MultiSegmentFn& segmenter,
                                  const VcarParams& params = VcarParams::robust(), const ProgressCallback& progress = {}) {
  using vcar::detail::Clock;
  using vcar::detail::seconds_since;
  params.validate();
  if (scene.empty()) throw Error("the scene has no Gaussians", "scene");
  if (train_cameras.empty()) throw Error("no training cameras", "cameras");
  if (objects.empty()) throw Error("no object to segment", "prompts");
  for (const ObjectPrompt& o : objects)
    if (o.prompt.reference_view >= train_cameras.size())
      throw Error("reference view " + std::to_string(o.prompt.reference_view) + " out of range", "object '" + o.name + "'");
  for (const Camera& c : train_cameras) c.validate();

  const auto t_start = Clock::now();
  const std::size_t M = train_cameras.size(), K = objects.size();
  MultiSegmentation out;
  out.objects.resize(K);
  for (auto& r : out.objects) r.diagnostics.n_scene = scene.size();

  // ---- the shared coarse round: frames in the first object's order (its reference first).
  const std::vector<std::size_t> order = vcar::detail::training_order(M, objects[0].prompt.reference_view);
  std::vector<Camera> frames;
  std::vector<std::size_t> frame_of(M);
  for (std::size_t k = 0; k < M; ++k) {
    frames.push_back(train_cameras[order[k]]);
    frame_of[order[k]] = k;
  }
  std::vector<ObjectRequest> requests;
  for (std::size_t o = 0; o < K; ++o) {
    ObjectRequest r{o, objects[o].name, objects[o].prompt};
    r.prompt.reference_view = frame_of[objects[o].prompt.reference_view];
    requests.push_back(std::move(r));
  }
  std::vector<std::unique_ptr<vcar::detail::RoundVote>> votes;
  for (std::size_t o = 0; o < K; ++o) votes.push_back(std::make_unique<vcar::detail::RoundVote>(scene, nullptr, params, false));
  const bool depth = votes[0]->wants_depth();
  std::vector<std::vector<std::optional<RleMask>>> train_masks(K, std::vector<std::optional<RleMask>>(M));
  std::vector<std::vector<bool>> seen(K, std::vector<bool>(M, false));
  std::optional<std::pair<std::size_t, RenderOutput>> last;  // one render per frame, shared by the objects
  double t_render = 0, t_vote = 0;
  auto render_frame = [&](std::size_t k, bool want_depth) {
    const auto tr = Clock::now();
    RenderRequest q;
    q.scene = &scene;
    q.camera = &frames[k];
    q.background = params.background;
    q.want_depth = want_depth;
    RenderOutput r = renderer.render(q);
    t_render += seconds_since(tr);
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
  auto usable = [&](const Mask* m) -> const Mask* {
    if (!m || !(params.min_mask_fraction > 0.f)) return m;
    std::size_t fg = 0;
    for (std::uint8_t v : m->data) fg += v != 0;
    return static_cast<double>(fg) > params.min_mask_fraction * static_cast<double>(m->pixels()) ? m : nullptr;
  };
  ObjectMaskSink sink = [&](std::size_t k, std::size_t q, const Mask* m) {
    if (k >= frames.size() || q >= K)
      throw Error("segmenter answered frame " + std::to_string(k) + " object " + std::to_string(q), "coarse round");
    const Camera& cam = frames[k];
    const std::string where = "coarse round, view '" + cam.name + "', object '" + objects[q].name + "'";
    if (seen[q][k]) throw Error("segmenter answered a frame twice", where);
    seen[q][k] = true;
    if (m && (m->width != cam.width || m->height != cam.height || m->channels != 1))
      throw Error("mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) + ", the view is " +
                      std::to_string(cam.width) + "x" + std::to_string(cam.height), where);
    if (!m) ++out.objects[q].diagnostics.masks_missing;
    m = usable(m);
    const RenderOutput* render = last && last->first == k ? &last->second : nullptr;
    if (depth && m && !render) {  // rendered once for this frame, then shared by the other objects
      last.emplace(k, render_frame(k, true));
      render = &last->second;
    }
    const auto tv = Clock::now();
    vcar::detail::vote(*votes[q], cam, m, render, scene, nullptr, renderer, params);
    train_masks[q][order[k]] = m && params.enable_abr ? std::optional<RleMask>(RleMask::encode(*m)) : std::nullopt;
    t_vote += seconds_since(tv);
    if (q + 1 == K && progress && !progress({"coarse round (all objects)", k + 1, M, seconds_since(t_start)}))
      throw Cancelled("coarse round");
  };
  if (progress && !progress({"coarse", 0, 0, 0.0})) throw Cancelled("coarse");
  const auto t1 = Clock::now();
  try {
    segmenter(seq, requests, sink);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(std::string("segmenter failed: ") + e.what(), "coarse round");
  }
  for (std::size_t o = 0; o < K; ++o)
    for (std::size_t k = 0; k < M; ++k)
      if (!seen[o][k]) ++out.objects[o].diagnostics.masks_missing;
  const double t_total = seconds_since(t1);
  out.timings_s = {{"coarse_render", t_render}, {"coarse_segment", t_total - t_render - t_vote}, {"coarse_voting", t_vote}};

  // ---- each object alone: sphere, view completeness, SSS + fine round, ABR.
  for (std::size_t o = 0; o < K; ++o) {
    std::vector<Index> selected;
    std::vector<float> scores;
    votes[o]->selected(params.tau_coarse, selected, scores);
    votes[o].reset();  // its counters are not needed any more
    detail_multi::OneObject one{&segmenter, ObjectRequest{o, objects[o].name, objects[o].prompt}};
    const auto to = Clock::now();
    detail_multi::finish_object(scene, train_cameras, objects[o].prompt, renderer, one, params, progress, t_start,
                                train_masks[o], std::move(selected), std::move(scores), out.objects[o]);
    out.objects[o].diagnostics.timings_s.emplace_back("total", seconds_since(to));
  }
  out.conflicts = resolve_conflicts(out.objects, scene.size(), out.lost);
  out.timings_s.emplace_back("total", seconds_since(t_start));
  return out;
}

}  // namespace vcar::cli
