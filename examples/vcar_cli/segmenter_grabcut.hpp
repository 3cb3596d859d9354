#pragma once
// `vcar segment --segmenter grabcut`: OpenCV's GrabCut on every frame, its box from the prompt
// lifted to 3D. Defined in cmd_segment_grabcut.cpp, the one translation unit that includes
// OpenCV, compiled only where OpenCV was found (VCAR_CLI_HAS_OPENCV).
#include <functional>
#include <optional>

#include <Eigen/Core>

#include "vcar/algo/prompt_lift.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/image.hpp"

namespace vcar::cli {

// Whether this build has GrabCut.
constexpr bool has_grabcut() {
#ifdef VCAR_CLI_HAS_OPENCV
  return true;
#else
  return false;
#endif
}

// A segmenter (through make_streaming_segmenter) running vcar::opencv::GrabCutSegmenter on `lifted`.
using SegmentFunction = std::function<void(const FrameSequence&, const Prompt&, const MaskSink&)>;
SegmentFunction make_grabcut_segmenter(LiftedPrompt lifted);

// The box of a points-only prompt on the prompt view's `image`: vcar::box_from_click with GrabCut
// (seeded by the prompt's points, as on frame 0) from its first positive point; nullopt when
// GrabCut finds no object there.
std::optional<Eigen::Vector4f> grabcut_click_box(const ImageRGB8& image, const Prompt& prompt);

}  // namespace vcar::cli
