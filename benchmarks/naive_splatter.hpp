#pragma once
// The straightforward CPU splatter the tiled renderer is measured against (OpenSplat CPU style):
// one thread, no tiles, no SIMD; Gaussians sorted by depth once, each one splatted over the
// pixels of its bounding box into a per-pixel transmittance buffer. Same rules as CONVENTIONS 3.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/core/spherical_harmonics.hpp"

namespace vcar::bench {

inline RenderOutput naive_render(const RenderRequest& q, const ProjectionParams& pp = {}) {
  const GaussianScene& sc = *q.scene;
  const Camera& cam = *q.camera;
  const int W = cam.width, H = cam.height;
  const std::size_t n = sc.size();
  struct Splat { float mx, my, a, b, c, op, z, r, g, bl; int rx, ry; };
  std::vector<Splat> splats;
  splats.reserve(n);
  const Eigen::Vector3f eye = cam.position();
  for (std::size_t i = 0; i < n; ++i) {
    const float op = sc.opacity(i);
    const ProjectedGaussian p = project_gaussian(cam, sc.mu(i), sc.R(i), sc.scale(i), op, pp);
    if (!p.valid || !p.on_screen) continue;
    const Eigen::Vector3f c = gaussian_rgb(sc, i, eye);
    splats.push_back({p.mean.x(), p.mean.y(), p.conic[0], p.conic[1], p.conic[2], op, p.depth,
                      c[0], c[1], c[2], p.radius_x, p.radius_y});
  }
  std::stable_sort(splats.begin(), splats.end(), [](const Splat& a, const Splat& b) { return a.z < b.z; });
  std::vector<float> T(static_cast<std::size_t>(W) * H, 1.f);
  std::vector<std::uint8_t> done(T.size(), 0);
  RenderOutput out;
  out.rgb = ImageF(W, H, 3);
  out.alpha = ImageF(W, H, 1);
  for (const Splat& s : splats) {
    const int x0 = std::max(0, static_cast<int>(std::floor(s.mx - s.rx)));
    const int x1 = std::min(W - 1, static_cast<int>(std::ceil(s.mx + s.rx)));
    const int y0 = std::max(0, static_cast<int>(std::floor(s.my - s.ry)));
    const int y1 = std::min(H - 1, static_cast<int>(std::ceil(s.my + s.ry)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const std::size_t o = static_cast<std::size_t>(y) * W + x;
        if (done[o]) continue;
        const float dx = s.mx - (x + 0.5f), dy = s.my - (y + 0.5f);
        const float sigma = 0.5f * (s.a * dx * dx + s.c * dy * dy) + s.b * dx * dy;
        if (sigma < 0.f) continue;
        const float alpha = std::min(0.999f, s.op * std::exp(-sigma));
        if (alpha < 1.f / 255.f) continue;
        const float nT = T[o] * (1.f - alpha);
        if (nT <= 1e-4f) { done[o] = 1; continue; }
        const float w = alpha * T[o];
        out.rgb.data[o * 3 + 0] += w * s.r;
        out.rgb.data[o * 3 + 1] += w * s.g;
        out.rgb.data[o * 3 + 2] += w * s.bl;
        T[o] = nT;
      }
  }
  for (std::size_t o = 0; o < T.size(); ++o) {
    for (int c = 0; c < 3; ++c) out.rgb.data[o * 3 + c] += q.background[c] * T[o];
    out.alpha.data[o] = 1.f - T[o];
  }
  return out;
}

}  // namespace vcar::bench
