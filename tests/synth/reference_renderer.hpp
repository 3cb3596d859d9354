#pragma once
// A tiny, slow, test-local Renderer (conventions §3 compositing, global depth order instead of
// tiles) so the synth tests do not depend on the CPU backend.
#include <algorithm>
#include <numeric>
#include <vector>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/projection.hpp"

namespace synth_test {

struct ReferenceRenderer {
  vcar::RenderOutput render(const vcar::RenderRequest& q) {
    const vcar::GaussianScene& s = *q.scene;
    const vcar::Camera& cam = *q.camera;
    const std::size_t n = q.subset ? q.subset->size() : s.size();
    struct P { vcar::ProjectedGaussian g; float opacity; std::size_t i; };
    std::vector<P> ps;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = q.subset ? (*q.subset)[k] : k;
      Eigen::Vector3f sc = s.scale(i);
      if (q.log_scale) for (int d = 0; d < 3; ++d) sc[d] = std::exp((*q.log_scale)[d][k]);
      const float op = s.opacity(i);
      auto g = vcar::project_gaussian(cam, s.mu(i), s.R(i), sc, op);
      if (g.valid && g.on_screen) ps.push_back({g, op, i});
    }
    std::stable_sort(ps.begin(), ps.end(), [](const P& a, const P& b) { return a.g.depth < b.g.depth; });
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(cam.width, cam.height, 3, 0.f);
    out.alpha = vcar::ImageF(cam.width, cam.height, 1, 0.f);
    if (q.want_depth) out.depth = vcar::ImageF(cam.width, cam.height, 1, 0.f);
    std::vector<float> T(static_cast<std::size_t>(cam.width) * cam.height, 1.f);
    std::vector<char> done(T.size(), 0);
    constexpr float C0 = 0.28209479177387814f;
    const int B = s.sh_coeffs();
    for (const P& p : ps) {
      const auto& g = p.g;
      const int x0 = std::max(0, static_cast<int>(g.mean.x()) - g.radius_x - 1);
      const int x1 = std::min(cam.width - 1, static_cast<int>(g.mean.x()) + g.radius_x + 1);
      const int y0 = std::max(0, static_cast<int>(g.mean.y()) - g.radius_y - 1);
      const int y1 = std::min(cam.height - 1, static_cast<int>(g.mean.y()) + g.radius_y + 1);
      Eigen::Vector3f rgb;
      for (int c = 0; c < 3; ++c) rgb[c] = std::max(0.f, 0.5f + C0 * s.sh[(p.i * B) * 3 + c]);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const std::size_t k = static_cast<std::size_t>(y) * cam.width + x;
          if (done[k]) continue;
          const float dx = g.mean.x() - (x + 0.5f), dy = g.mean.y() - (y + 0.5f);
          const float sigma = 0.5f * (g.conic[0] * dx * dx + g.conic[2] * dy * dy) + g.conic[1] * dx * dy;
          if (sigma < 0.f) continue;
          const float a = std::min(0.999f, p.opacity * std::exp(-sigma));
          if (a < 1.f / 255.f) continue;
          const float Tn = T[k] * (1.f - a);
          if (Tn <= 1e-4f) { done[k] = 1; continue; }
          for (int c = 0; c < 3; ++c) out.rgb.data[k * 3 + c] += rgb[c] * a * T[k];
          if (q.want_depth) out.depth.data[k] += g.depth * a * T[k];
          T[k] = Tn;
        }
    }
    for (std::size_t k = 0; k < T.size(); ++k) {
      out.alpha.data[k] = 1.f - T[k];
      for (int c = 0; c < 3; ++c) out.rgb.data[k * 3 + c] += T[k] * q.background[c];
    }
    return out;
  }
};
static_assert(vcar::Renderer<ReferenceRenderer>);

}  // namespace synth_test
