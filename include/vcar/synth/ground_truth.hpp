#pragma once
// Exact 2D ground truth by ray casting the analytic primitives through pixel centres
// (j + 0.5, i + 0.5) (conventions §2). The visible mask of an object is where it is the nearest
// surface (occlusion included: what a segmenter sees in a render of the full scene); its
// silhouette is where a ray meets it at all (the object alone: what a selection rendered alone
// is compared to). Objects made of inserted trained Gaussians have no analytic surface: their
// ground truth is their rendering alone, alpha > 0.5 (needs a Renderer, overloads below), and
// their normalised rendered depth decides occlusion against the primitives.
#include <climits>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/synth/primitive.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

constexpr int any_object = INT_MIN;  // id filter meaning "every object"

// Per pixel: the nearest object's id (-1 = nothing) and its camera-space depth z (inf = none).
struct IdImage {
  int width = 0, height = 0;
  std::vector<int> id;
  std::vector<float> depth;
  int at(int x, int y) const { return id[static_cast<std::size_t>(y) * width + x]; }
};

// The primitives only (inserted Gaussian objects are ignored); `only` restricts the cast to one
// object's primitives (its silhouette).
inline IdImage raycast(const World& w, const Camera& cam, int only = any_object) {
  IdImage out;
  out.width = cam.width;
  out.height = cam.height;
  out.id.assign(static_cast<std::size_t>(cam.width) * cam.height, -1);
  out.depth.assign(out.id.size(), INFINITY);
  std::vector<const Primitive*> prims;
  for (const auto& q : w.primitives)
    if (only == any_object || q.object_id == only) prims.push_back(&q);
  const Eigen::Vector3f o = cam.position();
  const Eigen::Matrix3f Rt = cam.R_w.transpose();
  parallel_for(cam.height, [&](std::int64_t i) {
    for (int j = 0; j < cam.width; ++j) {
      const Eigen::Vector3f dc((static_cast<float>(j) + 0.5f - cam.cx) / cam.fx,
                               (static_cast<float>(i) + 0.5f - cam.cy) / cam.fy, 1.f);
      const float len = dc.norm();
      const Eigen::Vector3f d = Rt * (dc / len);
      float best = INFINITY;
      int id = -1;
      for (const Primitive* q : prims) {
        float s;
        if (intersect(*q, o, d, 0.f, best, s)) { best = s; id = q->object_id; }
      }
      const std::size_t k = static_cast<std::size_t>(i) * cam.width + j;
      out.id[k] = id;
      out.depth[k] = id >= 0 ? best / len : INFINITY;  // ray length -> camera z
    }
  });
  return out;
}

// Adds the inserted Gaussian objects (filtered by `only`): a pixel belongs to one when its
// rendering alone has alpha > 0.5 and its normalised depth is nearer than what is there.
template <Renderer R>
void add_inserted(IdImage& img, const World& w, const Camera& cam, R& renderer, int only = any_object) {
  for (const auto& obj : w.inserted) {
    if (only != any_object && obj.object_id != only) continue;
    std::vector<Index> subset(obj.count);
    for (std::size_t k = 0; k < obj.count; ++k) subset[k] = static_cast<Index>(obj.begin + k);
    RenderRequest q;
    q.scene = &w.scene;
    q.camera = &cam;
    q.subset = &subset;
    q.want_depth = true;
    const RenderOutput r = renderer.render(q);
    for (std::size_t k = 0; k < img.id.size(); ++k) {
      const float a = r.alpha.data[k];
      if (!(a > 0.5f)) continue;
      const float z = r.depth.empty() ? 0.f : r.depth.data[k] / a;
      if (z < img.depth[k]) { img.depth[k] = z; img.id[k] = obj.object_id; }
    }
  }
}

template <Renderer R>
IdImage raycast(const World& w, const Camera& cam, R& renderer, int only = any_object) {
  IdImage img = raycast(w, cam, only);
  add_inserted(img, w, cam, renderer, only);
  return img;
}

inline Mask mask_of(const IdImage& img, int id) {
  Mask m(img.width, img.height, 1);
  for (std::size_t k = 0; k < img.id.size(); ++k) m.data[k] = img.id[k] == id ? 255 : 0;
  return m;
}

// Where object `id` is the nearest surface (primitives only).
inline Mask visible_mask(const World& w, const Camera& cam, int id) { return mask_of(raycast(w, cam), id); }
// Where object `id` alone covers the pixel (primitives only).
inline Mask silhouette_mask(const World& w, const Camera& cam, int id) { return mask_of(raycast(w, cam, id), id); }

template <Renderer R>
Mask visible_mask(const World& w, const Camera& cam, int id, R& renderer) {
  return mask_of(raycast(w, cam, renderer), id);
}
template <Renderer R>
Mask silhouette_mask(const World& w, const Camera& cam, int id, R& renderer) {
  return mask_of(raycast(w, cam, renderer, id), id);
}

}  // namespace vcar::synth
