#pragma once
// The unattended flow of the page's contract (`index.html?scene=&cameras=&view=&click=u,v`),
// shared by the browser (vcar_wasm.cpp) and the native twin (vcar_web_native.cpp) so that both
// pick the reference view and read the click the same way.
//   - with cameras and view=NAME: the camera named NAME (vcar::Error when none is);
//   - with cameras and no view: the first camera;
//   - without cameras: Session::default_view at default_view_width x default_view_height.
// The click is in pixels of that view.
#include <string>

#include "web_session.hpp"

namespace vcar::web {

inline constexpr int default_view_width = 640, default_view_height = 480;
// The page's trade-offs of speed against accuracy (grabcut.js vcarQualities, the same numbers;
// the stage test's Jaccard against the page checks they agree): the views' long side
// (SegmentOptions::max_side), GrabCut's crop (GrabCutParams::context: the box padded by this
// share of its size each side; negative: the whole frame) and its iterations per frame.
struct Quality {
  int max_side;
  float grabcut_context;
  int grabcut_iterations;
};
inline Quality quality_of(const std::string& name) {
  if (name == "full") return {400, -1.f, 5};
  if (name == "fast") return {200, 1.f, 3};
  throw Error("unknown quality '" + name + "' (full or fast)", "quality");
}

inline Camera reference_view(const Session& s, const std::string& view) {
  if (s.cameras().empty()) {
    if (!view.empty() && view != "default") throw Error("view '" + view + "' named but no cameras loaded", "view");
    return s.default_view(default_view_width, default_view_height);
  }
  if (view.empty()) return s.cameras().front();
  for (const Camera& c : s.cameras())
    if (c.name == view) return c;
  throw Error("no camera named '" + view + "'", "view");
}

}  // namespace vcar::web
