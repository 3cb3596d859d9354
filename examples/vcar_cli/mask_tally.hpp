#pragma once
// TallySegmenter: wraps any Segmenter and counts, per round, the frames that got no mask,
// training views and sampled (SSS) views apart, for the summary of `vcar segment`.
#include <cstddef>
#include <set>
#include <string>
#include <vector>

#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"

namespace vcar::cli {

struct RoundTally {
  std::size_t training = 0, sampled = 0;                  // frames of each kind
  std::size_t training_missing = 0, sampled_missing = 0;  // of those, no mask
};

template <Segmenter S>
class TallySegmenter {
public:
  TallySegmenter(S& inner, const std::vector<Camera>& training) : inner_(&inner) {
    for (const Camera& c : training) training_.insert(c.name);
  }

  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    std::vector<bool> got(frames.size(), false);
    inner_->segment(frames, prompt, [&](std::size_t k, const Mask* m) {
      if (k < got.size() && m) got[k] = true;
      sink(k, m);
    });
    RoundTally t;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const bool train = training_.count(frames.cameras[k].name) > 0;
      (train ? t.training : t.sampled) += 1;
      if (!got[k]) (train ? t.training_missing : t.sampled_missing) += 1;
    }
    rounds_.push_back(t);
  }

  const std::vector<RoundTally>& rounds() const noexcept { return rounds_; }
  // The round whose masks the final vote and ABR used: the last with any mask (a fine round
  // without masks keeps G_coarse, e.g. a mask folder's); the last round if none had one; null
  // before any round.
  const RoundTally* used() const noexcept {
    for (auto it = rounds_.rbegin(); it != rounds_.rend(); ++it)
      if (it->training_missing + it->sampled_missing < it->training + it->sampled) return &*it;
    return rounds_.empty() ? nullptr : &rounds_.back();
  }

private:
  S* inner_;
  std::set<std::string> training_;
  std::vector<RoundTally> rounds_;
};

}  // namespace vcar::cli
