#pragma once
// FlashSplat (Shen et al. 2024), binary case (conventions §8):
//   A[1][i] = sum over masked views and foreground pixels of alpha_i T_i,
//   A[0][i] = the same over background pixels;
// each Gaussian's column (A[0][i], A[1][i]) is L2-normalised, the background bias gamma is added
// to label 0 and the label is the argmax: foreground iff a1 > a0 + gamma (ties go to background,
// as do Gaussians that never contribute). score_i = a1 - a0 in [-1, 1].
// gamma = 0 by default: the unbiased optimum of FlashSplat's linear program; a positive gamma
// removes Gaussians that are only marginally foreground (noisy masks), a negative one keeps them.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>
#include <cstddef>
#include <span>

#include "vcar/baselines/inputs.hpp"
#include "vcar/baselines/view_contributions.hpp"

namespace vcar::baselines {

struct FlashSplatParams {
  float gamma = 0.f;  // background bias added to the normalised label-0 column entry
};

// From the accumulated sums (reusable across gammas).
inline Result flashsplat_from(const Contributions& c, const FlashSplatParams& p = {}) {
  const std::size_t n = c.weight.size();
  Result r;
  r.score.assign(n, 0.f);
  std::vector<std::uint8_t> fg(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const double a1 = c.weight_fg[i], a0 = std::max(0.0, c.weight[i] - c.weight_fg[i]);
    const double norm = std::sqrt(a0 * a0 + a1 * a1);
    if (!(norm > 0.0)) continue;
    r.score[i] = static_cast<float>((a1 - a0) / norm);
    fg[i] = a1 / norm > a0 / norm + p.gamma;
  }
  r.selected = select_where(n, [&](std::size_t i) { return fg[i] != 0; });
  return r;
}

template <ContributionRenderer R>
Result flashsplat(R& renderer, const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
                  const FlashSplatParams& p = {}) {
  return flashsplat_from(view_contributions(renderer, scene, cameras, masks), p);
}

}  // namespace vcar::baselines
