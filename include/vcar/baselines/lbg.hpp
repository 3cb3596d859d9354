#pragma once
// LBG (Chacko et al. 2025), lifting by maximum contributor (conventions §8): in every view with
// a mask, each pixel votes for its maximum contributor argmax_i alpha_i T_i (pixels where
// nothing is composited vote for nobody); a Gaussian is foreground when a strict majority of the
// pixels that chose it are foreground. score_i = foreground votes / votes (0 without votes).
// The per-pixel maximum contributor comes from a callback Image<int32> (const Camera&), -1 =
// none; by default the reference walk of contribution_walk.hpp (gsplat rules).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vcar/baselines/contribution_walk.hpp"
#include "vcar/baselines/inputs.hpp"

namespace vcar::baselines {

template <class MaxContributor>
Result lbg(const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
           MaxContributor&& max_contributor_of) {
  const std::size_t n = scene.size();
  std::vector<std::uint64_t> votes(n, 0), votes_fg(n, 0);
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    const Mask* m = checked_mask(masks, cameras, j);
    if (!m) continue;
    const Image<std::int32_t> who = max_contributor_of(cameras[j]);
    if (who.width != m->width || who.height != m->height)
      throw Error("maximum-contributor map has the wrong size", "view '" + cameras[j].name + "'");
    for (std::size_t px = 0; px < who.data.size(); ++px) {
      const std::int32_t i = who.data[px];
      if (i < 0 || static_cast<std::size_t>(i) >= n) continue;
      ++votes[i];
      votes_fg[i] += m->data[px] != 0;
    }
  }
  Result r;
  r.score.assign(n, 0.f);
  for (std::size_t i = 0; i < n; ++i)
    if (votes[i]) r.score[i] = static_cast<float>(double(votes_fg[i]) / double(votes[i]));
  r.selected = select_where(n, [&](std::size_t i) { return 2 * votes_fg[i] > votes[i]; });
  return r;
}

inline Result lbg(const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks) {
  return lbg(scene, cameras, masks, [&](const Camera& cam) { return max_contributor(scene, cam); });
}

}  // namespace vcar::baselines
