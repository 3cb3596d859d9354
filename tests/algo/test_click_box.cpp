#include <catch2/catch.hpp>

#include <cmath>
#include <optional>
#include <vector>

#include "vcar/algo/click_box.hpp"

namespace {

// Axis-aligned rectangles [x0, x1) x [y0, y1) of pixels: the objects of a W x H image.
struct Rect {
  int x0, y0, x1, y1;
  bool holds(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

// A segmenter that answers the objects' pixels inside the box (the pixels the box touches:
// columns floor(x0) .. ceil(x1) - 1), and counts its calls. `inside_empty`: no mask when the box
// lies inside an object (GrabCut's case: no background in the box to learn from).
struct RectSegmenter {
  int W, H;
  std::vector<Rect> objects;
  bool inside_empty = false;
  int calls = 0;
  std::optional<vcar::Mask> operator()(const Eigen::Vector4f& b) {
    ++calls;
    const int x0 = static_cast<int>(std::floor(b[0])), y0 = static_cast<int>(std::floor(b[1]));
    const int x1 = static_cast<int>(std::ceil(b[2])), y1 = static_cast<int>(std::ceil(b[3]));
    if (inside_empty)
      for (const Rect& r : objects)
        if (x0 >= r.x0 && x1 <= r.x1 && y0 >= r.y0 && y1 <= r.y1) return std::nullopt;
    vcar::Mask m(W, H, 1);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        for (const Rect& r : objects)
          if (r.holds(x, y)) m.data[static_cast<std::size_t>(y) * W + x] = 255;
    return m;
  }
};

void check_box(const vcar::ClickBox& got, float x0, float y0, float x1, float y1) {
  CHECK(got.box[0] == Approx(x0));
  CHECK(got.box[1] == Approx(y0));
  CHECK(got.box[2] == Approx(x1));
  CHECK(got.box[3] == Approx(y1));
}

// box_from_click on `seg` from `click` finds (x0, y0, x1, y1).
void check_found(RectSegmenter seg, const Eigen::Vector2f& click, float x0, float y0, float x1, float y1) {
  const auto got = vcar::box_from_click(std::ref(seg), click, seg.W, seg.H);
  REQUIRE(got);
  CHECK(got->rounds == seg.calls);
  check_box(*got, x0, y0, x1, y1);
}

}  // namespace

TEST_CASE("box_from_click grows a box around the click until the object lies inside it", "[click_box]") {
  // One object [60, 120) x [20, 70) in 200 x 100; the click at its middle. The first box
  // (half-side 0.05 * hypot(200, 100) = 11.2 px) lies inside the object: it grows until the
  // object touches no side, and the answer is the object's bounding box.
  for (const bool inside_empty : {false, true}) {
    RectSegmenter seg{200, 100, {{60, 20, 120, 70}}, inside_empty};
    const auto got = vcar::box_from_click(std::ref(seg), Eigen::Vector2f(90.f, 45.f), 200, 100);
    REQUIRE(got);
    CHECK(got->rounds == seg.calls);
    CHECK(got->rounds >= 3);  // 22 px, then 45, then 89 wide: the object (60 x 50) needs three
    CHECK(got->rounds <= vcar::ClickBoxParams{}.rounds);
    check_box(*got, 60.f, 20.f, 120.f, 70.f);
  }
  // With a margin: padded by 0.1 of its size, 6 px in x and 5 px in y.
  RectSegmenter seg{200, 100, {{60, 20, 120, 70}}};
  vcar::ClickBoxParams p;
  p.margin = 0.1f;
  const auto padded = vcar::box_from_click(std::ref(seg), Eigen::Vector2f(90.f, 45.f), 200, 100, p);
  REQUIRE(padded);
  check_box(*padded, 54.f, 15.f, 126.f, 75.f);
}

TEST_CASE("box_from_click grows past a small patch found inside the object", "[click_box]") {
  // GrabCut in a box inside an object answers a patch of it (the object's colours outside the
  // box model the background): here a 6 x 6 patch at the click while the box lies inside the
  // object [60, 120) x [20, 70), the object's pixels in the box otherwise. The patch fills
  // 36 / 22.4^2 = 0.07 of the first box, under min_fill (0.25): the box grows, and the answer is
  // the object's box.
  int calls = 0;
  const vcar::Mask object = [] {
    vcar::Mask m(200, 100, 1);
    for (int y = 20; y < 70; ++y)
      for (int x = 60; x < 120; ++x) m(x, y) = 255;
    return m;
  }();
  auto patch_inside = [&](const Eigen::Vector4f& b) {
    ++calls;
    vcar::Mask m(200, 100, 1);
    const bool inside = b[0] >= 60.f && b[1] >= 20.f && b[2] <= 120.f && b[3] <= 70.f;
    for (int y = 0; y < 100; ++y)
      for (int x = 0; x < 200; ++x) {
        const bool in_box = x + 1 > b[0] && x < b[2] && y + 1 > b[1] && y < b[3];
        if (inside) m(x, y) = (x >= 87 && x < 93 && y >= 42 && y < 48) ? 255 : 0;
        else m(x, y) = in_box ? object(x, y) : 0;
      }
    return std::optional<vcar::Mask>(m);
  };
  const auto got = vcar::box_from_click(patch_inside, Eigen::Vector2f(90.f, 45.f), 200, 100);
  REQUIRE(got);
  CHECK(got->rounds == calls);
  check_box(*got, 60.f, 20.f, 120.f, 70.f);
  // Without the fill test the patch is the answer.
  vcar::ClickBoxParams p;
  p.min_fill = 0.f;
  const auto part = vcar::box_from_click(patch_inside, Eigen::Vector2f(90.f, 45.f), 200, 100, p);
  REQUIRE(part);
  check_box(*part, 87.f, 42.f, 93.f, 48.f);
}

TEST_CASE("box_from_click keeps the clicked object's component, not its neighbour's", "[click_box]") {
  // Two objects in a row: A [20, 60) x [20, 60) (clicked) and B [62, 150) x [20, 60), 2 px apart.
  check_found({200, 100, {{20, 20, 60, 60}, {62, 20, 150, 60}}}, {40.f, 40.f}, 20.f, 20.f, 60.f, 60.f);  // B left out
}

TEST_CASE("box_from_click does not grow past the image's edges", "[click_box]") {
  // The object fills the left 50 columns from top to bottom: its sides at the image's edges are
  // not touched ones.
  check_found({200, 100, {{0, 0, 50, 100}}}, {25.f, 50.f}, 0.f, 0.f, 50.f, 100.f);
}

TEST_CASE("box_from_click: nothing when the segmenter never separates the object", "[click_box]") {
  // The object covers everything but a 1-px frame: the box grows to the whole image, which
  // leaves nothing outside to tell the object from. So does a segmenter that fills any box.
  RectSegmenter seg{64, 48, {{1, 1, 63, 47}}};
  CHECK_FALSE(vcar::box_from_click(std::ref(seg), Eigen::Vector2f(32.f, 24.f), 64, 48));
  RectSegmenter fills{64, 48, {{0, 0, 64, 48}}};
  CHECK_FALSE(vcar::box_from_click(std::ref(fills), Eigen::Vector2f(32.f, 24.f), 64, 48));
  CHECK(fills.calls >= 2);

  // A segmenter that never finds the object at the click (its object lies far from it): nothing,
  // after the box filled the image.
  RectSegmenter far{200, 100, {{180, 80, 200, 100}}};
  CHECK_FALSE(vcar::box_from_click(std::ref(far), Eigen::Vector2f(20.f, 20.f), 200, 100));
  CHECK(far.calls >= 2);  // it grew before giving up
  // Only `rounds` calls.
  RectSegmenter big{2000, 1000, {{0, 0, 2000, 1000}}, true};
  vcar::ClickBoxParams p;
  p.rounds = 2;
  CHECK_FALSE(vcar::box_from_click(std::ref(big), Eigen::Vector2f(1000.f, 500.f), 2000, 1000, p));
  CHECK(big.calls == 2);
}

TEST_CASE("box_from_click: a click next to the object finds it within the first square", "[click_box]") {
  // The click 5 px left of the object: its own pixel is background, the object's nearest pixel
  // lies within the first half-side (11.2 px).
  check_found({200, 100, {{60, 20, 120, 70}}}, {55.f, 45.f}, 60.f, 20.f, 120.f, 70.f);
}

TEST_CASE("box_from_click rejects bad input", "[click_box]") {
  RectSegmenter seg{200, 100, {{60, 20, 120, 70}}};
  CHECK_THROWS_AS(vcar::box_from_click(std::ref(seg), Eigen::Vector2f(200.f, 45.f), 200, 100), vcar::Error);
  CHECK_THROWS_AS(vcar::box_from_click(std::ref(seg), Eigen::Vector2f(NAN, 45.f), 200, 100), vcar::Error);
  auto wrong_size = [](const Eigen::Vector4f&) { return std::optional<vcar::Mask>(vcar::Mask(10, 10, 1)); };
  CHECK_THROWS_AS(vcar::box_from_click(wrong_size, Eigen::Vector2f(90.f, 45.f), 200, 100), vcar::Error);
  vcar::ClickBoxParams p;
  p.rounds = 0;
  CHECK_THROWS_AS(vcar::box_from_click(std::ref(seg), Eigen::Vector2f(90.f, 45.f), 200, 100, p), vcar::Error);
}
