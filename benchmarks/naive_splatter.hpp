#pragma once
// The naive CPU splatter the tiled renderer is measured against, structured like OpenSplat's CPU
// forward pass (rasterize_forward_tensor_cpu): one thread, no tiles, no SIMD. Project every
// Gaussian and take its SH colour first, sort by depth, then for each Gaussian front to back
// loop over its 3-sigma box (3 sqrt(Sigma2D_xx), 3 sqrt(Sigma2D_yy), +2 px, clipped), skipping
// pixels already done. Compositing rules are conventions §3 (pixel centres at +0.5), so its
// output equals the tiled renderer's except where the 3-sigma box is smaller than the
// opacity-aware extent (opaque splats lose their 3.0-3.33 sigma fringe, alpha < 0.012).
// With `pixel_lists`, it also does what OpenSplat's forward pass does for its backward pass:
// one list per pixel of the Gaussians composited there (px2gid: one vector per pixel, a
// push_back per composited Gaussian, reversed at the end). OpenSplat also projects with torch
// tensor operations, which this scalar loop does not imitate (it is faster than those).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include <Eigen/Core>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/core/spherical_harmonics.hpp"

namespace vcar::bench {

inline RenderOutput naive_render(const RenderRequest& q, const ProjectionParams& pp = {},
                                 std::vector<std::vector<std::int32_t>>* pixel_lists = nullptr) {
  const GaussianScene& sc = *q.scene;
  const Camera& cam = *q.camera;
  const int W = cam.width, H = cam.height;
  const std::size_t n = sc.size();
  // Per-Gaussian arrays, as OpenSplat keeps its tensors (culled ones stay, marked invalid).
  std::vector<float> mx(n), my(n), A(n), B(n), C(n), op(n), depth(n), sqx(n), sqy(n), rgb(3 * n);
  std::vector<std::uint8_t> valid(n, 0);
  const Eigen::Vector3f eye = cam.position();
  for (std::size_t i = 0; i < n; ++i) {
    op[i] = sc.opacity(i);
    const ProjectedGaussian p = project_gaussian(cam, sc.mu(i), sc.R(i), sc.scale(i), op[i], pp);
    depth[i] = p.depth;
    if (!p.valid || !p.on_screen) continue;
    valid[i] = 1;
    mx[i] = p.mean.x();
    my[i] = p.mean.y();
    A[i] = p.conic[0];
    B[i] = p.conic[1];
    C[i] = p.conic[2];
    sqx[i] = 3.f * std::sqrt(p.Sigma2D(0, 0));
    sqy[i] = 3.f * std::sqrt(p.Sigma2D(1, 1));
  }
  for (std::size_t i = 0; i < n; ++i) {  // SH colour of every Gaussian first (OpenSplat)
    const Eigen::Vector3f c = gaussian_rgb(sc, i, eye);
    for (int k = 0; k < 3; ++k) rgb[3 * i + k] = c[k];
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  // Stable, so equal depths keep the lower index in front (as the tiled renderer does).
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return depth[a] < depth[b]; });

  std::vector<float> T(static_cast<std::size_t>(W) * H, 1.f);
  std::vector<std::uint8_t> done(T.size(), 0);
  if (pixel_lists) pixel_lists->assign(T.size(), {});
  RenderOutput out;
  out.rgb = ImageF(W, H, 3);
  out.alpha = ImageF(W, H, 1);
  for (const std::size_t g : order) {
    if (!valid[g]) continue;
    const int y0 = std::max(0, static_cast<int>(std::floor(my[g] - sqy[g])) - 2);
    const int y1 = std::min(H, static_cast<int>(std::ceil(my[g] + sqy[g])) + 2);
    const int x0 = std::max(0, static_cast<int>(std::floor(mx[g] - sqx[g])) - 2);
    const int x1 = std::min(W, static_cast<int>(std::ceil(mx[g] + sqx[g])) + 2);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const std::size_t o = static_cast<std::size_t>(y) * W + x;
        if (done[o]) continue;
        const float dx = mx[g] - (static_cast<float>(x) + 0.5f), dy = my[g] - (static_cast<float>(y) + 0.5f);
        const float sigma = 0.5f * (A[g] * dx * dx + C[g] * dy * dy) + B[g] * dx * dy;
        if (sigma < 0.f) continue;
        const float alpha = std::min(0.999f, op[g] * std::exp(-sigma));
        if (alpha < 1.f / 255.f) continue;
        const float nT = T[o] * (1.f - alpha);
        if (nT <= 1e-4f) {  // this pixel is done; the Gaussian is not composited (gsplat)
          done[o] = 1;
          continue;
        }
        const float w = alpha * T[o];
        out.rgb.data[o * 3 + 0] += w * rgb[3 * g + 0];
        out.rgb.data[o * 3 + 1] += w * rgb[3 * g + 1];
        out.rgb.data[o * 3 + 2] += w * rgb[3 * g + 2];
        T[o] = nT;
        if (pixel_lists) (*pixel_lists)[o].push_back(static_cast<std::int32_t>(g));
      }
  }
  for (std::size_t o = 0; o < T.size(); ++o) {
    for (int c = 0; c < 3; ++c) out.rgb.data[o * 3 + c] += q.background[c] * T[o];
    out.alpha.data[o] = 1.f - T[o];
    if (pixel_lists) std::reverse((*pixel_lists)[o].begin(), (*pixel_lists)[o].end());
  }
  return out;
}

}  // namespace vcar::bench
