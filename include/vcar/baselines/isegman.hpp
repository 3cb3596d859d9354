#pragma once
// iSegMan-style visibility-guided voting weighted by opacity (conventions §8; the exact weights
// are not published in text we could read, these are ours):
//   w_ij = alpha_i(c) T_i(c), the composited weight of Gaussian i at the pixel c containing its
//          own projected centre in view j (opacity x Gaussian falloff x transmittance of what is
//          in front): 0 when the centre is off-image, the Gaussian is culled, or the pixel is
//          saturated before it (gsplat rules of contribution_walk.hpp);
//   R_i  = sum_j w_ij [mask_j(c) != 0] / sum_j w_ij over views with a mask;
//   kept when R_i >= tau (0.5). Never-visible Gaussians (sum w = 0) get R = 0.
// So an occluded or faint Gaussian barely votes, unlike centre voting where every projected
// centre counts the same. score_i = R_i.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vcar/baselines/contribution_walk.hpp"
#include "vcar/baselines/inputs.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::baselines {

struct ISegManParams {
  float tau = 0.5f;
};

// w_ij of the header comment for every Gaussian of the scene in one view.
inline std::vector<float> centre_visibility(const GaussianScene& scene, const Camera& cam) {
  const std::size_t n = scene.size();
  constexpr std::int64_t off = -1;
  std::vector<std::int64_t> centre(n, off);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
    const Eigen::Vector3f t = cam.to_camera(scene.mu(i));
    if (!(t.z() > 0.f)) return;
    const float u = cam.fx * t.x() / t.z() + cam.cx, v = cam.fy * t.y() / t.z() + cam.cy;
    if (!inside_image(u, v, cam.width, cam.height)) return;
    centre[i] = static_cast<std::int64_t>(v) * cam.width + static_cast<std::int64_t>(u);
  });
  std::vector<float> w(n, 0.f);
  // Gaussian i is written only at its own centre pixel, i.e. by one tile: no race.
  for_each_contribution(scene, cam, nullptr, [&](std::size_t p, Index i, float alpha, float T) {
    if (centre[i] == static_cast<std::int64_t>(p)) w[i] = alpha * T;
  });
  return w;
}

inline Result isegman(const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
                      const ISegManParams& p = {}) {
  const std::size_t n = scene.size();
  std::vector<double> num(n, 0.0), den(n, 0.0);
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    const Mask* m = checked_mask(masks, cameras, j);
    if (!m) continue;
    const std::vector<float> w = centre_visibility(scene, cameras[j]);
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
      if (!(w[i] > 0.f)) return;
      den[i] += w[i];
      if (point_label(cameras[j], m, scene.mu(i)) == 1) num[i] += w[i];
    });
  }
  Result r;
  r.score.assign(n, 0.f);
  for (std::size_t i = 0; i < n; ++i)
    if (den[i] > 0.0) r.score[i] = static_cast<float>(num[i] / den[i]);
  r.selected = select_where(n, [&](std::size_t i) { return den[i] > 0.0 && r.score[i] >= p.tau; });
  return r;
}

}  // namespace vcar::baselines
