// The SAM-like failure models (synth/sam_failures.hpp) on hand-drawn label images whose right
// answers are known: each does what its comment says and nothing else.
#include <catch2/catch.hpp>

#include <cmath>
#include <set>

#include "vcar/synth/sam_failures.hpp"

using namespace vcar::synth;

namespace {

// 80 x 60 labels: the floor (0) in the lower half, the target (1) a disc of radius 12 at
// (30, 30), a touching neighbour box (2) right of it, a distant object (4) in the top-left
// corner, a floor patch (0) above the disc behind a 3 px gap of nothing (-1); -1 elsewhere.
IdImage sam_scene() {
  IdImage img;
  img.width = 80;
  img.height = 60;
  img.id.assign(80 * 60, -1);
  auto set = [&](int x, int y, int id) { img.id[static_cast<std::size_t>(y) * 80 + x] = id; };
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 80; ++x) {
      const float dx = x + 0.5f - 30.f, dy = y + 0.5f - 30.f;
      if (y >= 36) set(x, y, 0);
      if (x >= 42 && x < 56 && y >= 20 && y < 40) set(x, y, 2);
      if (x < 8 && y < 8) set(x, y, 4);
      if (x >= 24 && x < 36 && y >= 10 && y < 15) set(x, y, 0);  // 3 px above the disc's top (y 18)
      if (dx * dx + dy * dy <= 144.f) set(x, y, 1);
    }
  return img;
}

double centroid_x(const vcar::Mask& m) {
  double s = 0;
  std::size_t n = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      if (m(x, y)) { s += x; ++n; }
  return s / static_cast<double>(n);
}
double centroid_y(const vcar::Mask& m) {
  double s = 0;
  std::size_t n = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      if (m(x, y)) { s += y; ++n; }
  return s / static_cast<double>(n);
}

}  // namespace

TEST_CASE("wrong: another label the frame shows (not only the neighbour), never the target or nothing") {
  const IdImage img = sam_scene();
  std::set<int> picked;
  for (std::uint64_t s = 0; s < 200; ++s) {
    Rng rng(s, 1);
    const int id = sam::other_label(img, 1, rng);
    CHECK(id >= 0);
    CHECK(id != 1);
    picked.insert(id);
  }
  CHECK(picked == std::set<int>{0, 2, 4});  // the floor, the neighbour and the distractor
  IdImage alone = img;                       // nothing but the target: it keeps its mask
  for (int& id : alone.id) id = id == 1 ? 1 : -1;
  Rng rng(1, 1);
  CHECK(sam::other_label(alone, 1, rng) == 1);
  IdImage speck = alone;                     // a label on a few pixels (< 0.1% of the frame) is no object
  speck.id[0] = speck.id[1] = 7;
  CHECK(sam::other_label(speck, 1, rng) == 1);
}

TEST_CASE("part: a strict subset, one side of a line through the centroid, about half") {
  const vcar::Mask disc = mask_of(sam_scene(), 1);
  const std::size_t n = count(disc);
  for (int k = 0; k < 16; ++k) {
    const float a = 0.4f * static_cast<float>(k);
    const vcar::Mask p = sam::cut_through_centroid(disc, a);
    std::size_t kept = 0, outside = 0;
    for (std::size_t i = 0; i < p.data.size(); ++i) {
      kept += p.data[i] != 0;
      outside += p.data[i] && !disc.data[i];
    }
    CHECK(outside == 0);
    CHECK(kept < n);
    CHECK(kept > n * 4 / 10);
    CHECK(kept < n * 6 / 10);
    // Everything kept lies on the side (cos a, sin a) of the centre (30, 30).
    for (int y = 0; y < p.height; ++y)
      for (int x = 0; x < p.width; ++x)
        if (p(x, y)) CHECK(std::cos(a) * (x + 0.5 - 30.0) + std::sin(a) * (y + 0.5 - 30.0) > -0.5);
  }
  vcar::Mask one(5, 5, 1);  // even a single pixel loses something (strict subset)
  one(2, 2) = 255;
  CHECK(count(sam::cut_through_centroid(one, 1.f)) == 0);
}

TEST_CASE("leak: adds only pixels of one other label, within reach and connected to the mask") {
  const IdImage img = sam_scene();
  const vcar::Mask disc = mask_of(img, 1);
  const std::vector<float> d2 = squared_distance(disc, true);
  std::set<int> leaked;
  for (std::uint64_t s = 0; s < 40; ++s) {
    vcar::Mask m = disc;
    Rng rng(s, 3);
    const int id = sam::leak(m, img, 1, 6, rng);
    REQUIRE((id == 0 || id == 2));  // the floor under it or the touching neighbour: never 4
    leaked.insert(id);
    std::size_t added = 0;
    for (std::size_t k = 0; k < m.data.size(); ++k) {
      if (!m.data[k] || disc.data[k]) continue;
      ++added;
      CHECK(img.id[k] == id);
      CHECK(d2[k] <= 36.f);
      CHECK(k / 80 >= 18);  // the floor patch above, behind a gap, stays out
    }
    CHECK(added > 20);
    // Every added pixel reaches the mask through added pixels (4-connected).
    std::vector<char> reach(m.data.size(), 0);
    std::vector<std::size_t> stack;
    for (std::size_t k = 0; k < m.data.size(); ++k)
      if (disc.data[k]) { reach[k] = 1; stack.push_back(k); }
    while (!stack.empty()) {
      const std::size_t k = stack.back();
      stack.pop_back();
      const std::size_t x = k % 80, y = k / 80;
      for (std::size_t j : {x > 0 ? k - 1 : k, x < 79 ? k + 1 : k, y > 0 ? k - 80 : k, y < 59 ? k + 80 : k})
        if (m.data[j] && !reach[j]) { reach[j] = 1; stack.push_back(j); }
    }
    for (std::size_t k = 0; k < m.data.size(); ++k)
      if (m.data[k]) CHECK(reach[k]);
  }
  CHECK(leaked == std::set<int>{0, 2});
  IdImage alone = img;  // nothing touches: unchanged
  for (int& id : alone.id) id = id == 1 ? 1 : -1;
  vcar::Mask m = disc;
  Rng rng(1, 3);
  CHECK(sam::leak(m, alone, 1, 6, rng) == -1);
  CHECK(m.data == disc.data);
}

TEST_CASE("drift: frame k shifted by k drift_px along one direction") {
  const vcar::Mask disc = mask_of(sam_scene(), 1);
  const float angle = sam::drift_angle(9);
  CHECK(angle == sam::drift_angle(9));
  CHECK(angle != sam::drift_angle(10));
  const double x0 = centroid_x(disc), y0 = centroid_y(disc);
  double last = -1.0;
  for (std::size_t k = 0; k < 6; ++k) {
    const vcar::Mask m = sam::drift(disc, k, 1.5f, angle);
    const double dx = centroid_x(m) - x0, dy = centroid_y(m) - y0;
    const double d = std::hypot(dx, dy);
    CHECK(d == Approx(1.5 * k).margin(0.75));  // rounded to whole pixels
    if (k > 0) CHECK(d > last);
    if (k > 1) {  // (frame 1's 1.5 px rounds to whole pixels: its direction is coarse)
      CHECK((dx * std::cos(angle) + dy * std::sin(angle)) / d == Approx(1.0).margin(0.15));  // one direction
    }
    last = d;
  }
  CHECK(sam::drift(disc, 0, 3.f, angle).data == disc.data);  // the prompted frame is exact
}

TEST_CASE("SAM failures: off by default, validated") {
  SamFailures f;
  CHECK_FALSE(f.any());
  CHECK_NOTHROW(f.validate());
  f.p_leak = 1.5;
  CHECK_THROWS_AS(f.validate(), vcar::Error);
  f = {};
  f.p_part = -0.1;
  CHECK_THROWS_AS(f.validate(), vcar::Error);
  f = {};
  f.p_wrong = std::nan("");
  CHECK_THROWS_AS(f.validate(), vcar::Error);
  f = {};
  f.leak_px = 0;
  CHECK_THROWS_AS(f.validate(), vcar::Error);
  f = {};
  f.drift_px = -1.f;
  CHECK_THROWS_AS(f.validate(), vcar::Error);
  f = {};
  f.drift_px = 0.5f;
  CHECK(f.any());
  CHECK_FALSE(f.needs_labels());
}
