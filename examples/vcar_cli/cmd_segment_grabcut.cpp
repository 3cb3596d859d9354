// `vcar segment --segmenter grabcut`: the one translation unit of the program that includes
// OpenCV (built only where OpenCV was found).
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "segmenter_grabcut.hpp"
#include "vcar/algo/click_box.hpp"
#include "vcar/opencv/grabcut_segmenter.hpp"

namespace vcar::cli {

SegmentFunction make_grabcut_segmenter(LiftedPrompt lifted) {
  auto grabcut = std::make_shared<opencv::GrabCutSegmenter>(std::move(lifted));
  return [grabcut](const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    grabcut->segment(frames, prompt, sink);
  };
}

std::optional<Eigen::Vector4f> grabcut_click_box(const ImageRGB8& image, const Prompt& prompt) {
  const opencv::GrabCutParams params;
  std::vector<opencv::GrabCutSeed> seeds;
  const Eigen::Vector2f* click = nullptr;
  for (std::size_t p = 0; p < prompt.points.size(); ++p) {
    const bool positive = p >= prompt.point_labels.size() || prompt.point_labels[p] != 0;
    seeds.push_back({prompt.points[p], positive});
    if (positive && !click) click = &prompt.points[p];
  }
  if (!click) return std::nullopt;
  const float radius = params.seed_radius * std::hypot(static_cast<float>(image.width), static_cast<float>(image.height));
  const auto found = box_from_click(
      [&](const Eigen::Vector4f& box) { return opencv::grabcut(image, box, params, seeds, radius, "GrabCut, the click's box"); },
      *click, image.width, image.height);
  if (!found) return std::nullopt;
  return found->box;
}

}  // namespace vcar::cli
