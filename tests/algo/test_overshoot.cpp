#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "vcar/algo/overshoot.hpp"

#include "square_mask.hpp"

using vcar::ImageF;
using vcar::Mask;

namespace {
// A 20 x 20 render, alpha 1 everywhere: the square [5, 15)^2 at depth 1 in front of a wall at
// depth `wall` (the depth image holds sum z alpha T = z here).
struct Render {
  ImageF alpha, depth;
};
Render square_before_wall(float wall = 3.f) {
  Render r{ImageF(20, 20, 1), ImageF(20, 20, 1)};
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * 20 + x;
      r.alpha.data[q] = 1.f;
      r.depth.data[q] = x >= 5 && x < 15 && y >= 5 && y < 15 ? 1.f : wall;
    }
  return r;
}
std::size_t count(const std::vector<std::uint8_t>& v) {
  std::size_t n = 0;
  for (auto b : v) n += b != 0;
  return n;
}
}  // namespace

TEST_CASE("Eq. R11a by hand: the near side of a depth step or of an empty pixel") {
  const Render r = square_before_wall();
  const std::vector<std::uint8_t> e = vcar::occlusion_edges(r.alpha, r.depth, 0.05f);
  auto at = [&](int x, int y) { return e[static_cast<std::size_t>(y) * 20 + x]; };
  CHECK(count(e) == 36);  // the square's border ring: 10 x 10 - 8 x 8
  CHECK(at(5, 5) == 1);
  CHECK(at(14, 9) == 1);
  CHECK(at(6, 6) == 0);   // inside: every neighbour at the same depth
  CHECK(at(4, 9) == 0);   // the wall next to the square: its neighbour is nearer, not farther
  // A step under the tolerance is no edge: 3 <= 1 * (1 + 2.5).
  CHECK(count(vcar::occlusion_edges(r.alpha, r.depth, 2.5f)) == 0);
  // A pixel with no surface (alpha < 0.5) is infinitely far: its neighbours with a surface are
  // edges; it is none itself.
  Render hole = square_before_wall();
  hole.alpha.data[2 * 20 + 2] = 0.2f;
  const std::vector<std::uint8_t> h = vcar::occlusion_edges(hole.alpha, hole.depth, 0.05f);
  CHECK(count(h) == 36 + 4);
  CHECK(h[2 * 20 + 2] == 0);
  CHECK(h[2 * 20 + 3] == 1);
  CHECK(h[1 * 20 + 2] == 1);
}

TEST_CASE("Eq. R11b by hand: a mask on the edge reads 0, a dilated one its dilation, an eroded one minus") {
  const Render r = square_before_wall();
  // The square itself: every contour pixel is an edge pixel inside the mask.
  CHECK(vcar::overshoot_px(square_mask(20, 20, 5, 5, 15, 15), r.alpha, r.depth, 0.05f) == 0.0);
  // Dilated by 2 (the square [3, 17)^2): of each side's 14 contour pixels, 10 are 2 px from the
  // square's border, 2 are sqrt 5 and 2 are sqrt 8 (the corners) away: the median is 2.
  CHECK(vcar::overshoot_px(square_mask(20, 20, 3, 3, 17, 17), r.alpha, r.depth, 0.05f) == 2.0);
  // Eroded by 2 (the square [7, 13)^2): no edge inside the mask; the border lies 2 px outside
  // every contour pixel but the corners (sqrt 8): -2.
  CHECK(vcar::overshoot_px(square_mask(20, 20, 7, 7, 13, 13), r.alpha, r.depth, 0.05f) == -2.0);
  // Nothing to measure: no mask, or a render without an occlusion edge.
  CHECK(vcar::overshoot_px(Mask(20, 20, 1), r.alpha, r.depth, 0.05f) == 0.0);
  const Render flat = square_before_wall(1.f);
  CHECK(vcar::overshoot_px(square_mask(20, 20, 3, 3, 17, 17), flat.alpha, flat.depth, 0.05f) == 0.0);
}

TEST_CASE("Eq. R11b is a median: a nearer neighbour along one side does not move it") {
  // A nearer object [15, 19) x [5, 15) (depth 0.5) touches the square's right side: there the
  // square is the far side and no edge; the neighbour's own border is. The dilated mask's right
  // contour reads 0-1 px (12 pixels), the three other sides still 2 (34) or more (6): median 2.
  Render r = square_before_wall();
  for (int y = 5; y < 15; ++y)
    for (int x = 15; x < 19; ++x) r.depth.data[static_cast<std::size_t>(y) * 20 + x] = 0.5f;
  CHECK(vcar::overshoot_px(square_mask(20, 20, 3, 3, 17, 17), r.alpha, r.depth, 0.05f) == 2.0);
}

TEST_CASE("Eq. R11b at a contact: an exact mask between same-depth neighbours reads an overshoot") {
  // A band [0, 20) x [2, 18) at depth 1 before a wall: the target, the rectangle [6, 14) x [2, 18)
  // of it, touches same-depth neighbours left and right, where the render has no edge. Its exact
  // mask: the top and bottom rows (8 + 8 px) lie on the band's edges (s = 0); each side column
  // (y = 3..16, 14 px) reads its distance to the nearest corner edge pixel in the mask,
  // min(y - 2, 17 - y) = 1..7: 16 zeros and 4 each of 1..7, the median (index 22 of 44) is 2, an
  // overshoot the mask does not have (the limit docs/robust.md states for R11 at contacts).
  Render r{ImageF(20, 20, 1), ImageF(20, 20, 1)};
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * 20 + x;
      r.alpha.data[q] = 1.f;
      r.depth.data[q] = y >= 2 && y < 18 ? 1.f : 3.f;
    }
  const std::vector<std::uint8_t> e = vcar::occlusion_edges(r.alpha, r.depth, 0.05f);
  CHECK(vcar::overshoot_px(square_mask(20, 20, 6, 2, 14, 18), e) == 2.0);
  // A mask that stops short (4 px inside the band's edges, every nearest edge outside it) reads
  // its undershoot.
  CHECK(vcar::overshoot_px(square_mask(20, 20, 6, 6, 14, 14), e) == -4.0);
}

TEST_CASE("Eq. R11c by hand: erosion keeps the pixels farther than e from the background") {
  Mask m = square_mask(20, 20, 3, 3, 17, 17);
  vcar::erode_by_overshoot(m, 2.0);  // (4, y) is 2 px from (2, y): removed; (5, y) 3 px: kept
  CHECK(m.data == square_mask(20, 20, 5, 5, 15, 15).data);
  Mask half = square_mask(20, 20, 3, 3, 17, 17);
  vcar::erode_by_overshoot(half, 1.5);  // the ring at distance 1 goes, (4, y) at 2 stays
  CHECK(half.data == square_mask(20, 20, 4, 4, 16, 16).data);
  // Brute force against the definition on an irregular mask.
  Mask blob(13, 11, 1);
  for (int y = 0; y < 11; ++y)
    for (int x = 0; x < 13; ++x) blob.data[static_cast<std::size_t>(y) * 13 + x] = (x * 7 + y * 3) % 11 < 8 ? 255 : 0;
  Mask eroded = blob;
  const double e = 1.2;
  vcar::erode_by_overshoot(eroded, e);
  for (int y = 0; y < 11; ++y)
    for (int x = 0; x < 13; ++x) {
      double best = INFINITY;
      for (int v = 0; v < 11; ++v)
        for (int u = 0; u < 13; ++u)
          if (!blob.data[static_cast<std::size_t>(v) * 13 + u]) best = std::min(best, std::hypot(u - x, v - y));
      const bool keep = blob.data[static_cast<std::size_t>(y) * 13 + x] && best > e;
      CHECK((eroded.data[static_cast<std::size_t>(y) * 13 + x] != 0) == keep);
    }
  // The image border is not background: a full mask stays full; e <= 0 changes nothing.
  Mask full = square_mask(6, 6, 0, 0, 6, 6);
  vcar::erode_by_overshoot(full, 3.0);
  CHECK(full.data == square_mask(6, 6, 0, 0, 6, 6).data);
  Mask same = square_mask(20, 20, 3, 3, 17, 17);
  vcar::erode_by_overshoot(same, 0.0);
  CHECK(same.data == square_mask(20, 20, 3, 3, 17, 17).data);
}

TEST_CASE("Eq. R11c and R12's condition by hand: the snap's direction from the contour's quartiles") {
  using vcar::SnapDirection;
  // {q1, o, q3}: a dilated mask (every contour pixel 2 px out) erodes; one a pixel out along a
  // quarter of its contour and on the edge elsewhere does not move; an eroded one grows.
  CHECK(vcar::snap_direction({2.0, 2.0, 2.236}) == SnapDirection::erode);
  CHECK(vcar::snap_direction({0.0, 1.0, 3.0}) == SnapDirection::erode);   // q1 = 0: on or outside
  CHECK(vcar::snap_direction({0.0, 0.0, 1.0}) == SnapDirection::none);    // o < o_min, q3 = o_min
  CHECK(vcar::snap_direction({0.0, 0.0, 0.0}) == SnapDirection::grow);    // exact: grows by m_g
  CHECK(vcar::snap_direction({-2.0, -2.0, -1.414}) == SnapDirection::grow);
  // Both sides of the edges: o >= o_min but a quarter lies 2 px inside (a shifted mask): none.
  CHECK(vcar::snap_direction({-2.0, 1.0, 2.828}) == SnapDirection::none);
  CHECK(vcar::snap_direction({-0.5, 0.5, 2.0}) == SnapDirection::none);
}

TEST_CASE("Eq. R11c's constants by hand: o_min and m scale with the image diagonal, floored at 1 and 1.5 px") {
  // 160 x 120: diagonal 200 px, 0.005 and 0.0075 of it are the floors, 1 and 1.5 px.
  const vcar::OvershootScale s160 = vcar::OvershootScale::of(160, 120);
  CHECK(s160.min == Approx(1.0));
  CHECK(s160.margin == Approx(1.5));
  // 640 x 480: diagonal 800 px: 4 and 6 px.
  const vcar::OvershootScale s640 = vcar::OvershootScale::of(640, 480);
  CHECK(s640.min == Approx(4.0));
  CHECK(s640.margin == Approx(6.0));
  // 64 x 48 (diagonal 80): the floors.
  const vcar::OvershootScale s64 = vcar::OvershootScale::of(64, 48);
  CHECK(s64.min == 1.0);
  CHECK(s64.margin == 1.5);
  // A contour 2 px past the edges overshoots at 160 x 120, not at 640 x 480, where it is a
  // segmenter's contour on the render's edge to within its resolution; R12's 1 px is the same.
  using vcar::SnapDirection;
  CHECK(vcar::snap_direction({2.0, 2.0, 2.5}, s160.min) == SnapDirection::erode);
  CHECK(vcar::snap_direction({2.0, 2.0, 2.5}, s640.min) == SnapDirection::none);
  CHECK(vcar::snap_direction({4.0, 5.0, 6.0}, s640.min) == SnapDirection::erode);
  CHECK(vcar::snap_direction({-1.0, 0.0, 0.5}, s640.min) == SnapDirection::grow);
}

TEST_CASE("Eq. R11b's quartiles against brute force: a dilated disc erodes, an eroded one grows, a shifted one neither") {
  // A disc of radius 7 at (11, 11), depth 1, before a wall at depth 3, in a 24 x 24 render.
  const int N = 24;
  auto disc = [&](int cx, int cy, int r) {
    Mask m(N, N, 1);
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x)
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r) m.data[static_cast<std::size_t>(y) * N + x] = 255;
    return m;
  };
  const Mask object = disc(11, 11, 7);
  Render r{ImageF(N, N, 1), ImageF(N, N, 1)};
  for (std::size_t q = 0; q < object.data.size(); ++q) {
    r.alpha.data[q] = 1.f;
    r.depth.data[q] = object.data[q] ? 1.f : 3.f;
  }
  const std::vector<std::uint8_t> e = vcar::occlusion_edges(r.alpha, r.depth, 0.05f);
  // s(c) by its definition (Eq. R11b), every pair of pixels compared; quartiles as documented.
  auto brute = [&](const Mask& m) {
    std::vector<double> s;
    auto at = [&](int x, int y) { return m.data[static_cast<std::size_t>(y) * N + x] != 0; };
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x) {
        if (!at(x, y)) continue;
        const bool contour = (x > 0 && !at(x - 1, y)) || (x + 1 < N && !at(x + 1, y)) || (y > 0 && !at(x, y - 1)) ||
                             (y + 1 < N && !at(x, y + 1));
        if (!contour) continue;
        double d_in = INFINITY, d_out = INFINITY;
        for (int v = 0; v < N; ++v)
          for (int u = 0; u < N; ++u) {
            if (!e[static_cast<std::size_t>(v) * N + u]) continue;
            double& d = at(u, v) ? d_in : d_out;
            d = std::min(d, std::hypot(u - x, v - y));
          }
        s.push_back(d_in <= d_out ? d_in : -d_out);
      }
    std::sort(s.begin(), s.end());
    return std::array<double, 3>{s[s.size() / 4], s[s.size() / 2], s[3 * s.size() / 4]};
  };
  struct Case {
    Mask m;
    std::array<double, 3> want;  // by brute force, written out
    vcar::SnapDirection dir;
  };
  const std::vector<Case> cases = {
      {object, {0.0, 0.0, 0.0}, vcar::SnapDirection::grow},                     // exact: by m_g only
      {disc(11, 11, 9), {2.0, 2.0, std::sqrt(5.0)}, vcar::SnapDirection::erode},  // dilated by 2
      {disc(11, 11, 5), {-2.0, -2.0, -std::sqrt(2.0)}, vcar::SnapDirection::grow},  // eroded by 2
      {disc(14, 13, 7), {-2.0, 1.0, std::sqrt(8.0)}, vcar::SnapDirection::none},  // shifted by (3, 2)
  };
  for (const Case& c : cases) {
    const std::array<double, 3> got = vcar::overshoot_quartiles_px(c.m, e), want = brute(c.m);
    for (int k = 0; k < 3; ++k) {
      CHECK(got[k] == Approx(want[k]));
      CHECK(got[k] == Approx(c.want[k]));
    }
    CHECK(vcar::overshoot_px(c.m, e) == got[1]);
    CHECK(vcar::snap_direction(got) == c.dir);
    // The transforms over a window around the mask read the whole image's wherever an edge
    // outside the window could be nearer: the same quartiles for any window.
    for (int window : {0, 1, 2, 3, 5})
      for (int k = 0; k < 3; ++k) CHECK(vcar::overshoot_quartiles_px(c.m, e, window, 0)[k] == got[k]);
    // So does the nearest-first search from each contour pixel, whatever its reach (one too short
    // for some pixel falls back to the transforms).
    for (int reach : {1, 2, 3, 5, 16})
      for (int k = 0; k < 3; ++k) CHECK(vcar::overshoot_quartiles_px(c.m, e, 2, reach)[k] == got[k]);
    // And the edges computed on demand, a box around the mask first (OcclusionEdges).
    for (int window : {0, 2, 48})
      for (int reach : {0, 1, 16}) {
        vcar::OcclusionEdges lazy(r.alpha, r.depth, 0.05f);
        for (int k = 0; k < 3; ++k) CHECK(vcar::overshoot_quartiles_px(c.m, lazy, window, reach)[k] == got[k]);
      }
  }
}

TEST_CASE("Eq. R11a over the render equals its per-pixel rule on random renders") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  for (auto [W, H] : {std::pair{31, 17}, std::pair{1, 9}, std::pair{12, 1}}) {
    ImageF alpha(W, H, 1), depth(W, H, 1);
    for (std::size_t q = 0; q < alpha.data.size(); ++q) {
      alpha.data[q] = U(rng) < 0.2f ? 0.3f : 0.5f + 0.5f * U(rng);
      depth.data[q] = alpha.data[q] * (U(rng) < 0.5f ? 1.f + 0.04f * U(rng) : 2.f);  // steps and near-ties
    }
    const std::vector<std::uint8_t> e = vcar::occlusion_edges(alpha, depth, 0.05f);
    std::size_t edges = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        CAPTURE(W, H, x, y);
        REQUIRE((e[static_cast<std::size_t>(y) * W + x] != 0) == vcar::occlusion_edge_at(alpha, depth, 0.05f, x, y));
        edges += vcar::occlusion_edge_at(alpha, depth, 0.05f, x, y);
      }
    CHECK(edges > 0);
    // Over a box: the whole map's values there, every other pixel left as it was; on demand
    // (OcclusionEdges): the whole map's over every box covered so far.
    std::uniform_int_distribution<int> X(0, W), Y(0, H);
    vcar::OcclusionEdges lazy(alpha, depth, 0.05f);
    std::vector<int> done(e.size(), 0);
    for (int trial = 0; trial < 20; ++trial) {
      int x0 = X(rng), x1 = X(rng), y0 = Y(rng), y1 = Y(rng);
      if (x0 > x1) std::swap(x0, x1);
      if (y0 > y1) std::swap(y0, y1);
      const vcar::PixelBox b{x0, y0, x1, y1};
      std::vector<std::uint8_t> part(e.size(), 7);
      vcar::occlusion_edges_in(alpha, depth, 0.05f, b, part);
      const std::vector<std::uint8_t>& on_demand = lazy.cover(b);
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) done[static_cast<std::size_t>(y) * W + x] = 1;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          const std::size_t q = static_cast<std::size_t>(y) * W + x;
          CAPTURE(W, H, x0, y0, x1, y1, x, y);
          const bool in_box = x >= x0 && x < x1 && y >= y0 && y < y1;
          REQUIRE(part[q] == (in_box ? e[q] : 7));
          if (done[q]) REQUIRE(on_demand[q] == e[q]);
        }
    }
    CHECK(lazy.cover(vcar::PixelBox{0, 0, W, H}) == e);
  }
}
