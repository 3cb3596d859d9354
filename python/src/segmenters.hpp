#pragma once
// The request a Python segmenter receives, and the library's own segmenters (oracle, mask
// folder) as Python objects: vcar.segment runs them in C++ with the GIL released, and they are
// also callables taking a request, like any Python segmenter.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::python {

// vcar.SegmentationRequest: the frames of one segmentation round, valid while the segmenter runs.
struct SegmentationRequest {
  const FrameSequence* frames = nullptr;  // null once the segmenter has returned
  ErrorStash* stash = nullptr;            // where a Python renderer's exception waits
  py::list cameras;
  py::dict prompt;
  std::string round;                      // "coarse" or "fine"

  void check() const {
    if (!frames) throw Error("this request is over: its segmenter has returned", "request");
  }
  std::size_t size() const { return static_cast<std::size_t>(py::len(cameras)); }
};

// vcar.synth.World: the primitives and ids in C++; the Gaussians in a vcar.Scene (w.scene stays
// empty except while a C++ call that needs them runs, see WorldScene in synth.cpp).
struct WorldPy {
  synth::World w;
  py::object scene;  // vcar.Scene
};

struct OracleSegmenterPy {
  py::object world;  // vcar.synth.World, kept alive: the oracle reads its primitives
  std::optional<synth::OracleSegmenter> seg;
};

struct MaskFolderSegmenterPy {
  std::optional<io::MaskFolderSegmenter> seg;
};

// Runs a C++ segmenter on a request (GIL released) and returns its masks as a list of bool
// arrays and None, one per frame.
template <class S>
py::list run_on_request(S& seg, SegmentationRequest& req) {
  req.check();
  std::vector<std::optional<Mask>> masks;
  {
    py::gil_scoped_release nogil;
    masks = segment_all(seg, *req.frames, Prompt{});
  }
  py::list out;
  for (const auto& m : masks) out.append(m ? py::object(mask_array(*m)) : py::object(py::none()));
  return out;
}

}  // namespace vcar::python
