#pragma once
// OracleSegmenter: a vcar::Segmenter that answers any camera (training, sampled, evaluation)
// from exact ground truth, with seeded failure models that can be combined. Deterministic from
// (seed, frame index, camera): the same call gives the same masks.
//
// Which ground truth a frame gets (`mode`):
//  - visible: the target where it is the nearest surface, what SAM sees in a render of the
//    full scene (occluders cut it); ray cast, never rendering (frames.image() is not called);
//  - silhouette: the target alone, what SAM sees when the frame is a render of a subset that
//    holds only the target (e.g. SSS views of G_coarse: the pipeline renders only the coarse
//    Gaussians, so the neighbour that would occlude is not drawn);
//  - by_name (default): silhouette for cameras whose name starts with `silhouette_prefix`
//    ("sss_") and for every frame of a sequence that renders a subset (FrameSequence::subset,
//    the fine round's renders of G_coarse: the occluders are not drawn), visible otherwise.
//    The fine round's answer is then the target's analytic silhouette whatever G_coarse holds;
//  - rendered (honest): what the frame's render draws (FrameSequence::drawn: the whole scene,
//    or G_coarse in the fine round): a pixel is the target's where the target's Gaussians
//    dominate its rendered weight (synth/rendered_labels.hpp). Pieces of other objects kept in
//    G_coarse stay out of the mask, pieces of the target dropped from it are missing. Needs the
//    constructor with a renderer; a subset frame without FrameSequence::drawn is an error.
// Failure models, applied in this order: drop (no mask) with p_drop; the neighbour's mask
// instead of the target's with p_swap; the SAM-like failures of `sam` (synth/sam_failures.hpp:
// another object's mask, a part of the object, a touching background piece included, drift
// along the sequence; they read the labels the frame shows: the rendered labels in rendered
// mode, the full scene's ray cast otherwise); dilation (k > 0) / erosion (k < 0) by a Euclidean
// disc of |k| px; a random shift of up to jitter_px in x and y; n_blobs false-positive discs of
// radius blob_radius_px at uniform centres. The SAM-like failures draw from streams of their
// own (one each), so turning one on changes no other model's draws.
#include <cstdint>
#include <cstring>
#include <deque>
#include <functional>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/random.hpp"
#include "vcar/synth/rendered_labels.hpp"
#include "vcar/synth/sam_failures.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

enum class OracleMode { visible, silhouette, by_name, rendered };

struct OracleParams {
  OracleMode mode = OracleMode::by_name;
  std::string silhouette_prefix = "sss_";
  std::uint64_t seed = 1;
  int dilate_px = 0;            // > 0 dilates, < 0 erodes (Euclidean disc)
  int n_blobs = 0;              // false-positive discs per frame
  float blob_radius_px = 6.f;
  double p_drop = 0.0;          // probability of "no mask" for a frame
  double p_swap = 0.0;          // probability of the neighbour's mask instead of the target's
  int jitter_px = 0;            // random shift in [-jitter_px, jitter_px] per axis and frame
  int target_id = -1;           // the object to answer with (-1: the world's target_id)
  SamFailures sam;              // wrong object, part, leak, drift (synth/sam_failures.hpp)

  void validate() const {
    if (!(p_drop >= 0.0 && p_drop <= 1.0)) throw Error("must be in [0, 1]", "OracleParams.p_drop");
    if (!(p_swap >= 0.0 && p_swap <= 1.0)) throw Error("must be in [0, 1]", "OracleParams.p_swap");
    if (n_blobs < 0) throw Error("must be >= 0", "OracleParams.n_blobs");
    if (jitter_px < 0) throw Error("must be >= 0", "OracleParams.jitter_px");
    if (!(blob_radius_px >= 0.f)) throw Error("must be >= 0", "OracleParams.blob_radius_px");
    sam.validate();
  }
};

class OracleSegmenter {
public:
  // Primitives only: inserted Gaussian objects are invisible to this oracle (no rendered mode).
  OracleSegmenter(const World& world, OracleParams params = {}) : world_(&world), p_(std::move(params)) {
    p_.validate();
    if (p_.mode == OracleMode::rendered)
      throw Error("the rendered mode needs a renderer (the constructor with one)", "OracleParams.mode");
  }
  // With a renderer for the inserted Gaussian objects and the rendered mode (kept by reference:
  // it must outlive this). `labels`: the rendered mode's label copies of this world's scene,
  // shared by several oracles (null: prepared here when the mode is rendered).
  template <Renderer R>
  OracleSegmenter(const World& world, OracleParams params, R& renderer,
                  std::shared_ptr<const RenderedLabels> labels = nullptr)
      : world_(&world), p_(std::move(params)) {
    p_.validate();
    if (!world.inserted.empty())
      render_ = [&renderer](IdImage& img, const World& w, const Camera& cam, int only) {
        add_inserted(img, w, cam, renderer, only);
      };
    if (p_.mode == OracleMode::rendered) {
      render_request_ = [&renderer](const RenderRequest& q) { return renderer.render(q); };
      labels_ = labels ? std::move(labels) : std::make_shared<const RenderedLabels>(world);
      if (labels_->scene_size() != world.scene.size())
        throw Error("the rendered labels are of another scene", "OracleSegmenter");
    }
  }

  const OracleParams& params() const { return p_; }

  // The ray casts (and label renders) of one frame, kept for the oracles (of one world) asked
  // about it in turn: the ones that see the frame as the full scene share one cast, as an image
  // model that encodes a frame once for every prompt does (the several-objects run's coarse
  // round); in rendered mode the ones that see the same drawn set share its label renders.
  class FrameCasts {
  public:
    const IdImage& get(const OracleSegmenter& o, const Camera& cam, int only) {
      start(o, cam);
      for (const auto& [key, img] : cache_)
        if (key == only) return img;
      IdImage img = raycast(*o.world_, cam, only);
      if (o.render_) o.render_(img, *o.world_, cam, only);
      return cache_.emplace_back(only, std::move(img)).second;
    }
    // The labels the frame shows when it draws `drawn` (null: the whole scene); rendered mode.
    const IdImage& rendered(const OracleSegmenter& o, const Camera& cam, const std::vector<Index>* drawn) {
      start(o, cam);
      for (const auto& [key, img] : rendered_)
        if (key == drawn) return img;
      auto r = make_renderer([&o](const RenderRequest& q) { return o.render_request_(q); });
      return rendered_.emplace_back(drawn, o.labels_->label_image(cam, drawn, r)).second;
    }

  private:
    void start(const OracleSegmenter& o, const Camera& cam) {
      if (cam_ != &cam || world_ != o.world_) { cache_.clear(); rendered_.clear(); }
      cam_ = &cam;
      world_ = o.world_;
    }
    const Camera* cam_ = nullptr;
    const World* world_ = nullptr;
    std::deque<std::pair<int, IdImage>> cache_;  // a deque: references stay valid as it grows
    std::deque<std::pair<const std::vector<Index>*, IdImage>> rendered_;
  };

  // The answer for one frame: nullopt when dropped. `subset`: the frame renders a subset of the
  // scene (by_name answers it with the silhouette); `drawn`: which (FrameSequence::drawn; null:
  // the whole scene, or unknown when `subset`), read by the rendered mode only.
  std::optional<Mask> mask(const Camera& cam, std::size_t frame, bool subset = false) const {
    FrameCasts casts;
    return mask(cam, frame, subset, casts);
  }
  // The same, the ray cast taken from (or added to) `casts` of this frame.
  std::optional<Mask> mask(const Camera& cam, std::size_t frame, bool subset, FrameCasts& casts,
                           const std::vector<Index>* drawn = nullptr) const {
    Rng rng(p_.seed, hash_combine(frame, hash_string(cam.name)), pose_hash(cam));
    if (rng.uniform_d() < p_.p_drop) return std::nullopt;
    const int target = p_.target_id >= 0 ? p_.target_id : world_->target_id;
    const int id = rng.uniform_d() < p_.p_swap ? world_->neighbour_id : target;
    Mask m;
    const IdImage* labels = nullptr;  // what the frame shows, for the SAM-like failures
    if (p_.mode == OracleMode::rendered) {
      if (subset && !drawn)
        throw Error("frame " + std::to_string(frame) + " renders a subset but does not say which Gaussians "
                    "(FrameSequence::drawn)", "OracleSegmenter, rendered mode");
      labels = &casts.rendered(*this, cam, drawn);
      m = mask_of(*labels, id);
    } else {
      const bool sil = p_.mode == OracleMode::silhouette ||
                       (p_.mode == OracleMode::by_name &&
                        (subset || (!p_.silhouette_prefix.empty() && cam.name.rfind(p_.silhouette_prefix, 0) == 0)));
      m = mask_of(casts.get(*this, cam, sil ? id : any_object), id);
      if (p_.sam.needs_labels()) labels = &casts.get(*this, cam, any_object);
    }
    if (p_.sam.any()) sam_failures(m, labels, id, target, cam, frame);
    m = dilate_erode(m, p_.dilate_px);
    const int dx = p_.jitter_px > 0 ? rng.uniform_int(-p_.jitter_px, p_.jitter_px) : 0;
    const int dy = p_.jitter_px > 0 ? rng.uniform_int(-p_.jitter_px, p_.jitter_px) : 0;
    if (dx != 0 || dy != 0) m = shift(m, dx, dy);
    for (int b = 0; b < p_.n_blobs; ++b) {
      const float cx = rng.uniform(0.f, static_cast<float>(m.width)), cy = rng.uniform(0.f, static_cast<float>(m.height));
      paint_disc(m, cx, cy, p_.blob_radius_px);
    }
    return m;
  }

  void segment(const FrameSequence& frames, const Prompt& /*prompt: the target is known*/, const MaskSink& sink) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
      FrameCasts casts;
      const std::vector<Index>* drawn = frames.drawn ? frames.drawn(k) : nullptr;  // null: the whole scene
      const bool subset = frames.drawn ? drawn != nullptr : frames.subset;
      const std::optional<Mask> m = mask(frames.cameras[k], k, subset, casts, drawn);
      sink(k, m ? &*m : nullptr);
    }
  }

private:
  static std::uint64_t pose_hash(const Camera& c) {
    std::uint64_t h = 0x5EEDu;
    auto add = [&](float v) { std::uint32_t b; std::memcpy(&b, &v, 4); h = hash_combine(h, b); };
    for (int r = 0; r < 3; ++r) { for (int k = 0; k < 3; ++k) add(c.R_w(r, k)); add(c.t_w[r]); }
    add(c.fx); add(c.fy); add(c.cx); add(c.cy);
    return hash_combine(h, (static_cast<std::uint64_t>(c.width) << 32) | static_cast<std::uint32_t>(c.height));
  }

  // synth/sam_failures.hpp, in its order; `id`: the object whose mask m is, `target` the oracle's.
  void sam_failures(Mask& m, const IdImage* labels, int id, int target, const Camera& cam, std::size_t frame) const {
    const std::uint64_t key = hash_combine(hash_combine(p_.seed, 0x5A3F41u), hash_combine(hash_combine(frame, hash_string(cam.name)), pose_hash(cam)));
    Rng r_wrong(key, 1), r_part(key, 2), r_leak(key, 3);
    if (r_wrong.uniform_d() < p_.sam.p_wrong) {
      const int other = sam::other_label(*labels, target, r_wrong);
      if (other != target) { id = other; m = mask_of(*labels, id); }
    }
    if (r_part.uniform_d() < p_.sam.p_part)
      m = sam::cut_through_centroid(m, r_part.uniform(0.f, 2.f * std::numbers::pi_v<float>));
    if (r_leak.uniform_d() < p_.sam.p_leak) sam::leak(m, *labels, id, p_.sam.leak_px, r_leak);
    if (p_.sam.drift_px > 0.f) m = sam::drift(m, frame, p_.sam.drift_px, sam::drift_angle(p_.seed));
  }

  const World* world_;
  OracleParams p_;
  std::function<void(IdImage&, const World&, const Camera&, int)> render_;
  std::function<RenderOutput(const RenderRequest&)> render_request_;  // rendered mode
  std::shared_ptr<const RenderedLabels> labels_;                      // rendered mode
};

static_assert(Segmenter<OracleSegmenter>);

}  // namespace vcar::synth
