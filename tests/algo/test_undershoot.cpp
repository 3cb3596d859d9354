#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "vcar/algo/undershoot.hpp"

#include "square_mask.hpp"

using vcar::ImageF;
using vcar::Mask;

namespace {
ImageF square_alpha(int n, int x0, int x1) {
  ImageF a(n, n, 1);
  for (int y = x0; y < x1; ++y)
    for (int x = x0; x < x1; ++x) a.data[static_cast<std::size_t>(y) * n + x] = 0.9f;
  return a;
}
}  // namespace

TEST_CASE("Eq. R6a by hand: a mask 3 px inside the render undershoots by 3, the render's own edge by 0") {
  const ImageF alpha = square_alpha(20, 5, 15);  // render [5, 15)^2
  // Mask [8, 12)^2: every contour pixel is 4 px (centre to centre) from the render's background
  // (x = 4 or 15, y likewise): e = 4 - 1 = 3.
  CHECK(vcar::undershoot_px(square_mask(20, 20, 8, 8, 12, 12), alpha) == 3.0);
  // The mask is the render: contour pixels touch the background at distance 1: e = 0.
  CHECK(vcar::undershoot_px(square_mask(20, 20, 5, 5, 15, 15), alpha) == 0.0);
  // A dilated mask: its contour lies in the render's background: e = 0.
  CHECK(vcar::undershoot_px(square_mask(20, 20, 2, 2, 18, 18), alpha) == 0.0);
  // No mask, or a render without background: nothing to measure.
  CHECK(vcar::undershoot_px(Mask(20, 20, 1), alpha) == 0.0);
  CHECK(vcar::undershoot_px(square_mask(20, 20, 8, 8, 12, 12), square_alpha(20, 0, 20)) == 0.0);
  // The image border is not a contour: a full mask has none.
  CHECK(vcar::undershoot_px(square_mask(20, 20, 0, 0, 20, 20), alpha) == 0.0);
  // Over a window around the mask too small to hold the render's background (0-3 px: the
  // background lies 4 px out), the whole image's transform decides: the same values. So does a
  // nearest-first search too short to reach it (reach 0-3), which falls back to the transform.
  for (int window : {0, 1, 2, 3, 4})
    for (int reach : {0, 1, 3, 4, 16}) {
      CAPTURE(window, reach);
      CHECK(vcar::undershoot_px(square_mask(20, 20, 8, 8, 12, 12), alpha, window, reach) == 3.0);
      CHECK(vcar::undershoot_px(square_mask(20, 20, 5, 5, 15, 15), alpha, window, reach) == 0.0);
      CHECK(vcar::undershoot_px(square_mask(20, 20, 8, 8, 12, 12), square_alpha(20, 0, 20), window, reach) == 0.0);
    }
}

TEST_CASE("Eq. R6a against brute force on random renders and masks, for any reach of the nearest-first search") {
  std::mt19937 rng(29);
  std::uniform_int_distribution<int> c(2, 27), r(2, 9);
  for (int t = 0; t < 40; ++t) {
    // A render of two discs and a mask of one disc near them.
    ImageF alpha(30, 30, 1);
    Mask m(30, 30, 1);
    const int ax = c(rng), ay = c(rng), ar = r(rng), bx = c(rng), by = c(rng), br = r(rng), mx = c(rng), my = c(rng), mr = r(rng);
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 30; ++x) {
        const std::size_t q = static_cast<std::size_t>(y) * 30 + x;
        const bool in = (x - ax) * (x - ax) + (y - ay) * (y - ay) <= ar * ar || (x - bx) * (x - bx) + (y - by) * (y - by) <= br * br;
        alpha.data[q] = in ? 0.8f : 0.1f;
        m.data[q] = (x - mx) * (x - mx) + (y - my) * (y - my) <= mr * mr ? 255 : 0;
      }
    // Brute force: each contour pixel's distance to the nearest background pixel; the upper median.
    std::vector<double> e;
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 30; ++x) {
        auto fg = [&](int u, int v) { return m.data[static_cast<std::size_t>(v) * 30 + u] != 0; };
        if (!fg(x, y) || !((x > 0 && !fg(x - 1, y)) || (x < 29 && !fg(x + 1, y)) || (y > 0 && !fg(x, y - 1)) || (y < 29 && !fg(x, y + 1)))) continue;
        double d = INFINITY;
        for (int v = 0; v < 30; ++v)
          for (int u = 0; u < 30; ++u)
            if (!(alpha.data[static_cast<std::size_t>(v) * 30 + u] >= 0.5f)) d = std::min(d, std::hypot(u - x, v - y));
        e.push_back(std::max(0.0, d - 1.0));
      }
    std::sort(e.begin(), e.end());
    const double want = e.empty() ? 0.0 : e[e.size() / 2];
    for (int reach : {0, 1, 2, 4, 16}) {
      CAPTURE(t, reach);
      CHECK(vcar::undershoot_px(m, alpha, vcar::undershoot_window_px, reach) == Approx(want).margin(1e-12));
      CHECK(vcar::undershoot_px(m, alpha, 1, reach) == Approx(want).margin(1e-12));
    }
  }
}

TEST_CASE("Eq. R6a is a median: a foreground blob of G_coarse that the mask leaves out does not move it") {
  // Render: [5, 15)^2 plus a blob [15, 19) x [5, 9) attached to the right (a background piece
  // in G_coarse). The mask is exactly the square: only its right-edge contour pixels next to
  // the blob see a larger distance; most contour pixels are on the render's edge.
  ImageF alpha = square_alpha(20, 5, 15);
  for (int y = 5; y < 9; ++y)
    for (int x = 15; x < 19; ++x) alpha.data[static_cast<std::size_t>(y) * 20 + x] = 1.f;
  CHECK(vcar::undershoot_px(square_mask(20, 20, 5, 5, 15, 15), alpha) == 0.0);
}

TEST_CASE("Eq. R6b by hand: background pixels within the reach (Euclidean) of the foreground become unsure") {
  Mask m(9, 9, 1);
  m.data[4 * 9 + 4] = 255;  // one pixel at (4, 4)
  std::vector<std::uint8_t> sure(81, 255);
  vcar::widen_outer_band(m, 2.0, sure);
  auto at = [&](int x, int y) { return sure[static_cast<std::size_t>(y) * 9 + x]; };
  CHECK(at(4, 4) == 255);  // foreground pixels are not touched
  CHECK(at(6, 4) == 0);    // distance 2
  CHECK(at(5, 5) == 0);    // sqrt 2
  CHECK(at(6, 5) == 255);  // sqrt 5 > 2
  CHECK(at(0, 0) == 255);
  int unsure = 0;
  for (auto v : sure) unsure += v == 0;
  CHECK(unsure == 12);  // (dx, dy) with 0 < dx^2 + dy^2 <= 4: 4 + 4 + 4
  std::vector<std::uint8_t> untouched(81, 255);
  vcar::widen_outer_band(m, 0.0, untouched);
  CHECK(untouched == std::vector<std::uint8_t>(81, 255));
}

TEST_CASE("Eq. R8 by hand: the mask grows by every background pixel within e (Euclidean) of its foreground") {
  Mask m(9, 9, 1);
  m.data[4 * 9 + 4] = 255;  // one pixel at (4, 4)
  auto count = [](const Mask& k) {
    int n = 0;
    for (auto v : k.data) n += v != 0;
    return n;
  };
  Mask a = m;
  vcar::dilate_by_undershoot(a, 1.0);
  CHECK(count(a) == 5);  // the pixel and its 4-neighbours
  Mask b = m;
  vcar::dilate_by_undershoot(b, 1.5);
  CHECK(count(b) == 9);  // the 3 x 3 block (sqrt 2 <= 1.5)
  Mask c = m;
  vcar::dilate_by_undershoot(c, 2.0);
  CHECK(count(c) == 13);  // 1 + 12, the pixels Eq. R6b marks unsure at the same reach
  CHECK(c.data[4 * 9 + 6] == 255);
  CHECK(c.data[5 * 9 + 6] == 0);  // sqrt 5 > 2
  Mask d = m;
  vcar::dilate_by_undershoot(d, 0.0);  // no undershoot: unchanged
  CHECK(d.data == m.data);
  Mask e = square_mask(20, 20, 5, 5, 15, 15);
  vcar::dilate_by_undershoot(e, 3.0);  // a square grows by 3 px on each side, corners rounded
  CHECK(e(2, 10) == 255);
  CHECK(e(1, 10) == 0);
  CHECK(e(3, 3) == 255);  // (2, 2) from the corner: sqrt 8 <= 3
  CHECK(e(2, 2) == 0);    // sqrt 18 > 3
}

TEST_CASE("Eq. R14's gate by hand: the round's masks undershoot when their median undershoot is positive") {
  using vcar::masks_undershoot;
  // Odd count: the middle value decides. {0, 0, 2}: median 0.
  CHECK_FALSE(masks_undershoot({0.0, 2.0, 0.0}));
  // {0, 0.4, 3}: median 0.4 > 0.
  CHECK(masks_undershoot({3.0, 0.0, 0.4}));
  // Even count: the mean of the two middle values; {0, 0, 1, 5}: (0 + 1) / 2 = 0.5 > 0.
  CHECK(masks_undershoot({5.0, 0.0, 1.0, 0.0}));
  // {0, 0, 0, 5}: (0 + 0) / 2 = 0.
  CHECK_FALSE(masks_undershoot({0.0, 5.0, 0.0, 0.0}));
  // No masked frame.
  CHECK_FALSE(masks_undershoot({}));
}
