// `vcar segment --segmenter grabcut`: the one translation unit of the program that includes
// OpenCV (built only where OpenCV was found).
#include <memory>
#include <utility>

#include "segmenter_grabcut.hpp"
#include "vcar/opencv/grabcut_segmenter.hpp"

namespace vcar::cli {

SegmentFunction make_grabcut_segmenter(LiftedPrompt lifted) {
  auto grabcut = std::make_shared<opencv::GrabCutSegmenter>(std::move(lifted));
  return [grabcut](const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    grabcut->segment(frames, prompt, sink);
  };
}

}  // namespace vcar::cli
