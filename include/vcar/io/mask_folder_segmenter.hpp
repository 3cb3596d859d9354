#pragma once
// MaskFolderSegmenter: a Segmenter (concepts/segmenter.hpp) that answers frame k with the mask
// file of a folder whose stem matches the stem of cameras[k].name ("IMG_01.jpg" -> IMG_01.png),
// .png preferred over .jpg / .jpeg; a frame without a file gets "no mask" (no evidence,
// conventions §4). The prompt is ignored: the masks already are the answer. Masks are read one at
// a time and streamed to the sink; a mask of the wrong size is an error naming the file.
// The files are masks of the captured images (renders of the whole scene). Frames that render a
// subset (the fine round's renders of G_coarse, FrameSequence::subset) are other images: the
// folder answers each of them "no mask", and the pipeline keeps G_coarse (docs/robust.md, "A
// folder of masks").
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <string>
#include <utility>

#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/image_file.hpp"

namespace vcar::io {

class MaskFolderSegmenter {
public:
  explicit MaskFolderSegmenter(std::filesystem::path dir) : dir_(std::move(dir)) {
    if (!std::filesystem::is_directory(dir_)) throw Error("mask folder does not exist", dir_.string());
  }

  const std::filesystem::path& dir() const noexcept { return dir_; }

  // Whether the folder holds masks of these frames: only of renders of the whole scene.
  static bool has_masks_of(const FrameSequence& frames) noexcept { return !frames.subset; }

  void segment(const FrameSequence& frames, const Prompt&, const MaskSink& sink) {
    if (!has_masks_of(frames)) {
      for (std::size_t k = 0; k < frames.size(); ++k) sink(k, nullptr);
      return;
    }
    const auto files = index();  // scanned per round: the folder may change between rounds
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const Camera& cam = frames.cameras[k];
      const auto it = files.find(std::filesystem::path(cam.name).stem().string());
      if (it == files.end()) {
        sink(k, nullptr);
        continue;
      }
      const Mask m = read_mask(it->second.second, cam.width, cam.height);
      sink(k, &m);
    }
  }

private:
  // stem -> (rank of the extension, file); lower rank wins (.png before .jpg before .jpeg).
  std::map<std::string, std::pair<int, std::filesystem::path>> index() const {
    std::map<std::string, std::pair<int, std::filesystem::path>> files;
    for (const auto& e : std::filesystem::directory_iterator(dir_)) {
      if (!e.is_regular_file()) continue;
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      const int rank = ext == ".png" ? 0 : ext == ".jpg" ? 1 : ext == ".jpeg" ? 2 : -1;
      if (rank < 0) continue;
      const std::string stem = e.path().stem().string();
      const auto it = files.find(stem);
      if (it == files.end() || rank < it->second.first) files[stem] = {rank, e.path()};
    }
    return files;
  }

  std::filesystem::path dir_;
};

static_assert(Segmenter<MaskFolderSegmenter>);

}  // namespace vcar::io

namespace vcar {
using io::MaskFolderSegmenter;  // the name concepts/segmenter.hpp documents
}  // namespace vcar
