#pragma once
// A Segmenter that needs no model weights, for the browser: colour + depth region growing from
// the clicked pixel on vcar's own renders.
//
// Frame 0 (the reference view, conventions §4) is grown from the first positive prompt point.
// That pixel is lifted to 3D with the rendered expected depth (depth / alpha), once, and every
// other frame is grown from the anchor's projection when the anchor is in view and not hidden
// (its depth agrees with the rendered depth there, else "no mask": no evidence). A pixel joins
// the region when it is covered (alpha >= min_alpha), its colour is within colour_tol of the
// seed colour (Euclidean, 0..255 units) and its expected depth differs from the neighbour it
// was reached from by at most depth_step (relative): objects end at colour edges and at depth
// discontinuities. Small enclosed holes of covered pixels are then filled (fill_holes).
//
// The renders come from `DepthKeepingRenderer`: vcar::FrameSequence hands segmenters 8-bit RGB
// only, so the renderer wrapper keeps the depth and alpha of the frame it rendered last, which is
// the frame the segmenter asked for (segment() calls frames.image(k) and then reads depth()).
//
// Hook for a learned model (SAM and the like): any class with the same segment() signature
// satisfies vcar::Segmenter; see docs/web.md ("Bring your own SAM") for the browser version.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"

namespace vcar::web {

// Renders through R, always with depth, and keeps the last output's depth and alpha.
template <Renderer R>
class DepthKeepingRenderer {
public:
  explicit DepthKeepingRenderer(R& r) : r_(r) {}
  RenderOutput render(const RenderRequest& q) {
    RenderRequest d = q;
    d.want_depth = true;
    RenderOutput out = r_.render(d);
    last_depth_ = out.depth;
    last_alpha_ = out.alpha;
    if (!q.want_depth) out.depth = ImageF();
    return out;
  }
  const ImageF& depth() const { return last_depth_; }
  const ImageF& alpha() const { return last_alpha_; }

private:
  R& r_;
  ImageF last_depth_, last_alpha_;
};

struct RegionGrowOptions {
  float colour_tol = 48.f;     // Euclidean RGB distance to the seed colour, 0..255 units
  float depth_step = 0.02f;    // max relative depth change between neighbouring pixels
  float min_alpha = 0.5f;      // a pixel must be covered this much
  float occlusion_tol = 0.05f; // relative: anchor depth vs rendered depth at its projection
  int seed_radius = 2;         // the seed colour is the mean of a (2r+1)^2 window
  float max_hole = 0.05f;      // enclosed covered holes up to this fraction of the region are filled
};

// Fills the holes of `m` (4-connected components of non-region pixels) that touch neither the
// image border nor an uncovered pixel and hold at most max_hole x |region| pixels: the
// sprinkles on a cake, specular spots, thin details of another colour inside the object.
inline void fill_holes(Mask& m, const ImageF& alpha, const RegionGrowOptions& o) {
  const int W = m.width, H = m.height;
  std::size_t region = 0;
  for (std::uint8_t v : m.data) region += v != 0;
  const std::size_t limit = static_cast<std::size_t>(o.max_hole * static_cast<float>(region));
  std::vector<std::uint8_t> seen(m.data.size(), 0);
  std::vector<std::pair<int, int>> stack, comp;
  const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
  for (int y0 = 0; y0 < H; ++y0)
    for (int x0 = 0; x0 < W; ++x0) {
      const std::size_t i0 = static_cast<std::size_t>(y0) * W + x0;
      if (m.data[i0] || seen[i0]) continue;
      bool open = false;  // touches the border or an uncovered pixel
      comp.clear();
      stack.assign(1, {x0, y0});
      seen[i0] = 1;
      while (!stack.empty()) {
        const auto [x, y] = stack.back();
        stack.pop_back();
        comp.emplace_back(x, y);
        if (x == 0 || y == 0 || x == W - 1 || y == H - 1 || alpha(x, y) < o.min_alpha) open = true;
        for (int k = 0; k < 4; ++k) {
          const int qx = x + dx[k], qy = y + dy[k];
          if (qx < 0 || qy < 0 || qx >= W || qy >= H) continue;
          const std::size_t q = static_cast<std::size_t>(qy) * W + qx;
          if (m.data[q] || seen[q]) continue;
          seen[q] = 1;
          stack.emplace_back(qx, qy);
        }
      }
      if (!open && comp.size() <= limit)
        for (const auto& [x, y] : comp) m(x, y) = 255;
    }
}

// Region growing on one frame: rgb (8-bit, 3 channels), expected depth and alpha images, seed
// pixel (sx, sy). Returns the mask (255 = region); empty region when the seed is not covered.
inline Mask grow_region(const ImageRGB8& rgb, const ImageF& depth, const ImageF& alpha, int sx, int sy,
                        const RegionGrowOptions& o) {
  const int W = rgb.width, H = rgb.height;
  Mask m(W, H, 1, 0);
  if (sx < 0 || sy < 0 || sx >= W || sy >= H) return m;
  auto z = [&](int x, int y) { const float a = alpha(x, y); return a > 0.f ? depth(x, y) / a : 0.f; };
  auto covered = [&](int x, int y) { return alpha(x, y) >= o.min_alpha; };
  if (!covered(sx, sy)) return m;
  float seed[3] = {0, 0, 0};
  int n = 0;
  for (int y = std::max(0, sy - o.seed_radius); y <= std::min(H - 1, sy + o.seed_radius); ++y)
    for (int x = std::max(0, sx - o.seed_radius); x <= std::min(W - 1, sx + o.seed_radius); ++x) {
      if (!covered(x, y)) continue;
      for (int c = 0; c < 3; ++c) seed[c] += rgb(x, y, c);
      ++n;
    }
  for (float& c : seed) c /= static_cast<float>(n);
  const float tol2 = o.colour_tol * o.colour_tol;
  auto colour_ok = [&](int x, int y) {
    float d2 = 0;
    for (int c = 0; c < 3; ++c) { const float d = rgb(x, y, c) - seed[c]; d2 += d * d; }
    return d2 <= tol2;
  };
  std::vector<std::pair<int, int>> stack{{sx, sy}};
  m(sx, sy) = 255;
  const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
  while (!stack.empty()) {
    const auto [x, y] = stack.back();
    stack.pop_back();
    const float zp = z(x, y);
    for (int k = 0; k < 4; ++k) {
      const int qx = x + dx[k], qy = y + dy[k];
      if (qx < 0 || qy < 0 || qx >= W || qy >= H || m(qx, qy) || !covered(qx, qy)) continue;
      if (std::abs(z(qx, qy) - zp) > o.depth_step * zp || !colour_ok(qx, qy)) continue;
      m(qx, qy) = 255;
      stack.emplace_back(qx, qy);
    }
  }
  fill_holes(m, alpha, o);
  return m;
}

template <Renderer R>
class RegionGrowSegmenter {
public:
  RegionGrowSegmenter(DepthKeepingRenderer<R>& r, RegionGrowOptions o = {}) : r_(r), o_(o) {}

  // The clicked point in world coordinates, once frame 0 of the first round has been seen.
  const std::optional<Eigen::Vector3f>& anchor() const { return anchor_; }
  void set_anchor(const Eigen::Vector3f& p) { anchor_ = p; }

  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    const Eigen::Vector2f* click = nullptr;
    for (std::size_t k = 0; k < prompt.points.size(); ++k)
      if (k >= prompt.point_labels.size() || prompt.point_labels[k] == 1) { click = &prompt.points[k]; break; }
    if (!click) throw Error("the region-growing segmenter needs a positive prompt point", "prompt");
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const Camera& cam = frames.cameras[k];
      const ImageRGB8 rgb = frames.image(k);
      const ImageF& depth = r_.depth();
      const ImageF& alpha = r_.alpha();
      int sx, sy;
      if (k == 0) {
        sx = static_cast<int>(std::floor((*click)[0]));
        sy = static_cast<int>(std::floor((*click)[1]));
        if (!anchor_) anchor_ = lift(cam, depth, alpha, sx, sy);
      } else {
        if (!anchor_ || !seed_of(cam, depth, alpha, sx, sy)) { sink(k, nullptr); continue; }
      }
      const Mask m = grow_region(rgb, depth, alpha, sx, sy, o_);
      sink(k, &m);
    }
  }

  // The world point under pixel (x, y): the ray through the pixel centre at the expected depth.
  static std::optional<Eigen::Vector3f> lift(const Camera& cam, const ImageF& depth, const ImageF& alpha, int x, int y) {
    if (x < 0 || y < 0 || x >= cam.width || y >= cam.height || alpha(x, y) < 0.5f) return std::nullopt;
    const float z = depth(x, y) / alpha(x, y);
    const Eigen::Vector3f pc((x + 0.5f - cam.cx) / cam.fx * z, (y + 0.5f - cam.cy) / cam.fy * z, z);
    return cam.R_w.transpose() * (pc - cam.t_w);
  }

private:
  // The anchor's pixel in `cam` when it is in view and visible (rendered depth agrees within
  // occlusion_tol, searched in a 5x5 window around the projection).
  bool seed_of(const Camera& cam, const ImageF& depth, const ImageF& alpha, int& sx, int& sy) const {
    const Eigen::Vector3f pc = cam.to_camera(*anchor_);
    if (!(pc.z() > 1e-6f)) return false;
    const float u = cam.fx * pc.x() / pc.z() + cam.cx, v = cam.fy * pc.y() / pc.z() + cam.cy;
    if (!inside_image(u, v, cam.width, cam.height)) return false;
    const int px = static_cast<int>(std::floor(u)), py = static_cast<int>(std::floor(v));
    float best = o_.occlusion_tol;
    bool found = false;
    for (int r = 0; r <= 2 && !found; ++r)
      for (int y = py - r; y <= py + r; ++y)
        for (int x = px - r; x <= px + r; ++x) {
          if (x < 0 || y < 0 || x >= cam.width || y >= cam.height || alpha(x, y) < o_.min_alpha) continue;
          const float rel = std::abs(depth(x, y) / alpha(x, y) - pc.z()) / pc.z();
          if (rel <= best) { best = rel; sx = x; sy = y; found = true; }
        }
    return found;
  }

  DepthKeepingRenderer<R>& r_;
  RegionGrowOptions o_;
  std::optional<Eigen::Vector3f> anchor_;
};

}  // namespace vcar::web
