#pragma once
// OracleSegmenter: a vcar::Segmenter that answers any camera (training, sampled, evaluation)
// from the exact ray-cast ground truth, never rendering (it does not call frames.image()),
// with seeded failure models that can be combined. Deterministic from (seed, frame index,
// camera): the same call gives the same masks.
//
// Which ground truth a frame gets (`mode`):
//  - visible: the target where it is the nearest surface, what SAM sees in a render of the
//    full scene (occluders cut it);
//  - silhouette: the target alone, what SAM sees when the frame is a render of a subset that
//    holds only the target (e.g. SSS views of G_coarse: the pipeline renders only the coarse
//    Gaussians, so the neighbour that would occlude is not drawn);
//  - by_name (default): silhouette for cameras whose name starts with `silhouette_prefix`
//    ("sss_") and for every frame of a sequence that renders a subset (FrameSequence::subset,
//    the fine round's renders of G_coarse: the occluders are not drawn), visible otherwise.
// Failure models, applied in this order: drop (no mask) with p_drop; the neighbour's mask
// instead of the target's with p_swap; dilation (k > 0) / erosion (k < 0) by a Euclidean disc
// of |k| px; a random shift of up to jitter_px in x and y; n_blobs false-positive discs of
// radius blob_radius_px at uniform centres.
#include <cstdint>
#include <cstring>
#include <functional>
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
#include "vcar/synth/world.hpp"

namespace vcar::synth {

enum class OracleMode { visible, silhouette, by_name };

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

  void validate() const {
    if (!(p_drop >= 0.0 && p_drop <= 1.0)) throw Error("must be in [0, 1]", "OracleParams.p_drop");
    if (!(p_swap >= 0.0 && p_swap <= 1.0)) throw Error("must be in [0, 1]", "OracleParams.p_swap");
    if (n_blobs < 0) throw Error("must be >= 0", "OracleParams.n_blobs");
    if (jitter_px < 0) throw Error("must be >= 0", "OracleParams.jitter_px");
    if (!(blob_radius_px >= 0.f)) throw Error("must be >= 0", "OracleParams.blob_radius_px");
  }
};

class OracleSegmenter {
public:
  // Primitives only: inserted Gaussian objects are invisible to this oracle.
  OracleSegmenter(const World& world, OracleParams params = {}) : world_(&world), p_(std::move(params)) {
    p_.validate();
  }
  // With a renderer for the inserted Gaussian objects (kept by reference: it must outlive this).
  template <Renderer R>
  OracleSegmenter(const World& world, OracleParams params, R& renderer) : OracleSegmenter(world, std::move(params)) {
    if (!world.inserted.empty())
      render_ = [&renderer](IdImage& img, const World& w, const Camera& cam, int only) {
        add_inserted(img, w, cam, renderer, only);
      };
  }

  const OracleParams& params() const { return p_; }

  // The ray casts of one frame, kept for the oracles (of one world) asked about it in turn: the
  // ones that see the frame as the full scene share one cast, as an image model that encodes a
  // frame once for every prompt does (the several-objects run's coarse round).
  class FrameCasts {
  public:
    const IdImage& get(const OracleSegmenter& o, const Camera& cam, int only) {
      if (cam_ != &cam || world_ != o.world_) cache_.clear();
      cam_ = &cam;
      world_ = o.world_;
      for (const auto& [key, img] : cache_)
        if (key == only) return img;
      IdImage img = raycast(*o.world_, cam, only);
      if (o.render_) o.render_(img, *o.world_, cam, only);
      return cache_.emplace_back(only, std::move(img)).second;
    }

  private:
    const Camera* cam_ = nullptr;
    const World* world_ = nullptr;
    std::vector<std::pair<int, IdImage>> cache_;
  };

  // The answer for one frame: nullopt when dropped. `subset`: the frame renders a subset of the
  // scene (by_name answers it with the silhouette).
  std::optional<Mask> mask(const Camera& cam, std::size_t frame, bool subset = false) const {
    FrameCasts casts;
    return mask(cam, frame, subset, casts);
  }
  // The same, the ray cast taken from (or added to) `casts` of this frame.
  std::optional<Mask> mask(const Camera& cam, std::size_t frame, bool subset, FrameCasts& casts) const {
    Rng rng(p_.seed, hash_combine(frame, hash_string(cam.name)), pose_hash(cam));
    if (rng.uniform_d() < p_.p_drop) return std::nullopt;
    const int target = p_.target_id >= 0 ? p_.target_id : world_->target_id;
    const int id = rng.uniform_d() < p_.p_swap ? world_->neighbour_id : target;
    const bool sil = p_.mode == OracleMode::silhouette ||
                     (p_.mode == OracleMode::by_name &&
                      (subset || (!p_.silhouette_prefix.empty() && cam.name.rfind(p_.silhouette_prefix, 0) == 0)));
    const IdImage& img = casts.get(*this, cam, sil ? id : any_object);
    Mask m = dilate_erode(mask_of(img, id), p_.dilate_px);
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
      const std::optional<Mask> m = mask(frames.cameras[k], k, frames.subset);
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

  const World* world_;
  OracleParams p_;
  std::function<void(IdImage&, const World&, const Camera&, int)> render_;
};

static_assert(Segmenter<OracleSegmenter>);

}  // namespace vcar::synth
