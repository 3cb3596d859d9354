#pragma once
// Click to box: the box that a box-prompted image segmenter (GrabCut, ISNet on a crop, SAM 1 with
// a box) needs on the reference view, found from one click by that segmenter itself. Beyond the
// paper (its SAM 2 takes the click). lift_prompt (algo/prompt_lift.hpp) lifts a click as a disc
// around it, a neighbourhood of the click rather than the object, so the boxes it projects cover
// part of the object; the box found here is lifted instead.
//
// box_from_click(segment, click, W, H): starting from a square of half-side start * (image
// diagonal) around the click (clipped to the image), each round
//  - asks segment(box) for a mask (std::optional<Mask>, W x H; nullopt: nothing found);
//  - keeps the mask's 4-connected component under the click (the object clicked on; when the
//    click's own pixel is background, the component of the mask pixel nearest to it within the
//    first square's half-side);
//  - the object touches a side of the box when the component reaches within
//    max(1 px, touch * (the box's size across that side)) of it, and that side is not at the
//    image's border: the object goes on beyond it. No side touched, the component's bounding box
//    at least `min_fill` of the box's area, and the box not the whole image: the object lies
//    inside the box, and the answer is the component's bounding box, each side padded by `margin`
//    of its width (x) or height (y), clipped to the image;
//  - otherwise each touched side moves out by `grow` of the box's size on its axis (every side
//    when there was no mask or no component: the box lay inside the object, or the click missed;
//    and when the component fills less than min_fill of the box: GrabCut in a box inside the
//    object, whose colours then model the background too, answers a small patch of it).
// nullopt after `rounds` rounds, or when the box fills the image: the segmenter never separated
// an object at the click from its surroundings (a box of the whole image leaves it nothing to
// separate the object from; the caller falls back to the click itself).
//
// When it fails: an object touching another of the segmenter's colours grows into it (the
// component spans both); a segmenter that answers a box inside the object with a part filling
// min_fill of it stops early on the part; an object smaller than min_fill of the first box (under
// about half its side) is never accepted (nullopt); a click on a thin part the segmenter drops
// finds no component and grows to a box around whatever it finds near the click.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"

namespace vcar {

struct ClickBoxParams {
  float start = 0.05f;  // first box: a square of half-side start * (image diagonal) around the click
  float grow = 0.5f;    // a touched side moves out by this share of the box's size on its axis
  float touch = 0.02f;  // the object touches a side within max(1 px, touch * box size)
  // An enclosed component's bounding box fills at least this share of the box (the stage's
  // objects, once enclosed: 0.60-0.73; GrabCut's patch in a box inside a donut: 0.07).
  float min_fill = 0.25f;
  // The answer: the object's bounding box padded by this share of its size. 0: a padded box
  // takes in the neighbours the object stands beside (the stage of three real objects, GrabCut,
  // 3D F1 of a click: biker 0.895 at 0, 0.749 at 0.1).
  float margin = 0.f;
  int rounds = 8;       // at most this many calls of the segmenter

  void validate() const {
    auto in = [](float v, float lo, float hi, const char* name) {
      if (!(v >= lo && v <= hi)) throw Error("out of range", std::string("ClickBoxParams.") + name);
    };
    in(start, 1e-3f, 1.f, "start");
    in(grow, 1e-2f, 10.f, "grow");
    in(touch, 0.f, 0.5f, "touch");
    in(min_fill, 0.f, 1.f, "min_fill");
    in(margin, 0.f, 1.f, "margin");
    if (rounds < 1) throw Error("must be >= 1", "ClickBoxParams.rounds");
  }
};

// What box_from_click found: the box and the rounds (segmenter calls) it took.
struct ClickBox {
  Eigen::Vector4f box;  // x0, y0, x1, y1 (pixels)
  int rounds = 0;
};

namespace detail {

// Bounding box (x0, y0, x1, y1 as pixel edges: the last column + 1) of the 4-connected component
// of `m` that holds pixel `seed`; nullopt when the seed is background.
inline std::optional<Eigen::Vector4i> component_box(const Mask& m, int sx, int sy) {
  const int W = m.width, H = m.height;
  auto at = [&](int x, int y) { return static_cast<std::size_t>(y) * W + x; };
  if (sx < 0 || sy < 0 || sx >= W || sy >= H || m.data[at(sx, sy)] == 0) return std::nullopt;
  std::vector<std::uint8_t> seen(m.pixels(), 0);
  std::vector<std::pair<int, int>> stack{{sx, sy}};
  seen[at(sx, sy)] = 1;
  Eigen::Vector4i b(sx, sy, sx + 1, sy + 1);
  while (!stack.empty()) {
    const auto [x, y] = stack.back();
    stack.pop_back();
    b = Eigen::Vector4i(std::min(b[0], x), std::min(b[1], y), std::max(b[2], x + 1), std::max(b[3], y + 1));
    const int nx[4] = {x - 1, x + 1, x, x}, ny[4] = {y, y, y - 1, y + 1};
    for (int k = 0; k < 4; ++k) {
      if (nx[k] < 0 || ny[k] < 0 || nx[k] >= W || ny[k] >= H) continue;
      const std::size_t q = at(nx[k], ny[k]);
      if (seen[q] || m.data[q] == 0) continue;
      seen[q] = 1;
      stack.emplace_back(nx[k], ny[k]);
    }
  }
  return b;
}

// The mask pixel nearest to (cx, cy) within `radius` pixels (nullopt: none).
inline std::optional<std::pair<int, int>> nearest_foreground(const Mask& m, int cx, int cy, int radius) {
  std::optional<std::pair<int, int>> best;
  long best_d2 = static_cast<long>(radius) * radius + 1;
  for (int y = std::max(0, cy - radius); y <= std::min(m.height - 1, cy + radius); ++y)
    for (int x = std::max(0, cx - radius); x <= std::min(m.width - 1, cx + radius); ++x) {
      const long d2 = static_cast<long>(x - cx) * (x - cx) + static_cast<long>(y - cy) * (y - cy);
      if (d2 < best_d2 && m.data[static_cast<std::size_t>(y) * m.width + x] != 0) best_d2 = d2, best = {x, y};
    }
  return best;
}

}  // namespace detail

// See the top of the file. `segment(box)` answers std::optional<Mask> of W x H for a box
// (x0, y0, x1, y1; pixels); nullopt: see above. Throws vcar::Error for an image size under 1 px, a click outside the
// image, and a mask of another size.
template <class SegmentInBox>
std::optional<ClickBox> box_from_click(SegmentInBox&& segment, const Eigen::Vector2f& click, int W, int H,
                                       const ClickBoxParams& params = {}) {
  params.validate();
  if (W < 1 || H < 1) throw Error("the image has no pixels", "box_from_click");
  if (!click.allFinite() || !inside_image(click.x(), click.y(), W, H))
    throw Error("the click lies outside the image", "box_from_click");
  const float Wf = static_cast<float>(W), Hf = static_cast<float>(H);
  const float half = params.start * std::hypot(Wf, Hf);
  auto clip = [&](Eigen::Vector4f b) {
    return Eigen::Vector4f(std::max(0.f, b[0]), std::max(0.f, b[1]), std::min(Wf, b[2]), std::min(Hf, b[3]));
  };
  Eigen::Vector4f box = clip({click.x() - half, click.y() - half, click.x() + half, click.y() + half});
  const int cx = static_cast<int>(click.x()), cy = static_cast<int>(click.y());
  for (int round = 1; round <= params.rounds; ++round) {
    const std::optional<Mask> m = segment(Eigen::Vector4f(box));
    std::optional<Eigen::Vector4i> object;
    if (m) {
      if (m->width != W || m->height != H)
        throw Error("the segmenter's mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) +
                        ", the image " + std::to_string(W) + "x" + std::to_string(H), "box_from_click");
      object = detail::component_box(*m, cx, cy);
      if (!object)
        if (const auto p = detail::nearest_foreground(*m, cx, cy, static_cast<int>(half)))
          object = detail::component_box(*m, p->first, p->second);
    }
    // touched[s]: side s (x0, y0, x1, y1) is reached by the object and is not the image's edge.
    bool touched[4] = {true, true, true, true};
    if (object) {
      const Eigen::Vector4f o = object->cast<float>();
      const float w = box[2] - box[0], h = box[3] - box[1];
      const float tx = std::max(1.f, params.touch * w), ty = std::max(1.f, params.touch * h);
      touched[0] = box[0] > 0.f && o[0] - box[0] < tx;
      touched[1] = box[1] > 0.f && o[1] - box[1] < ty;
      touched[2] = box[2] < Wf && box[2] - o[2] < tx;
      touched[3] = box[3] < Hf && box[3] - o[3] < ty;
      const bool whole = box[0] <= 0.f && box[1] <= 0.f && box[2] >= Wf && box[3] >= Hf;
      if (whole) return std::nullopt;  // nothing left outside the box to tell the object from
      const float fill = (o[2] - o[0]) * (o[3] - o[1]) / std::max(1.f, w * h);
      if (fill < params.min_fill) touched[0] = touched[1] = touched[2] = touched[3] = true;  // a part: grow
      if (!touched[0] && !touched[1] && !touched[2] && !touched[3]) {
        const float px = params.margin * (o[2] - o[0]), py = params.margin * (o[3] - o[1]);
        return ClickBox{clip({o[0] - px, o[1] - py, o[2] + px, o[3] + py}), round};
      }
    }
    const float gx = params.grow * (box[2] - box[0]), gy = params.grow * (box[3] - box[1]);
    const Eigen::Vector4f grown = clip({box[0] - (touched[0] ? gx : 0.f), box[1] - (touched[1] ? gy : 0.f),
                                        box[2] + (touched[2] ? gx : 0.f), box[3] + (touched[3] ? gy : 0.f)});
    if (grown == box) break;  // every touched side is at the image's edge: the box fills what it can
    box = grown;
  }
  return std::nullopt;
}

}  // namespace vcar
