#pragma once
// Naive centre voting (conventions §8): in every view with a mask, a Gaussian votes foreground
// when its projected centre falls in the mask; invisible (behind, outside the image) counts as
// background. score_i = foreground votes / views with a mask; kept when score_i >= tau.
// Views without a mask are no evidence for anyone and do not count.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vcar/baselines/inputs.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::baselines {

struct NaiveVotingParams {
  float tau = 0.5f;  // foreground share over all masked views
};

inline Result naive_voting(const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
                           const NaiveVotingParams& p = {}) {
  const std::size_t n = scene.size();
  std::vector<std::uint32_t> fg(n, 0);
  std::uint32_t views = 0;
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    const Mask* m = checked_mask(masks, cameras, j);
    if (!m) continue;
    ++views;
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
      fg[i] += point_label(cameras[j], m, scene.mu(i)) == 1;
    });
  }
  Result r;
  r.score.resize(n);
  for (std::size_t i = 0; i < n; ++i) r.score[i] = views ? float(fg[i]) / float(views) : 0.f;
  r.selected = select_where(n, [&](std::size_t i) { return views > 0 && r.score[i] >= p.tau; });
  return r;
}

}  // namespace vcar::baselines
