#pragma once
// The renderer's view-dependent colour of Lane::size Gaussians at once (conventions §3): the
// steps of core/spherical_harmonics.hpp's sh_to_rgb, the direction and basis SIMD over the
// Gaussians, then each Gaussian's sums in sh_to_rgb's order (results equal up to how
// multiply-adds fuse). The renderer shades every splat on screen with its projection, in index
// order: the coefficients then stream through memory, where shading a splat on first use read
// them at random.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>

#include "vcar/backends/cpu/tile_compositing.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/simd.hpp"
#include "vcar/core/spherical_harmonics.hpp"

namespace vcar::cpu {

namespace detail {
// rgb[c][l] = max(0, 0.5 + sum_k Y_k sh[k][c]) for the lanes l set in `lanes`, B = (degree+1)^2
// coefficients starting at rows[l].
template <int B>
inline void shade_rows(const Lane dir[3], const float* const* rows, std::uint32_t lanes, float (*rgb)[Lane::size]) {
  constexpr int L = static_cast<int>(Lane::size);
  alignas(64) float Y[B][L];  // basis value k of lane l at Y[k][l]
  if constexpr (B == 1) {
    for (int l = 0; l < L; ++l) Y[0][l] = sh::C0;  // no direction needed
  } else {
    // Divide (not multiply by 1/n): the bits of sh_to_rgb's dir / |dir|.
    const Lane zero(0.f);
    const Lane n = simd::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    const auto pos = n > zero;
    constexpr int degree = B == 4 ? 1 : B == 9 ? 2 : 3;
    Lane y[B];
    sh_basis(degree, simd::select(pos, dir[0] / n, zero), simd::select(pos, dir[1] / n, zero),
             simd::select(pos, dir[2] / n, zero), y);
    for (int k = 0; k < B; ++k) y[k].store_aligned(Y[k]);
  }
  // Lane by lane, over the set bits (a loop the compiler does not turn into gathers, which cost
  // more than these scalar loads).
  for (std::uint32_t left = lanes; left != 0; left &= left - 1) {
    const int l = std::countr_zero(left);
    const float* c = rows[l];
    float r = 0.f, g = 0.f, b = 0.f;
    for (int k = 0; k < B; ++k) {
      r += Y[k][l] * c[k * 3 + 0];
      g += Y[k][l] * c[k * 3 + 1];
      b += Y[k][l] * c[k * 3 + 2];
    }
    rgb[0][l] = std::max(0.f, 0.5f + r);
    rgb[1][l] = std::max(0.f, 0.5f + g);
    rgb[2][l] = std::max(0.f, 0.5f + b);
  }
}
}  // namespace detail

// Colour of the Gaussians with scene indices idx[l] for the lanes l set in `lanes` (bit l), seen
// from `eye`: rgb[c][l]. mu holds their means (lane l: Gaussian idx[l]). Other lanes are left
// as they are (no coefficients are read for them).
inline void shade_batch(const GaussianScene& sc, const std::size_t* idx, std::uint32_t lanes, const Lane mu[3],
                        const float eye[3], float (*rgb)[Lane::size]) {
  constexpr int L = static_cast<int>(Lane::size);
  const int B = sc.sh_coeffs();
  const float* rows[L];
  for (int l = 0; l < L; ++l)
    rows[l] = (lanes >> l) & 1u ? sc.sh.data() + idx[l] * static_cast<std::size_t>(3 * B) : nullptr;
  const Lane dir[3] = {mu[0] - Lane(eye[0]), mu[1] - Lane(eye[1]), mu[2] - Lane(eye[2])};
  switch (B) {
    case 1: detail::shade_rows<1>(dir, rows, lanes, rgb); break;
    case 4: detail::shade_rows<4>(dir, rows, lanes, rgb); break;
    case 9: detail::shade_rows<9>(dir, rows, lanes, rgb); break;
    default: detail::shade_rows<16>(dir, rows, lanes, rgb); break;
  }
}

}  // namespace vcar::cpu
