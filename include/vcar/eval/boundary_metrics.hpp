#pragma once
// Boundary metrics of a predicted mask against a ground-truth mask (conventions §6), all with one
// band width d (pixels), by default d = max(1, round(0.02 * image diagonal)):
//
//  - Boundary IoU (Cheng et al. 2021, their reference `mask_to_boundary`): the band of a mask is
//    the mask minus its erosion by a 3x3 kernel applied d times, with the outside of the image
//    counted as background (so the image border is a contour, as in their zero padding); that is
//    the foreground pixels whose Chebyshev distance to a background pixel or to outside is <= d.
//    BIoU = |band(P) n band(G)| / |band(P) u band(G)|; both bands empty -> 1.
//  - Boundary F1 (DAVIS F-measure): the boundary of a mask is mask XOR its 3x3 erosion, with the
//    outside of the image replicating the border (the image border is not a contour, as in
//    DAVIS). A predicted boundary pixel is matched when a GT boundary pixel lies within Euclidean
//    distance d (pixel centres; the same set as dilating with a disc of radius d), and vice versa.
//    precision = matched(P)/|B(P)|, recall = matched(G)/|B(G)|; an empty boundary has precision or
//    recall 1 (DAVIS); F1 = 2PR/(P+R), 0 when P+R = 0. Both empty -> 1; one empty -> 0.
//  - Trimap IoU: the band is every pixel within Euclidean distance d of a pixel of the other GT
//    label (both sides of the GT contour; d = 1 gives one ring inside and one outside). IoU of
//    P and G restricted to it. When the GT has no contour (empty or full), the band is empty and
//    the plain IoU over the image is returned (so GT empty, prediction not -> 0).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "vcar/core/image.hpp"
#include "vcar/core/distance_transform.hpp"
#include "vcar/eval/mask_metrics.hpp"

namespace vcar::eval {

// d = max(1, round(ratio * sqrt(W^2 + H^2))), ratio 0.02 (conventions §6).
inline int band_width(int width, int height, double ratio = 0.02) {
  const double diag = std::sqrt(double(width) * width + double(height) * height);
  return std::max(1, static_cast<int>(std::lround(ratio * diag)));
}

// Binary copy (0/1) of a mask.
inline std::vector<std::uint8_t> binary(const Mask& m) {
  std::vector<std::uint8_t> b(m.data.size());
  for (std::size_t k = 0; k < b.size(); ++k) b[k] = m.data[k] != 0;
  return b;
}

// Erosion by a 3x3 kernel applied `times` times. outside_is_background: the image is padded with
// background (Cheng et al.); otherwise the border replicates (DAVIS).
inline std::vector<std::uint8_t> erode3x3(std::vector<std::uint8_t> b, int width, int height, int times,
                                          bool outside_is_background) {
  std::vector<std::uint8_t> t(b.size());
  const std::size_t W = static_cast<std::size_t>(width);
  const std::uint8_t pad_rule = outside_is_background ? 0 : 1;
  for (int it = 0; it < times; ++it) {
    // 3x3 min is separable: a row pass then a column pass.
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const std::size_t k = y * W + x;
        std::uint8_t v = b[k];
        v &= x > 0 ? b[k - 1] : (pad_rule ? b[k] : 0);
        v &= x + 1 < width ? b[k + 1] : (pad_rule ? b[k] : 0);
        t[k] = v;
      }
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const std::size_t k = y * W + x;
        std::uint8_t v = t[k];
        v &= y > 0 ? t[k - W] : (pad_rule ? t[k] : 0);
        v &= y + 1 < height ? t[k + W] : (pad_rule ? t[k] : 0);
        b[k] = v;
      }
  }
  return b;
}

// Cheng et al. band: mask minus its d-fold 3x3 erosion (outside = background).
inline std::vector<std::uint8_t> boundary_band(const Mask& m, int d) {
  std::vector<std::uint8_t> b = binary(m);
  const std::vector<std::uint8_t> e = erode3x3(b, m.width, m.height, d, true);
  for (std::size_t k = 0; k < b.size(); ++k) b[k] = b[k] && !e[k];
  return b;
}

inline double boundary_iou(const Mask& pred, const Mask& gt, int d, const std::string& where = "mask") {
  check_same_size(pred, gt, where);
  const std::vector<std::uint8_t> bp = boundary_band(pred, d), bg = boundary_band(gt, d);
  std::size_t inter = 0, uni = 0;
  for (std::size_t k = 0; k < bp.size(); ++k) { inter += bp[k] && bg[k]; uni += bp[k] || bg[k]; }
  return uni == 0 ? 1.0 : double(inter) / double(uni);
}
inline double boundary_iou(const Mask& pred, const Mask& gt) {
  return boundary_iou(pred, gt, band_width(gt.width, gt.height));
}

// DAVIS boundary: mask XOR its 3x3 erosion (border replicated).
inline std::vector<std::uint8_t> boundary_map(const Mask& m) {
  std::vector<std::uint8_t> b = binary(m);
  const std::vector<std::uint8_t> e = erode3x3(b, m.width, m.height, 1, false);
  for (std::size_t k = 0; k < b.size(); ++k) b[k] = b[k] ^ e[k];
  return b;
}

struct BoundaryF {
  double precision = 1, recall = 1, f1 = 1;
};

inline BoundaryF boundary_f1(const Mask& pred, const Mask& gt, int d, const std::string& where = "mask") {
  check_same_size(pred, gt, where);
  const std::vector<std::uint8_t> bp = boundary_map(pred), bg = boundary_map(gt);
  const std::vector<double> to_g = squared_distance_to(bg, gt.width, gt.height);
  const std::vector<double> to_p = squared_distance_to(bp, gt.width, gt.height);
  const double d2 = double(d) * d;
  std::size_t np = 0, ng = 0, mp = 0, mg = 0;
  for (std::size_t k = 0; k < bp.size(); ++k) {
    if (bp[k]) { ++np; mp += to_g[k] <= d2; }
    if (bg[k]) { ++ng; mg += to_p[k] <= d2; }
  }
  BoundaryF r;
  r.precision = np == 0 ? 1.0 : double(mp) / double(np);
  r.recall = ng == 0 ? 1.0 : double(mg) / double(ng);
  if (np == 0 && ng == 0) return r;  // both without boundary: a perfect match
  if (np == 0 || ng == 0) { r.f1 = 0.0; return r; }
  r.f1 = r.precision + r.recall > 0 ? 2 * r.precision * r.recall / (r.precision + r.recall) : 0.0;
  return r;
}
inline BoundaryF boundary_f1(const Mask& pred, const Mask& gt) {
  return boundary_f1(pred, gt, band_width(gt.width, gt.height));
}

// Pixels within Euclidean distance d of a pixel of the other GT label (both sides of the contour).
inline std::vector<std::uint8_t> trimap_band(const Mask& gt, int d) {
  const std::vector<std::uint8_t> fg = binary(gt);
  std::vector<std::uint8_t> bgm(fg.size());
  for (std::size_t k = 0; k < fg.size(); ++k) bgm[k] = !fg[k];
  const std::vector<double> to_fg = squared_distance_to(fg, gt.width, gt.height);
  const std::vector<double> to_bg = squared_distance_to(bgm, gt.width, gt.height);
  const double d2 = double(d) * d;
  std::vector<std::uint8_t> band(fg.size());
  for (std::size_t k = 0; k < fg.size(); ++k) band[k] = (fg[k] ? to_bg[k] : to_fg[k]) <= d2;
  return band;
}

inline double trimap_iou(const Mask& pred, const Mask& gt, int d, const std::string& where = "mask") {
  check_same_size(pred, gt, where);
  const std::vector<std::uint8_t> band = trimap_band(gt, d);
  std::size_t inter = 0, uni = 0, in_band = 0;
  for (std::size_t k = 0; k < band.size(); ++k) {
    if (!band[k]) continue;
    ++in_band;
    const bool p = pred.data[k] != 0, g = gt.data[k] != 0;
    inter += p && g; uni += p || g;
  }
  if (in_band == 0) return mask_iou(pred, gt, where);  // GT without a contour
  return uni == 0 ? 1.0 : double(inter) / double(uni);
}
inline double trimap_iou(const Mask& pred, const Mask& gt) {
  return trimap_iou(pred, gt, band_width(gt.width, gt.height));
}

}  // namespace vcar::eval
