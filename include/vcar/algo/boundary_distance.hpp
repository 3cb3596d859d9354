#pragma once
// Directional boundary distance l_u of ABR (supplementary B.3): from the projected centre m,
// march along the signed unit direction u towards the overflowing endpoint m + L u and find the
// first exit from the mask foreground or the image.
#include <algorithm>
#include <bit>
#include <cstdint>

#include <Eigen/Core>

#include "vcar/core/image.hpp"
#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/simd.hpp"

namespace vcar {

// The first of the lanes 0 .. n-1 whose point (x, y) is outside the foreground or the image
// (mask_at), -1 when none is.
inline int first_outside(const Mask& mask, const simd::batch<float>& x, const simd::batch<float>& y, int n) {
  alignas(64) float xs[simd::width], ys[simd::width];
  x.store_aligned(xs);
  y.store_aligned(ys);
  for (int l = 0; l < n; ++l)
    if (!mask_at(mask, xs[l], ys[l])) return l;
  return -1;
}
inline int first_outside(const MaskTiles& tiles, const simd::batch<float>& x, const simd::batch<float>& y, int n) {
  const std::uint32_t out = ~simd::nonzero_lanes(mask_at(tiles, x, y)) & ((2u << (n - 1)) - 1u);  // lanes 0 .. n-1
  return out ? std::countr_zero(out) : -1;
}

// The march of B.3: samples t_k = k step, k = 0 .. last, each looked up in the pixel that
// contains m + t_k u (floor, conventions §2). Returns the first k whose sample is outside the
// foreground or the image, last + 1 when there is none. The points are computed simd::width
// samples at a time (t_k = float(k) step, then one fused multiply-add per coordinate), the same
// bits for every mask type; `mask` is the Mask (looked up lane by lane) or its MaskTiles (one
// gather per batch), which give the same answers.
template <class MaskLike>
int first_exit_sample(const MaskLike& mask, const Eigen::Vector2f& m, const Eigen::Vector2f& u, float step,
                      int last) {
  using B = simd::batch<float>;
  constexpr int L = static_cast<int>(simd::width);
  alignas(64) float lane[L];
  for (int l = 0; l < L; ++l) lane[l] = static_cast<float>(l);
  const B lanes = B::load_aligned(lane), mx(m.x()), my(m.y()), ux(u.x()), uy(u.y()), st(step);
  for (int k0 = 0; k0 <= last; k0 += L) {
    const B t = (B(static_cast<float>(k0)) + lanes) * st;  // float(k) step (k < 2^24: exact sums)
    const int e = first_outside(mask, simd::fma(t, ux, mx), simd::fma(t, uy, my), std::min(L, last - k0 + 1));
    if (e >= 0) return k0 + e;
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
template <class MaskLike>
float boundary_distance(const MaskLike& mask, const Eigen::Vector2f& m, const Eigen::Vector2f& u, float L,
                               int samples = 129) {
  const float step = L / static_cast<float>(samples - 1);  // 128 step == L exactly for 129 samples
  const int k = first_exit_sample(mask, m, u, step, samples - 1);
  return k == samples ? L : exit_distance(k, step);
}

}  // namespace vcar
