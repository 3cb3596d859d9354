#pragma once
// Beyond the paper: the uncertainty band along a mask's edge (docs/robust.md, Eq. R1).
//
// A segmenter's mask is least reliable next to its own contour (erosion, dilation, a pixel of
// rasterisation at a silhouette rim). For mask M^(j) with A_j foreground pixels the band
// half-width follows the mask's own scale:
//   w_j = max(1, round(beta sqrt(A_j / pi)))                                       (Eq. R1a)
// and with B_w(p) the (2 w_j + 1)^2 box around pixel p, clipped to the image,
//   sure foreground  iff every pixel of B_w(p) is foreground,
//   sure background  iff no pixel of B_w(p) is foreground,
//   unsure otherwise (p lies within w_j pixels, Chebyshev, of the contour).      (Eq. R1b)
// One summed-area table per mask: O(W H) per view, independent of the number of Gaussians.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "vcar/core/image.hpp"

namespace vcar {

// Eq. R1a: band half-width in pixels for a mask with `foreground` pixels (beta > 0).
inline int edge_band_width(std::size_t foreground, float beta) {
  const double r_eq = std::sqrt(static_cast<double>(foreground) / std::numbers::pi);
  return std::max(1, static_cast<int>(std::lround(static_cast<double>(beta) * r_eq)));
}

// The two planes of Eq. R1b as masks of the view's size (255 = set): pixels that are sure
// foreground, and pixels that are sure (foreground or background).
struct EdgeBandMasks {
  Mask sure_foreground;
  Mask sure;
  int w = 0;  // the half-width used
};

// Eq. R1b with half-width w (>= 0; w = 0 makes every pixel sure). `scratch` is reused across
// calls (the summed-area table, (W+1)(H+1) uint32).
inline void edge_band(const Mask& m, int w, EdgeBandMasks& out, std::vector<std::uint32_t>& scratch) {
  const int W = m.width, H = m.height;
  const std::size_t S = static_cast<std::size_t>(W) + 1;
  scratch.assign(S * (static_cast<std::size_t>(H) + 1), 0u);
  for (int y = 0; y < H; ++y) {
    std::uint32_t row = 0;
    const std::uint8_t* src = m.data.data() + static_cast<std::size_t>(y) * W;
    std::uint32_t* above = scratch.data() + static_cast<std::size_t>(y) * S;
    std::uint32_t* cur = above + S;
    for (int x = 0; x < W; ++x) {
      row += src[x] != 0;
      cur[x + 1] = above[x + 1] + row;
    }
  }
  out.w = w;
  for (Mask* plane : {&out.sure_foreground, &out.sure}) {
    plane->width = W; plane->height = H; plane->channels = 1;
    plane->data.assign(static_cast<std::size_t>(W) * H, 0);
  }
  for (int y = 0; y < H; ++y) {
    const int y0 = std::max(0, y - w), y1 = std::min(H, y + w + 1);
    const std::uint32_t* top = scratch.data() + static_cast<std::size_t>(y0) * S;
    const std::uint32_t* bot = scratch.data() + static_cast<std::size_t>(y1) * S;
    std::uint8_t* fg = out.sure_foreground.data.data() + static_cast<std::size_t>(y) * W;
    std::uint8_t* sure = out.sure.data.data() + static_cast<std::size_t>(y) * W;
    for (int x = 0; x < W; ++x) {
      const int x0 = std::max(0, x - w), x1 = std::min(W, x + w + 1);
      const std::uint32_t count = bot[x1] - bot[x0] - top[x1] + top[x0];
      const std::uint32_t area = static_cast<std::uint32_t>((x1 - x0) * (y1 - y0));
      fg[x] = count == area ? 255 : 0;
      sure[x] = (count == area || count == 0) ? 255 : 0;
    }
  }
}

}  // namespace vcar
