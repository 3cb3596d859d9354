#pragma once
// Eq. R14 (beyond the paper): a fine-round mask registered to the render it was drawn on.
// In the fine round the segmenter sees renders of G_coarse, whose alpha is a silhouette of the
// candidates; a mask displaced against its own frame (a segmenter that tracks and drifts, a
// box off by a few pixels) takes the object's thin parts out of the vote. The mask is moved by
// the integer translation s that maximises
//   IoU(M_s, A),  M_s(p) = M(p - s),  A = {p : alpha(p) > 0.5},  |s|_inf <= r,            (Eq. R14)
// r = ceil(fine_registration * sqrt(|A|)) (relative to the silhouette's size), found coarse to
// fine (step 4 over the square, then 2 and 1 around the best): IoU of a compact silhouette is
// unimodal over shifts of a few pixels. Pixels moved out of the image are dropped.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vcar/core/image.hpp"

namespace vcar {

struct MaskShift {
  int dx = 0, dy = 0;         // s: M_s(x, y) = M(x - dx, y - dy)
  double iou_unmoved = 0.0;   // IoU(M, A)
  double iou = 0.0;           // IoU(M_s, A)
};

namespace detail {
// IoU(M_s, A) from M's foreground pixels (x, y pairs) and A (0/1 per pixel).
inline double shifted_iou(const std::vector<int>& fg, const std::vector<std::uint8_t>& a, std::size_t a_count,
                          int w, int h, int dx, int dy) {
  std::size_t inside = 0, inter = 0;
  for (std::size_t k = 0; k < fg.size(); k += 2) {
    const int x = fg[k] + dx, y = fg[k + 1] + dy;
    if (x < 0 || y < 0 || x >= w || y >= h) continue;
    ++inside;
    inter += a[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)];
  }
  const std::size_t uni = inside + a_count - inter;
  return uni == 0 ? 0.0 : static_cast<double>(inter) / static_cast<double>(uni);
}
}  // namespace detail

// Eq. R14: the translation of `m` (within radius r px, |s|_inf) that best overlaps alpha > 0.5.
// Ties keep the shorter shift; an empty mask or silhouette stays where it is.
inline MaskShift register_to_alpha(const Mask& m, const ImageF& alpha, int r) {
  MaskShift best;
  const int w = m.width, h = m.height;
  if (alpha.width != w || alpha.height != h || m.data.empty()) return best;
  std::vector<std::uint8_t> a(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::size_t a_count = 0;
  for (std::size_t i = 0; i < a.size(); ++i) a_count += a[i] = alpha.data[i] > 0.5f;
  std::vector<int> fg;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (m.data[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)]) {
        fg.push_back(x);
        fg.push_back(y);
      }
  if (fg.empty() || a_count == 0) return best;
  best.iou = best.iou_unmoved = detail::shifted_iou(fg, a, a_count, w, h, 0, 0);
  auto consider = [&](int dx, int dy) {
    if (std::max(std::abs(dx), std::abs(dy)) > r) return;
    const double v = detail::shifted_iou(fg, a, a_count, w, h, dx, dy);
    const bool shorter = dx * dx + dy * dy < best.dx * best.dx + best.dy * best.dy;
    if (v > best.iou || (v == best.iou && shorter)) {
      best.dx = dx;
      best.dy = dy;
      best.iou = v;
    }
  };
  const int coarse = 4;
  for (int dy = -(r / coarse) * coarse; dy <= r; dy += coarse)
    for (int dx = -(r / coarse) * coarse; dx <= r; dx += coarse) consider(dx, dy);
  for (int step : {2, 1}) {
    const int cx = best.dx, cy = best.dy;
    for (int dy = -step; dy <= step; dy += step)
      for (int dx = -step; dx <= step; dx += step) consider(cx + dx, cy + dy);
  }
  return best;
}

// Eq. R14's radius: ceil(factor * sqrt(|alpha > 0.5|)) px (0 when factor <= 0).
inline int registration_radius(const ImageF& alpha, float factor) {
  if (!(factor > 0.f)) return 0;
  std::size_t n = 0;
  for (float v : alpha.data) n += v > 0.5f;
  return static_cast<int>(std::ceil(static_cast<double>(factor) * std::sqrt(static_cast<double>(n))));
}

// M_s: `m` moved by (dx, dy), what leaves the image dropped.
inline Mask shifted(const Mask& m, int dx, int dy) {
  Mask out(m.width, m.height, 1);
  for (int y = 0; y < m.height; ++y) {
    const int sy = y - dy;
    if (sy < 0 || sy >= m.height) continue;
    for (int x = 0; x < m.width; ++x) {
      const int sx = x - dx;
      if (sx < 0 || sx >= m.width) continue;
      out.data[static_cast<std::size_t>(y) * static_cast<std::size_t>(m.width) + static_cast<std::size_t>(x)] =
          m.data[static_cast<std::size_t>(sy) * static_cast<std::size_t>(m.width) + static_cast<std::size_t>(sx)];
    }
  }
  return out;
}

}  // namespace vcar
