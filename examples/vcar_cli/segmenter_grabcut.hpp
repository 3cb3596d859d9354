#pragma once
// `vcar segment --segmenter grabcut`: OpenCV's GrabCut on every frame, its box from the prompt
// lifted to 3D. Defined in cmd_segment_grabcut.cpp, the one translation unit that includes
// OpenCV, compiled only where OpenCV was found (VCAR_CLI_HAS_OPENCV).
#include <functional>

#include "vcar/algo/prompt_lift.hpp"
#include "vcar/concepts/segmenter.hpp"

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

}  // namespace vcar::cli
