#pragma once
// Prompt lifting: one prompt on the reference view -> a box on every frame, for image-only
// segmenters (GrabCut, ISNet, SAM 1) that need a prompt on each frame they segment. Beyond the
// paper: the paper's segmenter (SAM 2 in video mode) propagates the prompt itself.
//
// lift_prompt renders the reference view with depth from the Gaussians at least opacity_min
// opaque (Z(p) = D(p) / A(p), the alpha-normalised expected depth, where A(p) >= alpha_min;
// faint floaters would pull that mean in front of the surface) and lifts each prompt region:
//  - a box: the region is the box; a positive point: the disc of radius point_radius * (image
//    diagonal) around it. The box wins when both are given (the points do not change the lift).
//  - z_ref: the median of Z over the region's central part (the box shrunk to `central` of its
//    width and height around its centre; the disc shrunk to `central` of its radius).
//  - s: the region's size in world units at that depth, s = max(w / fx, h / fy) * z_ref (a
//    pinhole maps a width w px at depth z to w z / f). Every band below is a fraction of s.
//  - lifted: the Gaussians whose centre projects into the region at pixel p, lies at the
//    surface there, |z - Z(p)| <= surface_band * s (front-most: the object's back and anything
//    it hides are out), and within the object's depth range, |z - z_ref| <= depth_range * s
//    (the floor or wall visible behind the object inside the box is out).
//  - back: each lifted centre moved along the reference view's axis to the depth z_back =
//    z_near + depth_ratio * s (z_near: the region's nearest lifted centre): the object is assumed
//    as deep as it is wide, so that boxes in other views cover what the reference does not see.
// LiftedPrompt::box_in(camera) projects the lifted centres and their back points, drops the
// `outliers` fraction of extremes (half on each side, per axis), pads each side by `margin`
// of the box's width (x) or height (y) and clips to the image; nullopt when more than the
// outlier fraction lies behind the camera or the box misses the image.
//
// When it fails:
//  - box_in is geometry only: an object hidden behind another in some view still gets its box
//    there (the segmenter then sees the occluder);
//  - a point prompt lifts a neighbourhood of the point, not the object: its boxes cover part of
//    the object (give a box, or find the click's box with the segmenter first:
//    box_from_click, algo/click_box.hpp);
//  - an object deeper than wide seen end-on (a bench along the view axis), or whose centre part
//    shows the background (a ring seen through its hole), breaks the depth-range assumption:
//    parts are dropped, or the background is lifted instead;
//  - whatever else the box shows at the object's depth is lifted too: an occluder in front of
//    the object, a neighbour touching it, the floor around its foot (boxes grow to include them);
//  - a flat object seen face-on in the reference view gets boxes too tall in side views (the
//    depth_ratio assumption).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/projection.hpp"

namespace vcar {

namespace detail {
// A float as printf's %g writes it (0.5, not 0.500000), for messages.
inline std::string short_float(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}
}  // namespace detail

struct LiftParams {
  float surface_band = 0.1f;   // |z - Z(p)| <= surface_band * s: at the rendered surface (front-most)
  float depth_range = 1.f;     // |z - z_ref| <= depth_range * s: the object's depth range
  float central = 0.5f;        // z_ref: median Z over the region shrunk to this fraction
  float point_radius = 0.05f;  // a point's region: a disc of this fraction of the image diagonal
  float depth_ratio = 1.f;     // assumed depth of the object / its width (the back points)
  float alpha_min = 0.5f;      // a pixel shows a surface where alpha >= alpha_min
  // Only Gaussians at least this opaque are rendered for Z and lifted: Z is an alpha-weighted
  // mean, so faint floaters in front pull it forward, off the surface behind them.
  float opacity_min = 0.3f;

  void validate() const {
    auto in = [](float v, float lo, float hi, const char* name) {
      if (!(v >= lo && v <= hi)) throw Error("must be in [" + detail::short_float(lo) + ", " + detail::short_float(hi) + "]",
                                             std::string("LiftParams.") + name);
    };
    in(surface_band, 0.f, 10.f, "surface_band");
    in(depth_range, 0.f, 10.f, "depth_range");
    in(central, 0.01f, 1.f, "central");
    in(point_radius, 1e-4f, 1.f, "point_radius");
    in(depth_ratio, 0.f, 100.f, "depth_ratio");
    in(alpha_min, 0.01f, 1.f, "alpha_min");
    in(opacity_min, 0.f, 0.99f, "opacity_min");
  }
};

// What lift_prompt returns: the prompt as points in the world, ready to be boxed in any frame.
struct LiftedPrompt {
  std::vector<Index> indices;            // the lifted Gaussians, ascending scene indices
  std::vector<Eigen::Vector3f> points;   // their centres (world), aligned with indices
  std::vector<Eigen::Vector3f> back;     // each centre moved to the object's assumed back (world)
  Camera reference;                      // the view the prompt was given on
  std::optional<Eigen::Vector4f> reference_box;  // the prompt's own box (x0, y0, x1, y1), if any

  bool empty() const noexcept { return points.empty(); }

  // The box (x0, y0, x1, y1, pixels of `cam`, clipped to [0, W] x [0, H]) of the lifted points in
  // `cam`: the projections of points and back, the `outliers` fraction of extremes dropped (half
  // each side, per axis), each side padded by `margin` of the box's width (x) or height (y).
  // nullopt: more than the outlier fraction behind the camera, or the box misses the image.
  std::optional<Eigen::Vector4f> box_in(const Camera& cam, float margin = 0.05f, float outliers = 0.02f) const {
    if (!(margin >= 0.f) || !(outliers >= 0.f && outliers < 1.f))
      throw Error("margin must be >= 0 and outliers in [0, 1)", "LiftedPrompt::box_in");
    const std::size_t n = points.size() + back.size();
    if (n == 0) return std::nullopt;
    const float near = ProjectionParams{}.near_plane;  // the renderers' near plane
    std::vector<float> us, vs;
    us.reserve(n);
    vs.reserve(n);
    std::size_t behind = 0;
    auto add = [&](const Eigen::Vector3f& X) {
      const Eigen::Vector3f t = cam.to_camera(X);
      if (!(t.z() > near)) { ++behind; return; }
      us.push_back(cam.fx * t.x() / t.z() + cam.cx);  // pinhole: u = fx x / z + cx
      vs.push_back(cam.fy * t.y() / t.z() + cam.cy);
    };
    for (const auto& X : points) add(X);
    for (const auto& X : back) add(X);
    if (static_cast<double>(behind) > outliers * static_cast<double>(n) || us.empty()) return std::nullopt;
    // Trimmed extent: the q-th and (1 - q)-th order statistics, q = outliers / 2.
    const std::size_t m = us.size();
    const std::size_t lo = static_cast<std::size_t>(std::floor(0.5 * outliers * static_cast<double>(m - 1)));
    const std::size_t hi = m - 1 - lo;
    auto order_stat = [](std::vector<float>& x, std::size_t k) {
      std::nth_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(k), x.end());
      return x[k];
    };
    const float u0 = order_stat(us, lo), u1 = order_stat(us, hi);
    const float v0 = order_stat(vs, lo), v1 = order_stat(vs, hi);
    const float W = static_cast<float>(cam.width), H = static_cast<float>(cam.height);
    if (u1 < 0.f || v1 < 0.f || u0 > W || v0 > H) return std::nullopt;  // out of view
    const float pad_x = margin * (u1 - u0), pad_y = margin * (v1 - v0);
    const Eigen::Vector4f box(std::max(0.f, u0 - pad_x), std::max(0.f, v0 - pad_y), std::min(W, u1 + pad_x),
                              std::min(H, v1 + pad_y));
    if (!(box[2] - box[0] >= 1.f && box[3] - box[1] >= 1.f)) return std::nullopt;  // less than a pixel in view
    return box;
  }

  // The box a segmenter should use on `cam`: the prompt's own box on the reference view (same
  // name, size, intrinsics and pose), box_in elsewhere.
  std::optional<Eigen::Vector4f> box_for(const Camera& cam, float margin = 0.05f, float outliers = 0.02f) const {
    if (reference_box && same_view(cam, reference)) return reference_box;
    return box_in(cam, margin, outliers);
  }

  static bool same_view(const Camera& a, const Camera& b) {
    return a.name == b.name && a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
           a.cx == b.cx && a.cy == b.cy && a.R_w == b.R_w && a.t_w == b.t_w;
  }
};

namespace detail {

// One prompt region on the reference view: a box, or a disc around a point.
struct LiftRegion {
  Eigen::Vector4f box;              // bounding box (x0, y0, x1, y1), clipped to the image
  bool disc = false;
  Eigen::Vector2f centre{0, 0};     // disc only
  float radius = 0;                 // disc only (pixels)
  std::size_t point = 0;            // disc only: the prompt point's index
  bool contains(float u, float v) const {
    if (!(u >= box[0] && u < box[2] && v >= box[1] && v < box[3])) return false;
    return !disc || (Eigen::Vector2f(u, v) - centre).squaredNorm() <= radius * radius;
  }
  // The region shrunk around its centre to `f` of its size (the part that z_ref reads).
  LiftRegion shrunk(float f) const {
    LiftRegion r = *this;
    const Eigen::Vector2f c = disc ? centre : Eigen::Vector2f(0.5f * (box[0] + box[2]), 0.5f * (box[1] + box[3]));
    const Eigen::Vector2f half = disc ? Eigen::Vector2f::Constant(f * radius)
                                      : Eigen::Vector2f(0.5f * f * (box[2] - box[0]), 0.5f * f * (box[3] - box[1]));
    r.box = {c.x() - half.x(), c.y() - half.y(), c.x() + half.x(), c.y() + half.y()};
    r.radius = f * radius;
    return r;
  }
};

// Z(p) = D(p) / A(p) where A(p) >= alpha_min; a negative value where no surface.
inline float surface_depth(const RenderOutput& r, std::size_t p, float alpha_min) {
  const float a = r.alpha.data[p];
  return a >= alpha_min && a > 0.f ? r.depth.data[p] / a : -1.f;
}

// Median of the surface depth over the pixels whose centres lie in `region` (the pixel under
// its centre when none does); negative when none shows a surface.
inline float median_depth(const RenderOutput& r, const LiftRegion& region, float alpha_min) {
  const int W = r.alpha.width, H = r.alpha.height;
  std::vector<float> z;
  const int j0 = std::max(0, static_cast<int>(std::floor(region.box[0]))), j1 = std::min(W - 1, static_cast<int>(std::ceil(region.box[2])));
  const int i0 = std::max(0, static_cast<int>(std::floor(region.box[1]))), i1 = std::min(H - 1, static_cast<int>(std::ceil(region.box[3])));
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      if (!region.contains(static_cast<float>(j) + 0.5f, static_cast<float>(i) + 0.5f)) continue;
      const float d = surface_depth(r, static_cast<std::size_t>(i) * W + j, alpha_min);
      if (d > 0.f) z.push_back(d);
    }
  if (z.empty()) {
    const float cu = 0.5f * (region.box[0] + region.box[2]), cv = 0.5f * (region.box[1] + region.box[3]);
    if (!inside_image(cu, cv, W, H)) return -1.f;
    return surface_depth(r, static_cast<std::size_t>(static_cast<int>(cv)) * W + static_cast<int>(cu), alpha_min);
  }
  const std::size_t k = (z.size() - 1) / 2;
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(k), z.end());
  return z[k];
}

}  // namespace detail

// Lifts `prompt` (its box, else its positive points; pixels of `reference`) to the Gaussians of
// `scene` it shows, from one render of `reference` with depth (see the top of the file).
// Throws vcar::Error for an invalid camera, a prompt with neither a box nor a positive point,
// an empty or non-finite box or one outside the image, a renderer without depth, a region that
// shows no surface, and when no Gaussian is lifted.
template <Renderer R>
LiftedPrompt lift_prompt(const GaussianScene& scene, const Camera& reference, const Prompt& prompt, R& renderer,
                         const LiftParams& params = {}) {
  params.validate();
  reference.validate();
  if (scene.empty()) throw Error("the scene has no Gaussians", "lift_prompt");
  const std::string where = "prompt on view '" + reference.name + "'";
  const float W = static_cast<float>(reference.width), H = static_cast<float>(reference.height);

  std::vector<detail::LiftRegion> regions;
  if (prompt.box) {
    const Eigen::Vector4f& b = *prompt.box;
    if (!b.allFinite() || !(b[2] > b[0] && b[3] > b[1]))
      throw Error("the box is empty or not finite (needs finite x0 < x1 and y0 < y1)", where);
    if (b[2] <= 0.f || b[3] <= 0.f || b[0] >= W || b[1] >= H) throw Error("the box lies outside the image", where);
    regions.push_back({Eigen::Vector4f(std::max(0.f, b[0]), std::max(0.f, b[1]), std::min(W, b[2]), std::min(H, b[3]))});
  } else {
    const float radius = params.point_radius * std::hypot(W, H);
    for (std::size_t k = 0; k < prompt.points.size(); ++k) {
      if (k < prompt.point_labels.size() && prompt.point_labels[k] == 0) continue;  // negative points do not lift
      const Eigen::Vector2f& p = prompt.points[k];
      if (!p.allFinite() || !inside_image(p.x(), p.y(), reference.width, reference.height))
        throw Error("point " + std::to_string(k) + " lies outside the image", where);
      detail::LiftRegion r;
      r.disc = true;
      r.centre = p;
      r.radius = radius;
      r.point = k;
      r.box = {std::max(0.f, p.x() - radius), std::max(0.f, p.y() - radius), std::min(W, p.x() + radius),
               std::min(H, p.y() + radius)};
      regions.push_back(r);
    }
  }
  if (regions.empty()) throw Error("nothing to lift: the prompt has neither a box nor a positive point", where);

  std::vector<Index> opaque;  // the Gaussians rendered and lifted: opacity >= opacity_min
  const std::size_t N = scene.size();
  // sigmoid(o) >= p  <=>  o >= logit(p) = log(p / (1 - p))
  const float logit_min = params.opacity_min > 0.f ? std::log(params.opacity_min / (1.f - params.opacity_min)) : -INFINITY;
  for (std::size_t i = 0; i < N; ++i)
    if (scene.opacity_logit[i] >= logit_min) opaque.push_back(static_cast<Index>(i));
  if (opaque.empty()) throw Error("no Gaussian is at least " + detail::short_float(params.opacity_min) + " opaque", where);
  RenderRequest q;
  q.scene = &scene;
  q.camera = &reference;
  q.subset = opaque.size() < N ? &opaque : nullptr;
  q.want_depth = true;
  const RenderOutput render = renderer.render(q);
  if (render.depth.empty() || render.alpha.width != reference.width || render.alpha.height != reference.height ||
      render.depth.data.size() != render.alpha.data.size())
    throw Error("lifting a prompt needs a renderer that returns alpha and depth of the view's size", where);

  LiftedPrompt out;
  out.reference = reference;
  out.reference_box = prompt.box;
  std::vector<float> back_depth(N, 0.f);  // > 0: lifted, pushed back to this depth
  const float near = ProjectionParams{}.near_plane;
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const detail::LiftRegion& region = regions[r];
    const float z_ref = detail::median_depth(render, region.shrunk(params.central), params.alpha_min);
    if (!(z_ref > 0.f))
      throw Error(std::string(prompt.box ? "the box" : "point " + std::to_string(region.point)) +
                      " shows no surface (rendered alpha below " + detail::short_float(params.alpha_min) + ")", where);
    // s = max(w / fx, h / fy) z_ref: the region's size in world units at the object's depth.
    const float s = std::max((region.box[2] - region.box[0]) / reference.fx, (region.box[3] - region.box[1]) / reference.fy) * z_ref;
    const float band = params.surface_band * s, range = params.depth_range * s;
    std::vector<Index> lifted;
    float z_near = INFINITY;
    for (const Index i : opaque) {
      const Eigen::Vector3f t = reference.to_camera(scene.mu(i));
      if (!(t.z() > near)) continue;
      const float u = reference.fx * t.x() / t.z() + reference.cx, v = reference.fy * t.y() / t.z() + reference.cy;
      if (!inside_image(u, v, reference.width, reference.height) || !region.contains(u, v)) continue;
      const float Z = detail::surface_depth(render, static_cast<std::size_t>(static_cast<int>(v)) * reference.width + static_cast<int>(u), params.alpha_min);
      if (!(Z > 0.f) || std::abs(t.z() - Z) > band || std::abs(t.z() - z_ref) > range) continue;
      lifted.push_back(i);
      z_near = std::min(z_near, t.z());
    }
    // z_back = z_near + depth_ratio s: the object's assumed back.
    const float z_back = z_near + params.depth_ratio * s;
    for (Index i : lifted) back_depth[i] = std::max(back_depth[i], z_back);
  }
  const Eigen::Vector3f forward = reference.forward();
  for (std::size_t i = 0; i < N; ++i) {
    if (!(back_depth[i] > 0.f)) continue;
    const Eigen::Vector3f X = scene.mu(i);
    const float z = reference.to_camera(X).z();
    out.indices.push_back(static_cast<Index>(i));
    out.points.push_back(X);
    // X moved along the reference view's axis to depth z_back: X + (z_back - z) forward (a prism
    // behind the visible surface; along the rays it would widen with depth, as no object does).
    out.back.push_back(back_depth[i] > z ? Eigen::Vector3f(X + (back_depth[i] - z) * forward) : X);
  }
  if (out.empty()) throw Error("no Gaussian lies at the rendered surface inside the prompt", where);
  return out;
}

// The same on cameras[prompt.reference_view], with a range check of the reference view.
template <Renderer R>
LiftedPrompt lift_prompt(const GaussianScene& scene, const std::vector<Camera>& cameras, const Prompt& prompt,
                         R& renderer, const LiftParams& params = {}) {
  if (prompt.reference_view >= cameras.size())
    throw Error("reference view " + std::to_string(prompt.reference_view) + " out of range (" +
                    std::to_string(cameras.size()) + " views)", "prompt");
  return lift_prompt(scene, cameras[prompt.reference_view], prompt, renderer, params);
}

}  // namespace vcar
