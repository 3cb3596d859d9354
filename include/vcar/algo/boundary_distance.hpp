#pragma once
// Directional boundary distance l_u of ABR (supplementary B.3): from the projected centre m,
// march along the signed unit direction u towards the overflowing endpoint m + L u and find the
// first exit from the mask foreground or the image.
#include <Eigen/Core>

#include "vcar/core/image.hpp"

namespace vcar {

// The march of B.3: samples t_k = k step, k = 0 .. last, each looked up in the pixel that
// contains m + t_k u (floor, conventions §2). Returns the first k whose sample is outside the
// foreground or the image, last + 1 when there is none. (Skipping samples that share a pixel,
// or testing them 8 at a time without branches, measured slower: the plain loop's lookups are
// independent and overlap.)
inline int first_exit_sample(const Mask& mask, const Eigen::Vector2f& m, const Eigen::Vector2f& u, float step,
                             int last) {
  for (int k = 0; k <= last; ++k) {
    const float t = static_cast<float>(k) * step;
    if (!mask_at(mask, m.x() + t * u.x(), m.y() + t * u.y())) return k;
  }
  return last + 1;
}

// l_u (B.3) from the first exit sample k of a march with `step`: halfway between the last
// foreground sample and the first sample outside; 0 when the centre itself is outside (k = 0).
inline float exit_distance(int k, float step) {
  return k == 0 ? 0.f : 0.5f * (static_cast<float>(k - 1) * step + static_cast<float>(k) * step);
}

// l_u (B.3): `samples` points t_k = k L / (samples - 1), k = 0 .. samples-1, uniformly from the
// centre (k = 0) to the endpoint (k = samples-1). The boundary is halfway between the last
// foreground sample and the first sample outside the foreground or the image; L when every
// sample is foreground; 0 when the centre itself is outside (no foreground sample; never the
// case for an eligible observation). Stops at the first exit.
inline float boundary_distance(const Mask& mask, const Eigen::Vector2f& m, const Eigen::Vector2f& u, float L,
                               int samples = 129) {
  const float step = L / static_cast<float>(samples - 1);  // 128 step == L exactly for 129 samples
  const int k = first_exit_sample(mask, m, u, step, samples - 1);
  return k == samples ? L : exit_distance(k, step);
}

}  // namespace vcar
