#pragma once
// Beyond the paper: an outer band as wide as the mask's measured undershoot (docs/robust.md,
// Eq. R6). Used in the fine round, whose frames are renders of G_coarse alone.
//
// A segmenter that undershoots (an eroded mask) does it again on every frame of the fine round,
// so the rim of G_coarse falls outside the mask of every sampled view and the fine vote erodes
// the coarse selection a second time. In that round the library has the render of the object
// it asked about (alpha A_j of G_coarse), and the mask's undershoot can be read off the frame:
//   C_j  = contour of M_j: foreground pixels with a 4-neighbour background pixel in the image
//   e_j  = median over p in C_j of max(0, dist(p, {A_j < 0.5}) - 1)                 (Eq. R6a)
// (distance between pixel centres; a contour on the render's own edge gives 0, a mask eroded by
// e px inside the render gives ~e, a dilated one 0). The background pixels of M_j within
//   reach_j = gamma e_j                                                             (Eq. R6b)
// px (Euclidean) of its foreground are no evidence (unsure): a Gaussian of G_coarse that the
// undershooting mask leaves out is not counted as background there. With e_j = 0 nothing
// changes. Two distance transforms per frame, over boxes around the mask (undershoot_px,
// for_each_within_reach).
//
// When the fine vote is split (Eq. R7 kept tau_fine: the masks disagree systematically, as
// undershooting masks do), ABR (Eq. 9-14) reads each training view's mask widened by its e_j:
//   M'_j = M_j  union  {p : dist(p, M_j) <= e_j}                                    (Eq. R8)
// so a rim Gaussian whose ellipse reaches past an eroded mask is not shrunk for the erosion.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "vcar/core/distance_transform.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/mask_contour.hpp"
#include "vcar/core/nearest_pixels.hpp"
#include "vcar/core/pixel_box.hpp"
#include "vcar/core/row_seeds.hpp"

namespace vcar {

// Eq. R6a: the undershoot e_j of mask m against the render alpha (same size, one channel), px.
// 0 when the mask has no contour or the render no background. First each contour pixel looks
// for the render's background within `reach` px, nearest first (NearestPixels): when more than
// half of them find it, the median is theirs (the others' values are larger). Otherwise the
// distance transform runs over the mask's bounding box grown by `window` px; a contour pixel
// farther from the render's background in the box than from the box's outside (the background
// there could be nearer) reads the nearest background pixel of the whole image instead (by rows,
// RowSeeds). Either way the result is the whole image's transform's, for any reach and window.
inline constexpr int undershoot_window_px = 48;
inline double undershoot_px(const Mask& m, const ImageF& alpha, int window = undershoot_window_px,
                            int reach = contour_reach_px) {
  const int W = m.width, H = m.height;
  auto background = [&](int x, int y) { return !(alpha.data[static_cast<std::size_t>(y) * W + x] >= 0.5f); };
  auto value = [](double d2) { return std::isfinite(d2) ? std::max(0.0, std::sqrt(d2) - 1.0) : std::numeric_limits<double>::quiet_NaN(); };
  if (reach > 0 && std::any_of(alpha.data.begin(), alpha.data.end(), [](float a) { return !(a >= 0.5f); })) {
    const NearestPixels& near = nearest_pixels(reach);
    std::vector<double> found;
    std::size_t contour = 0;
    for_each_contour_pixel(m, [&](std::size_t q) {
      ++contour;
      const int x = static_cast<int>(q % static_cast<std::size_t>(W)), y = static_cast<int>(q / static_cast<std::size_t>(W));
      const int d2 = nearest_squared_distance(near, x, y, W, H, [&](std::size_t r) { return !(alpha.data[r] >= 0.5f); });
      if (d2 >= 0) found.push_back(value(d2));
    });
    if (contour == 0) return 0.0;
    // Every value found is at most reach - 1, every other one larger: the median (the upper one
    // of an even count, contour_quartiles) is the found values' when it falls among them.
    const std::size_t mid = contour / 2;
    if (mid < found.size()) {
      std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(mid), found.end());
      return found[mid];
    }
  }
  const PixelBox b = foreground_box(m, std::max(window, 0));
  if (b.width() <= 0) return 0.0;  // no foreground, no contour
  const std::vector<double> box = squared_distance_in(b, background);
  std::optional<RowSeeds> whole;  // the whole image's, only when a pixel needs it
  return contour_median(m, [&](std::size_t q) {
    const int x = static_cast<int>(q % static_cast<std::size_t>(W)), y = static_cast<int>(q / static_cast<std::size_t>(W));
    const double o = b.distance_to_outside(x, y, W, H);
    double d2 = box[b.at(x, y)];
    if (!(d2 <= o * o)) {
      if (!whole) whole.emplace(W, H, background);
      d2 = whole->nearest_squared(x, y);
    }
    return value(d2);
  });
}

// Eq. R14's gate: true when the median of the round's undershoots e (px, Eq. R6a, one per
// masked frame) is positive, i.e. the round's masks measurably undershoot.
inline bool masks_undershoot(std::vector<double> e) {
  if (e.empty()) return false;
  const auto mid = e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2);
  std::nth_element(e.begin(), mid, e.end());
  double median = *mid;
  if (e.size() % 2 == 0) median = 0.5 * (median + *std::max_element(e.begin(), mid));
  return median > 0.0;
}

namespace detail {  // vcar::detail
// Calls f(q) for every background pixel q of m within reach px (Euclidean) of its foreground:
// they lie in the foreground's bounding box grown by reach, where the transform runs.
template <class F>
void for_each_within_reach(const Mask& m, double reach, F&& f) {
  if (!(reach > 0.0)) return;
  const int W = m.width;
  const PixelBox b = foreground_box(m, static_cast<int>(std::min(std::ceil(reach), double(W + m.height))));
  if (b.width() <= 0) return;
  const std::vector<double> d2 =
      squared_distance_in(b, [&](int x, int y) { return m.data[static_cast<std::size_t>(y) * W + x] != 0; });
  for (int y = b.y0; y < b.y1; ++y)
    for (int x = b.x0; x < b.x1; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * W + x;
      if (!m.data[q] && d2[b.at(x, y)] <= reach * reach) f(q);
    }
}
}  // namespace detail

// Eq. R6b: marks unsure (0) in `sure` (W x H, 255 = sure) every background pixel of m whose
// distance to the nearest foreground pixel is at most reach px.
inline void widen_outer_band(const Mask& m, double reach, std::vector<std::uint8_t>& sure) {
  detail::for_each_within_reach(m, reach, [&](std::size_t q) { sure[q] = 0; });
}

// Eq. R8: the mask as wide as its measured undershoot e (px): every background pixel within e
// (Euclidean, pixel centres) of the foreground becomes foreground (255). ABR reads it when the
// fine vote is split (Eq. R7), i.e. when the masks undershoot.
inline void dilate_by_undershoot(Mask& m, double e) {
  // In place: each pixel's test reads only its own value and the distances computed first.
  detail::for_each_within_reach(m, e, [&](std::size_t q) { m.data[q] = 255; });
}

}  // namespace vcar
