#pragma once
// Beyond the paper: a mask that stops short of the render's occlusion edges grows to them
// (docs/robust.md, Eq. R12). Used in the coarse round only, on the renders of the whole scene.
//
// A segmenter that undershoots (an eroded mask, SAM missing a thin rim) leaves a band of the
// object outside the mask in every view. The object's surface Gaussians near its rim then sit
// outside the mask in the views that see them edge-on, their coarse ratios fall below tau, and
// the selection loses its rim; no later step brings it back. The render of the whole scene
// shows where the object ends: at an occlusion edge (Eq. R11a, the near side of a depth step or
// of an empty pixel). Between an undershooting contour and that edge the render's surface is
// depth-continuous. With A_j, D^_j the render's alpha and expected depth (as in Eq. R11a),
// two 8-neighbour pixels p, q are joined when
//   A_j(p) >= 0.5, A_j(q) >= 0.5  and  max(D^_j(p), D^_j(q)) <= (1 + delta) min(D^_j(p), D^_j(q))
// and, over the covered pixels outside M_j, with paths of joined steps,
//   a_j(p) = the fewest steps from a pixel of M_j to p
//   b_j(p) = the fewest steps from a pixel of E_j outside M_j to p                   (Eq. R12a)
// A pixel lies in the gap between the mask and an occlusion edge when a path from the mask
// through it reaches the edge within the reach r_j:
//   M'_j = M_j  union  {p : a_j(p) + b_j(p) <= r_j}                                   (Eq. R12b)
//   r_j  = min(-o_j + m_g, g |diag|, sqrt(|M_j| / pi))     where q3_j < 1 px (Eq. R11b) (Eq. R12c)
// (m_g = 1 px, grow_margin_px; g = 0.1 of the image diagonal, grow_max_diagonal; 1 px,
// overshoot_min_px, the floor of R11's o_min: a mask that R11 erodes does not grow). Where the
// object touches the table the surface is continuous but no occlusion edge lies beyond the
// contact, so b_j stays above the reach there and the table is not taken; the far side of a
// depth step is never reached. The last term keeps a mask of a part (a handle prompted inside a
// mug's silhouette) from growing into the whole: its contour moves by at most the mask's own
// radius. Two breadth-first searches of at most r_j steps each, over the pixels they reach.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vcar/core/image.hpp"
#include "vcar/core/pixel_box.hpp"

namespace vcar {

// Eq. R12c's constants (fields grow_margin and grow_max until 2026-12-03; R11 and R12 now share
// one switch, VcarParams::snap): the margin in pixels of the view (the contour's grid, as R11's),
// the cap as a fraction of the image diagonal.
inline constexpr double grow_margin_px = 1.0;     // m_g
inline constexpr double grow_max_diagonal = 0.1;  // g

// Eq. R12c: the reach r_j (px, rounded up to whole steps; 0: no growth) of a mask with `foreground` pixels
// whose contour lies o_j px outside the occlusion edges (Eq. R11b), in an image of the given size.
inline int growth_reach(double o_j, std::size_t foreground, int width, int height, double grow_max, double margin) {
  const double diagonal = std::hypot(static_cast<double>(width), static_cast<double>(height));
  const double r = std::min({-o_j + margin, grow_max * diagonal,
                             std::sqrt(static_cast<double>(foreground) / 3.14159265358979323846)});
  return r > 0.0 ? static_cast<int>(std::ceil(r)) : 0;
}

// The pixels whose edges can decide Eq. R12b for mask m and reach r: a pixel added lies within
// r steps of the mask (a_j <= r) and within r - 1 of an edge pixel (b_j <= r - a_j, a_j >= 1), so
// that edge pixel lies within 2 r - 1 px (8-neighbour steps) of the mask's bounding box.
inline PixelBox growth_seed_box(const Mask& m, int reach) { return foreground_box(m, 2 * std::max(reach, 0)); }

// Eq. R12a-b: grows m (in place) by the covered pixels on a depth-continuous path of at most
// `reach` steps from the mask to an occlusion edge outside it. `edge`: Eq. R11a of the render
// (alpha, expected depth sum z alpha T), delta its depth step. Returns the pixels added.
inline std::size_t grow_to_occlusion_edges(Mask& m, const std::vector<std::uint8_t>& edge, const ImageF& alpha,
                                           const ImageF& depth, float delta, int reach) {
  if (reach <= 0) return 0;
  const int W = m.width, H = m.height;
  const std::size_t N = m.data.size();
  auto covered = [&](std::size_t q) { return alpha.data[q] >= 0.5f; };
  auto z = [&](std::size_t q) { return depth.data[q] / alpha.data[q]; };
  constexpr std::uint16_t unreached = 0xffff;
  // Eq. R12a: steps from the seeds through covered pixels outside the mask, at most `reach`.
  auto steps_from = [&](std::vector<std::uint32_t> front) {
    std::vector<std::uint16_t> d(N, unreached);
    for (std::uint32_t q : front) d[q] = 0;
    std::vector<std::uint32_t> next;
    for (int step = 1; step <= reach && !front.empty(); ++step) {
      next.clear();
      for (std::uint32_t q : front) {
        if (!covered(q)) continue;
        const int x = static_cast<int>(q % static_cast<std::uint32_t>(W)), y = static_cast<int>(q / static_cast<std::uint32_t>(W));
        const float zq = z(q);
        for (int v = std::max(0, y - 1); v <= std::min(H - 1, y + 1); ++v)
          for (int u = std::max(0, x - 1); u <= std::min(W - 1, x + 1); ++u) {
            const std::size_t r = static_cast<std::size_t>(v) * W + u;
            if (d[r] != unreached || m.data[r] || !covered(r)) continue;
            const float zr = z(r);
            if (std::max(zq, zr) > std::min(zq, zr) * (1.f + delta)) continue;  // not joined
            d[r] = static_cast<std::uint16_t>(step);
            next.push_back(static_cast<std::uint32_t>(r));
          }
      }
      front.swap(next);
    }
    return d;
  };
  // Seeds: mask pixels with an 8-neighbour outside the mask; edge pixels outside the mask.
  std::vector<std::uint32_t> from_mask, from_edge;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * W + x;
      if (!m.data[q]) {
        if (edge[q]) from_edge.push_back(static_cast<std::uint32_t>(q));
        continue;
      }
      bool rim = false;
      for (int v = std::max(0, y - 1); v <= std::min(H - 1, y + 1) && !rim; ++v)
        for (int u = std::max(0, x - 1); u <= std::min(W - 1, x + 1) && !rim; ++u)
          rim = !m.data[static_cast<std::size_t>(v) * W + u];
      if (rim) from_mask.push_back(static_cast<std::uint32_t>(q));
    }
  if (from_mask.empty() || from_edge.empty()) return 0;
  const std::vector<std::uint16_t> a = steps_from(std::move(from_mask)), b = steps_from(std::move(from_edge));
  std::size_t added = 0;
  for (std::size_t q = 0; q < N; ++q)
    if (a[q] != unreached && b[q] != unreached && a[q] + b[q] <= reach) {  // Eq. R12b
      m.data[q] = 255;
      ++added;
    }
  return added;
}

}  // namespace vcar
