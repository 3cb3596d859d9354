#pragma once
// Per-Gaussian sums over every view with a mask (conventions §8):
//   weight[i] = sum_views sum_p alpha_i T_i,  weight_fg[i] = the same over foreground pixels.
// Views without a mask add nothing (no evidence).
#include <cstddef>
#include <span>

#include "vcar/baselines/inputs.hpp"
#include "vcar/concepts/renderer.hpp"

namespace vcar::baselines {

template <ContributionRenderer R>
Contributions view_contributions(R& renderer, const GaussianScene& scene, std::span<const Camera> cameras,
                                 const MaskProvider& masks) {
  Contributions acc;
  acc.reset(scene.size());
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    const Mask* m = checked_mask(masks, cameras, j);
    if (!m) continue;
    RenderRequest q;
    q.scene = &scene;
    q.camera = &cameras[j];
    renderer.accumulate_contributions(q, *m, acc);
  }
  return acc;
}

}  // namespace vcar::baselines
