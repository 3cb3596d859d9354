#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "vcar/algo/occlusion_growth.hpp"
#include "vcar/algo/overshoot.hpp"

#include "square_mask.hpp"

using vcar::ImageF;
using vcar::Mask;

namespace {
// A W x H render, alpha 1 where `covered`, depth z(x, y) there (sum z alpha T = z).
template <class Covered, class Depth>
std::pair<ImageF, ImageF> render(int W, int H, Covered covered, Depth z) {
  ImageF alpha(W, H, 1), depth(W, H, 1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * W + x;
      alpha.data[q] = covered(x, y) ? 1.f : 0.f;
      depth.data[q] = covered(x, y) ? z(x, y) : 0.f;
    }
  return {alpha, depth};
}
// The square [5, 15)^2 at depth 1 in front of a wall at depth 3, 20 x 20 (as test_overshoot).
std::pair<ImageF, ImageF> square_in_front() {
  return render(20, 20, [](int, int) { return true; },
                [](int x, int y) { return x >= 5 && x < 15 && y >= 5 && y < 15 ? 1.f : 3.f; });
}
std::size_t grow(Mask& m, const std::pair<ImageF, ImageF>& r, int reach, float delta = 0.05f) {
  return vcar::grow_to_occlusion_edges(m, vcar::occlusion_edges(r.first, r.second, delta), r.first, r.second, delta,
                                       reach);
}
}  // namespace

TEST_CASE("Eq. R12c by hand: the reach is the smallest of the measured gap, the cap and the mask's radius") {
  // o_j = -2.3, margin 1: 3.3; cap 0.1 x 200 (160 x 120) = 20; radius sqrt(100 / pi) = 5.64: 3.3 -> 4 steps.
  CHECK(vcar::growth_reach(-2.3, 100, 160, 120, 0.1, 1.0) == 4);
  // o_j = -10: 11, but the mask's radius 5.64 -> 6 steps.
  CHECK(vcar::growth_reach(-10.0, 100, 160, 120, 0.1, 1.0) == 6);
  // The cap: 0.02 x 200 = 4.
  CHECK(vcar::growth_reach(-10.0, 10000, 160, 120, 0.02, 1.0) == 4);
  // A contour 0.5 px inside the edge: 1 step; one 1.5 px outside (R11's): none; cap 0: none.
  CHECK(vcar::growth_reach(0.5, 100, 160, 120, 0.1, 1.0) == 1);
  CHECK(vcar::growth_reach(1.5, 100, 160, 120, 0.1, 1.0) == 0);
  CHECK(vcar::growth_reach(-5.0, 100, 160, 120, 0.0, 1.0) == 0);
  CHECK(vcar::growth_reach(-5.0, 0, 160, 120, 0.1, 1.0) == 0);
}

TEST_CASE("Eq. R12a-b by hand: an eroded mask grows to the square's edge and no further") {
  const auto r = square_in_front();
  // Eroded by 2 ([7, 13)^2): the ring [6, 14)^2 is a = 1, b = 1; the square's border (the edge,
  // Eq. R11a) a = 2, b = 0: a + b = 2 everywhere in the gap.
  Mask m = square_mask(20, 20, 7, 7, 13, 13);
  CHECK(grow(m, r, 2) == 100 - 36);
  CHECK(m.data == square_mask(20, 20, 5, 5, 15, 15).data);
  // A reach of 1 cannot span the gap: nothing grows.
  Mask short_reach = square_mask(20, 20, 7, 7, 13, 13);
  CHECK(grow(short_reach, r, 1) == 0);
  CHECK(short_reach.data == square_mask(20, 20, 7, 7, 13, 13).data);
  // The wall behind is the far side of a depth step: never joined, whatever the reach.
  Mask far_reach = square_mask(20, 20, 7, 7, 13, 13);
  CHECK(grow(far_reach, r, 10) == 100 - 36);
  CHECK(far_reach.data == square_mask(20, 20, 5, 5, 15, 15).data);
  // Steps under the tolerance: no occlusion edge at all, so no gap to fill.
  Mask flat = square_mask(20, 20, 7, 7, 13, 13);
  CHECK(grow(flat, r, 10, 2.5f) == 0);
  // A mask on the edge already: nothing to add; R11b reads -2 for the eroded one (Eq. R12c's o_j).
  Mask exact = square_mask(20, 20, 5, 5, 15, 15);
  CHECK(grow(exact, r, 10) == 0);
  CHECK(vcar::overshoot_px(square_mask(20, 20, 7, 7, 13, 13), r.first, r.second, 0.05f) == -2.0);
}

TEST_CASE("Eq. R12 by hand: where the surface runs on past the contact, with no edge beyond, it is not taken") {
  // A surface at depth 1 from x = 2 to the image's right border (nothing left of it), 20 x 12;
  // the mask is the band x in [5, 9). Left of it the gap to the edge (x = 2) is filled; right of
  // it the surface continues with no occlusion edge (a table past the contact): b is unreached.
  const auto r = render(20, 12, [](int x, int) { return x >= 2; }, [](int, int) { return 1.f; });
  Mask m = square_mask(20, 12, 5, 0, 9, 12);
  CHECK(grow(m, r, 10) == 3 * 12);
  CHECK(m.data == square_mask(20, 12, 2, 0, 9, 12).data);
}

TEST_CASE("Eq. R12a-b against a brute-force shortest-path search on an irregular render") {
  const int W = 17, H = 13;
  const auto r = render(
      W, H, [](int x, int y) { return (x * 5 + y * 3) % 13 != 0 && x > 0; },
      [](int x, int y) { return 1.f + 0.02f * static_cast<float>((x * 7 + y * 11) % 5) + (x > 12 ? 1.f : 0.f); });
  Mask m(W, H, 1);
  for (int y = 3; y < 10; ++y)
    for (int x = 4; x < 10; ++x) m.data[static_cast<std::size_t>(y) * W + x] = (x + y) % 7 ? 255 : 0;
  const std::vector<std::uint8_t> edge = vcar::occlusion_edges(r.first, r.second, 0.05f);
  for (int reach : {1, 2, 3, 5, 8}) {
    Mask grown = m;
    vcar::grow_to_occlusion_edges(grown, edge, r.first, r.second, 0.05f, reach);
    // Bellman-Ford over every pixel: a and b by the definition (8-neighbours, both covered,
    // depths within 5%, paths through covered pixels outside the mask).
    const std::size_t N = static_cast<std::size_t>(W) * H;
    auto covered = [&](std::size_t q) { return r.first.data[q] >= 0.5f; };
    auto joined = [&](std::size_t p, std::size_t q) {
      if (!covered(p) || !covered(q)) return false;
      const float zp = r.second.data[p], zq = r.second.data[q];
      return std::max(zp, zq) <= std::min(zp, zq) * 1.05f;
    };
    auto shortest = [&](auto is_seed) {
      std::vector<int> d(N, 1 << 20);
      for (std::size_t q = 0; q < N; ++q)
        if (is_seed(q)) d[q] = 0;
      for (bool changed = true; changed;) {
        changed = false;
        for (int y = 0; y < H; ++y)
          for (int x = 0; x < W; ++x) {
            const std::size_t q = static_cast<std::size_t>(y) * W + x;
            if (m.data[q] || !covered(q)) continue;  // paths run outside the mask
            for (int v = y - 1; v <= y + 1; ++v)
              for (int u = x - 1; u <= x + 1; ++u) {
                if (u < 0 || v < 0 || u >= W || v >= H) continue;
                const std::size_t p = static_cast<std::size_t>(v) * W + u;
                if (joined(p, q) && d[p] + 1 < d[q] && (m.data[p] ? d[p] == 0 : true)) {
                  d[q] = d[p] + 1;
                  changed = true;
                }
              }
          }
      }
      return d;
    };
    const std::vector<int> a = shortest([&](std::size_t q) { return m.data[q] != 0; });
    const std::vector<int> b = shortest([&](std::size_t q) { return !m.data[q] && edge[q]; });
    for (std::size_t q = 0; q < N; ++q) {
      const bool expect = m.data[q] || (a[q] + b[q] <= reach);
      CHECK((grown.data[q] != 0) == expect);
    }
  }
}

TEST_CASE("Eq. R12 reads the edges within twice its reach of the mask: the same growth from the edges of that box alone") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  const int W = 70, H = 50;
  for (int trial = 0; trial < 6; ++trial) {
    ImageF alpha(W, H, 1), depth(W, H, 1);
    for (std::size_t q = 0; q < alpha.data.size(); ++q) {  // mostly covered, smooth with depth steps
      const int x = static_cast<int>(q % W), y = static_cast<int>(q / W);
      alpha.data[q] = U(rng) < 0.05f ? 0.2f : 1.f;
      depth.data[q] = alpha.data[q] * (1.f + 0.01f * static_cast<float>((x + 2 * y) % 3) + ((x / 9 + y / 7 + trial) % 4 == 0 ? 1.f : 0.f));
    }
    Mask m(W, H, 1);
    const int cx = 20 + 5 * trial, cy = 18 + 2 * trial;
    for (int y = cy - 4; y <= cy + 4; ++y)
      for (int x = cx - 6; x <= cx + 6; ++x) m.data[static_cast<std::size_t>(y) * W + x] = (x * y) % 11 ? 255 : 0;
    const std::vector<std::uint8_t> whole = vcar::occlusion_edges(alpha, depth, 0.05f);
    for (int reach : {1, 2, 4, 7}) {
      vcar::OcclusionEdges lazy(alpha, depth, 0.05f);
      const std::vector<std::uint8_t>& part = lazy.cover(vcar::growth_seed_box(m, reach));
      Mask a = m, b = m;
      const std::size_t added = vcar::grow_to_occlusion_edges(a, whole, alpha, depth, 0.05f, reach);
      CHECK(vcar::grow_to_occlusion_edges(b, part, alpha, depth, 0.05f, reach) == added);
      CAPTURE(trial, reach, added);
      CHECK(a.data == b.data);
      if (reach == 7) CHECK(part != whole);  // the box left some edge out
    }
  }
}
