#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <random>

#include "vcar/algo/mask_registration.hpp"

#include "square_mask.hpp"

using vcar::ImageF;
using vcar::Mask;

namespace {
ImageF alpha_of(const Mask& m) {
  ImageF a(m.width, m.height, 1);
  for (std::size_t i = 0; i < m.data.size(); ++i) a.data[i] = m.data[i] ? 0.9f : 0.1f;
  return a;
}
// A filled ellipse with a thin horizontal arm (a handle): centre (cx, cy), semi-axes (ax, ay).
Mask blob(int w, int h, double cx, double cy, double ax, double ay) {
  Mask m(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = (x + 0.5 - cx) / ax, v = (y + 0.5 - cy) / ay;
      const bool arm = std::abs(y + 0.5 - cy) < 1.5 && x + 0.5 > cx && x + 0.5 < cx + 1.8 * ax;
      m.data[static_cast<std::size_t>(y) * w + x] = (u * u + v * v <= 1.0 || arm) ? 255 : 0;
    }
  return m;
}
}  // namespace

TEST_CASE("Eq. R14 by hand: a square 3 px right and 2 px up of the render's comes back exactly") {
  const Mask truth = square_mask(40, 30, 10, 8, 22, 20);  // 12 x 12 at (10, 8)
  const Mask drawn = square_mask(40, 30, 13, 6, 25, 18);  // moved by (+3, -2)
  const vcar::MaskShift s = vcar::register_to_alpha(drawn, alpha_of(truth), 8);
  CHECK(s.dx == -3);
  CHECK(s.dy == 2);
  CHECK(s.iou == 1.0);
  // Unmoved overlap: (12 - 3) x (12 - 2) = 90 of 144 + 144 - 90 = 198.
  CHECK(s.iou_unmoved == Approx(90.0 / 198.0));
  CHECK(vcar::shifted(drawn, s.dx, s.dy).data == truth.data);
}

TEST_CASE("Eq. R14: within the radius only; a mask already in place and an empty one stay") {
  const Mask truth = square_mask(40, 30, 10, 8, 22, 20);
  const Mask drawn = square_mask(40, 30, 16, 8, 28, 20);  // 6 px right
  const vcar::MaskShift near = vcar::register_to_alpha(drawn, alpha_of(truth), 3);
  CHECK(near.dx == -3);  // the best shift the radius allows
  CHECK(near.dy == 0);
  const vcar::MaskShift none = vcar::register_to_alpha(truth, alpha_of(truth), 8);
  CHECK((none.dx == 0 && none.dy == 0 && none.iou == 1.0));
  const vcar::MaskShift empty = vcar::register_to_alpha(Mask(40, 30, 1), alpha_of(truth), 8);
  CHECK((empty.dx == 0 && empty.dy == 0 && empty.iou == 0.0));
}

TEST_CASE("Eq. R14's coarse-to-fine search finds the exhaustive search's best IoU on blobs with a thin arm") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const int r = 12;
  for (int trial = 0; trial < 20; ++trial) {
    const double ax = 14 + 6 * U(rng), ay = 10 + 4 * U(rng);
    const Mask truth = blob(96, 72, 40 + 4 * U(rng), 36 + 4 * U(rng), ax, ay);
    const int tx = static_cast<int>(std::lround(10 * U(rng))), ty = static_cast<int>(std::lround(10 * U(rng)));
    Mask drawn = vcar::shifted(truth, tx, ty);
    // Segmenter noise: a few pixels flipped along the rows.
    for (int k = 0; k < 40; ++k) drawn.data[static_cast<std::size_t>(rng() % drawn.data.size())] ^= 255;
    const ImageF a = alpha_of(truth);
    const vcar::MaskShift s = vcar::register_to_alpha(drawn, a, r);
    double brute = 0.0;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const Mask moved = vcar::shifted(drawn, dx, dy);
        std::size_t inter = 0, uni = 0;
        for (std::size_t i = 0; i < moved.data.size(); ++i) {
          const bool p = moved.data[i] != 0, q = truth.data[i] != 0;
          inter += p && q;
          uni += p || q;
        }
        brute = std::max(brute, static_cast<double>(inter) / static_cast<double>(uni));
      }
    INFO("trial " << trial << ", true shift (" << tx << ", " << ty << ")");
    CHECK(s.iou == Approx(brute).epsilon(1e-12));
    CHECK(s.dx == -tx);
    CHECK(s.dy == -ty);
  }
}

TEST_CASE("Eq. R14's radius grows with the silhouette: ceil(factor sqrt(|A|))") {
  const ImageF a = alpha_of(square_mask(40, 30, 10, 8, 22, 20));  // 144 px: sqrt 12
  CHECK(vcar::registration_radius(a, 0.1f) == 2);  // ceil(1.2)
  CHECK(vcar::registration_radius(a, 0.5f) == 6);
  CHECK(vcar::registration_radius(a, 0.f) == 0);
}
