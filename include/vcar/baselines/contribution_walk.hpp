#pragma once
// A reference front-to-back walk over the contributions alpha_i(p) T_i(p) of one view, with
// gsplat's rules (conventions §3: projection, 16 x 16 tiles, depth order, alpha clamp 0.999,
// skip below 1/255, stop before T would drop to 1e-4). It is the "brute-force/tiled logic" the
// peer methods need where a renderer does not expose it: LBG's per-pixel maximum contributor,
// and test-local ContributionRenderers.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/projection.hpp"

namespace vcar::baselines {

inline constexpr int tile_size = 16;

// visit(pixel, i, alpha, T) for every contribution, per pixel in front-to-back order; pixel =
// y * width + x, i indexes the scene. subset: only these Gaussians (null = all). parallel: tiles
// run concurrently, so `visit` may only write per pixel; pass false to accumulate per Gaussian.
template <class Visit>
void for_each_contribution(const GaussianScene& scene, const Camera& cam, const std::vector<Index>* subset,
                           Visit&& visit, bool parallel = true, const ProjectionParams& pp = {}) {
  const std::size_t n = subset ? subset->size() : scene.size();
  const int W = cam.width, H = cam.height;
  const int tiles_x = (W + tile_size - 1) / tile_size, tiles_y = (H + tile_size - 1) / tile_size;
  // Projected state, SoA, one slot per drawn Gaussian.
  std::vector<float> u(n), v(n), ca(n), cb(n), cc(n), op(n), depth(n);
  std::vector<std::int32_t> tx0(n), tx1(n), ty0(n), ty1(n);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t k) {
    const std::size_t i = subset ? (*subset)[k] : static_cast<std::size_t>(k);
    const float o = scene.opacity(i);
    const ProjectedGaussian g = project_gaussian(cam, scene.mu(i), scene.R(i), scene.scale(i), o, pp);
    tx0[k] = tx1[k] = ty0[k] = ty1[k] = 0;
    if (!g.valid || !g.on_screen) return;
    u[k] = g.mean.x(); v[k] = g.mean.y();
    ca[k] = g.conic.x(); cb[k] = g.conic.y(); cc[k] = g.conic.z();
    op[k] = o; depth[k] = g.depth;
    auto clampi = [](float x, int hi) { return std::min(std::max(0, static_cast<int>(x)), hi); };
    tx0[k] = clampi(std::floor((u[k] - g.radius_x) / tile_size), tiles_x);
    tx1[k] = clampi(std::ceil((u[k] + g.radius_x) / tile_size), tiles_x);
    ty0[k] = clampi(std::floor((v[k] - g.radius_y) / tile_size), tiles_y);
    ty1[k] = clampi(std::ceil((v[k] + g.radius_y) / tile_size), tiles_y);
  });
  // Bin per tile in Gaussian order, then a stable depth sort: ties keep index order.
  const std::size_t T = static_cast<std::size_t>(tiles_x) * tiles_y;
  std::vector<std::size_t> start(T + 1, 0);
  for (std::size_t k = 0; k < n; ++k)
    for (int ty = ty0[k]; ty < ty1[k]; ++ty)
      for (int tx = tx0[k]; tx < tx1[k]; ++tx) ++start[static_cast<std::size_t>(ty) * tiles_x + tx + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::uint32_t> bins(start[T]);
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  for (std::size_t k = 0; k < n; ++k)
    for (int ty = ty0[k]; ty < ty1[k]; ++ty)
      for (int tx = tx0[k]; tx < tx1[k]; ++tx) bins[fill[static_cast<std::size_t>(ty) * tiles_x + tx]++] = static_cast<std::uint32_t>(k);
  auto tile = [&](std::int64_t t) {
    auto* b = bins.data() + start[t];
    std::stable_sort(b, bins.data() + start[t + 1], [&](std::uint32_t a, std::uint32_t c) { return depth[a] < depth[c]; });
    const int x0 = static_cast<int>(t % tiles_x) * tile_size, y0 = static_cast<int>(t / tiles_x) * tile_size;
    const std::size_t count = start[t + 1] - start[t];
    for (int y = y0; y < std::min(H, y0 + tile_size); ++y)
      for (int x = x0; x < std::min(W, x0 + tile_size); ++x) {
        const float px = x + 0.5f, py = y + 0.5f;
        float Tr = 1.f;
        for (std::size_t s = 0; s < count; ++s) {
          const std::uint32_t k = b[s];
          const float dx = u[k] - px, dy = v[k] - py;
          const float sigma = 0.5f * (ca[k] * dx * dx + cc[k] * dy * dy) + cb[k] * dx * dy;
          if (sigma < 0.f) continue;
          const float alpha = std::min(0.999f, op[k] * std::exp(-sigma));
          if (alpha < 1.f / 255.f) continue;
          const float next_T = Tr * (1.f - alpha);
          if (next_T <= 1e-4f) break;  // gsplat: this one is not composited
          const std::size_t i = subset ? (*subset)[k] : k;
          visit(static_cast<std::size_t>(y) * W + x, static_cast<Index>(i), alpha, Tr);
          Tr = next_T;
        }
      }
  };
  if (parallel) parallel_for_dynamic(static_cast<std::int64_t>(T), tile);
  else for (std::size_t t = 0; t < T; ++t) tile(static_cast<std::int64_t>(t));
}

inline constexpr std::int32_t no_contributor = -1;

// Per pixel, argmax_i alpha_i(p) T_i(p) (the first in depth order on ties); no_contributor
// where nothing is composited.
inline Image<std::int32_t> max_contributor(const GaussianScene& scene, const Camera& cam,
                                           const std::vector<Index>* subset = nullptr) {
  Image<std::int32_t> who(cam.width, cam.height, 1, no_contributor);
  std::vector<float> best(who.pixels(), 0.f);
  for_each_contribution(scene, cam, subset, [&](std::size_t p, Index i, float alpha, float T) {
    if (alpha * T > best[p]) { best[p] = alpha * T; who.data[p] = static_cast<std::int32_t>(i); }
  });
  return who;
}

}  // namespace vcar::baselines
