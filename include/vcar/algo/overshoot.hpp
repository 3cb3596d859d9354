#pragma once
// Beyond the paper: a mask that overshoots the object is eroded by its measured overshoot
// (docs/robust.md, Eq. R11). Used in the coarse round, on the renders of the whole scene, and
// in the fine round (renders of G_coarse) only after the coarse round eroded some mask.
//
// A segmenter that overshoots (a dilated mask) puts a shell of background around the object in
// every view: the table under it, the neighbour's near side. Those Gaussians project inside
// every mask and the vote keeps them at any threshold; ABR, reading the same masks, finds
// nothing overflowing. The masks cannot show it, but the render can: an object's silhouette is
// an occlusion edge of the render (the object in front of something farther, or of nothing),
// and a mask that overshoots has its contour outside that edge. With A_j, D_j the alpha and
// expected depth of the render and D^_j = D_j / A_j,
//   E_j  = {p : A_j(p) >= 0.5 and a 4-neighbour q has A_j(q) < 0.5
//               or D^_j(q) > (1 + delta) D^_j(p)}                                  (Eq. R11a)
// the near side of every occlusion edge (delta = depth_tolerance). Per contour pixel c of M_j
// (foreground with a background 4-neighbour in the image) the signed distance to the nearest
// such edge pixel, positive when it lies inside the mask,
//   s(c) = d(c, E_j in M_j)        if d(c, E_j in M_j) <= d(c, E_j outside M_j)
//        = -d(c, E_j outside M_j)  otherwise                                       (Eq. R11b)
//   o_j  = median of s(c) over the contour pixels c
// Where the object touches a neighbour at its own depth (a contact: donuts side by side) the
// render has no occlusion edge along the contour, and the nearest edge lies far inside the mask:
// those pixels read as an overshoot the mask does not have. Leaving them out (a reach of r r_M,
// r_M the mask's radius) was measured and removed: nine trained donuts 1 cm apart with exact
// masks 3D F1 0.851 -> 0.938, a held-out GrabCut donut 0.931 -> 0.446 (docs/robust.md, History).
// (Euclidean distances between pixel centres). A mask on the object's true edge gives o_j < 0:
// the render's edge lies outside the true silhouette by the splats' own extent, measured 1-5 px
// at 160 x 120 and 7-10 px at 640 x 480 (median over a round's views); a mask eroded by e px
// reads about e less; a segmenter that follows the render's own edges (the frames are renders)
// reads 0. A mask dilated by d reads about d minus the extent. So a contour at least o_min
// outside the render's edge overshoots, and the mask is eroded:
//   M'_j = {p in M_j : d(p, not M_j) > o_j + m}   where o_j >= o_min, q1_j >= 0    (Eq. R11c)
// (q1_j, q3_j the lower and upper quartiles of s(c): erosion asks three quarters of the contour
// on or outside the edges, R12's growth three quarters less than 1 px outside; snap_direction)
// o_min and m scale with the view: o_min = max(1 px, 0.005 |diag|), m = max(1.5 px, 0.0075
// |diag|), |diag| the image diagonal in px (1 and 1.5 px at 160 x 120, where they were chosen; 4
// and 6 px at 640 x 480; m: part of the splats' extent that the dilated contour also holds, and
// that extent grows with the resolution; the floors: the contour's own grid). In pixels at every
// size (until 2026-12-05) they read a real segmenter's contour, a pixel or two off the render's
// edge at 640 x 480, as an overshoot and cut 1.5 px into the object's fringe (ISNet's donut,
// docs/notes/field-isnet-donut-2026-12-05.md). Measured o_j per view (forward, orbit, sparse
// and hemisphere rigs, 3 seeds, 160 x 120, the coarse round's renders of the scene): clean masks
// median -1 to -5.4, dilated by 2 px 0 to 1, by 4 px 1.4 to 2.8. Per view: Eq. R11a over the
// mask's bounding box grown by 48 px (OcclusionEdges; the whole render's only where that box
// cannot decide a contour pixel's s(c), which then reads the nearest edge pixel on each side by
// rows, RowSeeds), two exact distance transforms over that box to measure, one over the mask's
// bounding box to erode.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
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

// Eq. R11c's constants (see the top of the file): fractions of the image diagonal, floored at
// the pixel grid's own resolution (the contour is measured to within a pixel). They were fields
// (overshoot_min, overshoot_margin) until 2026-12-03, in pixels until 2026-12-05; R11 and R12
// share one switch, VcarParams::snap (docs/robust.md). overshoot_min_px is also R12c's threshold.
inline constexpr double overshoot_min_px = 1.0;          // o_min's floor
inline constexpr double overshoot_min_diagonal = 0.005;  // o_min: this far past the edges overshoots
inline constexpr double overshoot_margin_px = 1.5;       // m's floor
inline constexpr double overshoot_margin_diagonal = 0.0075;  // m: eroded by o_j + m

// Eq. R11c's o_min and m for a W x H view (px).
struct OvershootScale {
  double min = overshoot_min_px, margin = overshoot_margin_px;
  static OvershootScale of(int width, int height) {
    const double diagonal = std::hypot(static_cast<double>(width), static_cast<double>(height));
    return {std::max(overshoot_min_px, overshoot_min_diagonal * diagonal),
            std::max(overshoot_margin_px, overshoot_margin_diagonal * diagonal)};
  }
};

// Eq. R11a at pixel (x, y) of the render (alpha, expected depth sum z alpha T): the near side
// of an occlusion edge with relative depth step delta.
inline bool occlusion_edge_at(const ImageF& alpha, const ImageF& depth, float delta, int x, int y) {
  const int W = alpha.width, H = alpha.height;
  const std::size_t q = static_cast<std::size_t>(y) * W + x;
  if (!(alpha.data[q] >= 0.5f)) return false;
  auto far_side = [&](std::size_t r) {  // a neighbour with no surface is infinitely far
    return !(alpha.data[r] >= 0.5f) || depth.data[r] / alpha.data[r] > depth.data[q] / alpha.data[q] * (1.f + delta);
  };
  return (x > 0 && far_side(q - 1)) || (x + 1 < W && far_side(q + 1)) || (y > 0 && far_side(q - W)) ||
         (y + 1 < H && far_side(q + W));
}

// Eq. R11a over the pixels of box b of the render: e (one byte per pixel of the image) gets 1
// where the pixel is the near side of an occlusion edge, 0 elsewhere in b; pixels outside b are
// left as they are. A pixel reads its 4-neighbours only, so b's values are the whole render's.
inline void occlusion_edges_in(const ImageF& alpha, const ImageF& depth, float delta, const PixelBox& b,
                               std::vector<std::uint8_t>& e) {
  // occlusion_edge_at at every pixel of b, each surface depth D / A (b grown by the neighbours'
  // pixel) divided once.
  const int W = alpha.width, H = alpha.height;
  if (b.empty()) return;
  const PixelBox g = b.grown(1, W, H);
  std::vector<float> s(static_cast<std::size_t>(g.width()) * g.height());
  std::vector<std::uint8_t> has(s.size());
  for (int y = g.y0; y < g.y1; ++y)
    for (int x = g.x0; x < g.x1; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * W + x, k = g.at(x, y);
      has[k] = alpha.data[q] >= 0.5f;
      s[k] = depth.data[q] / alpha.data[q];
    }
  const std::size_t gw = static_cast<std::size_t>(g.width());
  for (int y = b.y0; y < b.y1; ++y)
    for (int x = b.x0; x < b.x1; ++x) {
      const std::size_t k = g.at(x, y);
      std::uint8_t& out = e[static_cast<std::size_t>(y) * W + x];
      if (!has[k]) {
        out = 0;
        continue;
      }
      const float near = s[k] * (1.f + delta);
      auto far_side = [&](std::size_t r) { return !has[r] || s[r] > near; };  // no surface: infinitely far
      out = (x > 0 && far_side(k - 1)) || (x + 1 < W && far_side(k + 1)) || (y > 0 && far_side(k - gw)) ||
            (y + 1 < H && far_side(k + gw));
    }
}

// Eq. R11a over the whole render.
inline std::vector<std::uint8_t> occlusion_edges(const ImageF& alpha, const ImageF& depth, float delta) {
  std::vector<std::uint8_t> e(alpha.data.size(), 0);
  occlusion_edges_in(alpha, depth, delta, PixelBox{0, 0, alpha.width, alpha.height}, e);
  return e;
}

// Eq. R11a on demand: the map of the whole render, exact over the boxes asked for so far
// (cover), 0 elsewhere. R11b reads it near the mask's contour (the whole image only where a box
// cannot decide a contour pixel), R12 within twice its reach of the mask: most views need a box
// around the mask, not the whole render.
class OcclusionEdges {
public:
  OcclusionEdges(const ImageF& alpha, const ImageF& depth, float delta)
      : alpha_(&alpha), depth_(&depth), delta_(delta), e_(alpha.data.size(), 0) {}
  // The map, exact over b and every box covered before.
  const std::vector<std::uint8_t>& cover(const PixelBox& b) {
    if (done_.contains(b)) return e_;
    done_ = done_.united(b);  // its earlier part is recomputed: the same values
    occlusion_edges_in(*alpha_, *depth_, delta_, done_, e_);
    return e_;
  }

private:
  const ImageF* alpha_;
  const ImageF* depth_;
  float delta_;
  std::vector<std::uint8_t> e_;
  PixelBox done_;
};

// Eq. R11b: the quartiles {q1_j, o_j, q3_j} of s(c) over mask m's contour (px; > 0: outside the
// render's occlusion edges `edge`, Eq. R11a), o_j the overshoot. {0, 0, 0} when no contour pixel
// has a value (no contour, no edge). First each contour pixel looks for the nearest edge pixel
// within `reach` px, nearest first (NearestPixels; an edge pixel in the mask wins a tie, as
// below): when the quartiles are certain from the values found (below), they are the result.
// Otherwise the two distance
// transforms run over the mask's bounding box grown by `window` px; a contour pixel whose nearer
// side is not certain from the box (an edge outside it could be nearer) reads the nearest edge
// pixel of the whole image on each side instead (RowSeeds). Either way the result is the whole
// image's transforms', for any reach and window.
// The edges are read through cover(box), which returns the map exact over that box: a box
// around the mask first, the whole render only for the pixels the box cannot decide.
inline constexpr int overshoot_window_px = 48;
namespace detail {
template <class Cover>
std::array<double, 3> overshoot_quartiles(const Mask& m, Cover&& cover, int window, int reach) {
  const int W = m.width, H = m.height;
  const PixelBox fg = foreground_box(m, 0);
  if (fg.empty()) return {0.0, 0.0, 0.0};  // no foreground, no contour
  const PixelBox b = fg.grown(std::max(window, 0), W, H);
  const std::vector<std::uint8_t>& edge = cover(fg.grown(std::max({window, reach, 0}), W, H));
  if (reach > 0) {
    const NearestPixels& near = nearest_pixels(reach);
    std::vector<std::size_t> contour;
    for_each_contour_pixel(m, [&](std::size_t q) { contour.push_back(q); });
    std::vector<double> s;
    std::size_t far = 0;  // contour pixels with no edge pixel within the reach
    for (const std::size_t q : contour) {
      if (4 * far > contour.size()) break;  // more than a quarter: the quartiles cannot be certain
      const int x = static_cast<int>(q % static_cast<std::size_t>(W)), y = static_cast<int>(q / static_cast<std::size_t>(W));
      int nearest = -1;  // d2 of the nearest edge pixel
      bool inside = false;  // one of that distance lies in the mask
      near.visit(x, y, W, H, [&](std::size_t r, int d2) {
        if (nearest >= 0 && d2 > nearest) return false;
        if (edge[r]) nearest = d2, inside = inside || m.data[r] != 0;
        return true;
      });
      if (nearest < 0) ++far;
      else s.push_back(inside ? std::sqrt(double(nearest)) : -std::sqrt(double(nearest)));
    }
    // A pixel that found none has |s(c)| > reach, on either side: with a of them negative, the
    // sorted values are those a, then the found ones, then the rest, and the quartile at i is
    // found[i - a]. It is certain, whatever a in [0, far], when found[i - far .. i] are one value
    // (distances on the pixel grid repeat). Some edge pixel exists when something was found, so
    // every contour pixel has a value.
    std::sort(s.begin(), s.end());
    const std::size_t n = contour.size();
    if (s.size() + far < n) far = n - s.size();  // stopped early: the rest count as far (not certain)
    std::array<double, 3> out{};
    bool certain = !s.empty();
    for (int k = 0; k < 3 && certain; ++k) {
      const std::size_t i = (k == 0 ? n / 4 : k == 1 ? n / 2 : 3 * n / 4);
      certain = i >= far && i < s.size() && s[i - far] == s[i];
      if (certain) out[static_cast<std::size_t>(k)] = s[i];
    }
    if (certain) return out;
    if (n == 0) return {0.0, 0.0, 0.0};  // no contour
  }
  auto seeds = [&](bool inside) {
    return [&, inside](int x, int y) {
      const std::size_t q = static_cast<std::size_t>(y) * W + x;
      return edge[q] && (m.data[q] != 0) == inside;
    };
  };
  const std::vector<double> box_in = squared_distance_in(b, seeds(true));
  const std::vector<double> box_out = squared_distance_in(b, seeds(false));
  std::optional<RowSeeds> all_in, all_out;  // the whole image's, only when a pixel needs them
  auto whole = [&](bool inside, std::size_t q) {
    std::optional<RowSeeds>& d = inside ? all_in : all_out;
    if (!d) cover(PixelBox{0, 0, W, H}), d.emplace(W, H, seeds(inside));
    return d->nearest_squared(static_cast<int>(q % static_cast<std::size_t>(W)), static_cast<int>(q / static_cast<std::size_t>(W)));
  };
  return contour_quartiles(m, [&](std::size_t q) {  // s(c); no edge pixel at all: no value
    const int x = static_cast<int>(q % static_cast<std::size_t>(W)), y = static_cast<int>(q / static_cast<std::size_t>(W));
    // A box distance within o (PixelBox::distance_to_outside) is the whole image's; one beyond
    // it bounds the image's, which is at least o. The nearer side decides s(c): certain when its
    // distance is below o and the other side's is not exact.
    const double o = b.distance_to_outside(x, y, W, H), o2 = o * o;
    double d_in = box_in[b.at(x, y)], d_out = box_out[b.at(x, y)];
    const bool in_exact = d_in <= o2, out_exact = d_out <= o2;
    if (!out_exact && d_in < o2) return std::sqrt(d_in);
    if (!in_exact && d_out < o2) return -std::sqrt(d_out);
    if (!in_exact || !out_exact) {
      d_in = whole(true, q);
      d_out = whole(false, q);
    }
    const double d2 = std::min(d_in, d_out);
    if (!std::isfinite(d2)) return std::numeric_limits<double>::quiet_NaN();
    return d_in <= d_out ? std::sqrt(d_in) : -std::sqrt(d_out);
  });
}
}  // namespace detail

// Eq. R11b from the whole render's edge map.
inline std::array<double, 3> overshoot_quartiles_px(const Mask& m, const std::vector<std::uint8_t>& edge,
                                                    int window = overshoot_window_px, int reach = contour_reach_px) {
  return detail::overshoot_quartiles(m, [&](const PixelBox&) -> const std::vector<std::uint8_t>& { return edge; }, window, reach);
}
// Eq. R11b from the render's edges computed on demand (the same values).
inline std::array<double, 3> overshoot_quartiles_px(const Mask& m, OcclusionEdges& edges,
                                                    int window = overshoot_window_px, int reach = contour_reach_px) {
  return detail::overshoot_quartiles(m, [&](const PixelBox& b) -> const std::vector<std::uint8_t>& { return edges.cover(b); }, window, reach);
}
// Eq. R11b: the overshoot o_j alone.
inline double overshoot_px(const Mask& m, const std::vector<std::uint8_t>& edge) {
  return overshoot_quartiles_px(m, edge)[1];
}
// The same from the render (alpha, expected depth) and the depth step delta.
inline double overshoot_px(const Mask& m, const ImageF& alpha, const ImageF& depth, float delta) {
  return overshoot_px(m, occlusion_edges(alpha, depth, delta));
}

// Eq. R11c and R12's condition: which way the snap moves a mask whose contour reads the
// quartiles q = {q1_j, o_j, q3_j} (Eq. R11b). Inwards (erode) when it overshoots, o_j >= o_min
// (OvershootScale::min of the view; 1 px by default), and three quarters of the contour lie on
// or outside the edges, q1_j >= 0; outwards (grow) when three quarters lie less than 1 px outside
// them, q3_j < 1 px (the grid's unit at any size); otherwise not at all: a contour
// on both sides of the edges (a mask shifted off the object, the SAM-like drift) is no
// overshoot to erode and no gap to fill.
enum class SnapDirection { none, erode, grow };
inline SnapDirection snap_direction(const std::array<double, 3>& q, double o_min = overshoot_min_px) {
  if (q[1] >= o_min && q[0] >= 0.0) return SnapDirection::erode;             // Eq. R11c
  if (q[2] < overshoot_min_px) return SnapDirection::grow;                    // Eq. R12c
  return SnapDirection::none;
}

// Eq. R11c: erodes m (in place) by e px: a foreground pixel stays only when its distance to the
// nearest background pixel of the image is above e (pixels outside the image do not count). The
// distance transform runs over the foreground's bounding box grown by 1 px: the nearest
// background pixel of any foreground pixel lies in it.
inline void erode_by_overshoot(Mask& m, double e) {
  if (!(e > 0.0)) return;
  const PixelBox b = foreground_box(m, 1);
  if (b.width() <= 0) return;
  const int W = m.width;
  const std::vector<double> d2 = squared_distance_in(
      b, [&](int x, int y) { return m.data[static_cast<std::size_t>(y) * W + x] == 0; });
  for (int y = b.y0; y < b.y1; ++y)
    for (int x = b.x0; x < b.x1; ++x) {
      std::uint8_t& v = m.data[static_cast<std::size_t>(y) * W + x];
      if (v && !(d2[b.at(x, y)] > e * e)) v = 0;
    }
}

}  // namespace vcar
