#pragma once
// A prompt for each named object of a world, as a user would give it: positive points deep inside
// its visible ground truth (prompt_points) and the box around that (mask_box), on the rig's
// reference view; where the object shows fewer than 0.1% of that view's pixels (hidden behind
// another, or out of frame), on the training view that shows most of it.
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/error.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

struct NamedObject {
  std::string name;
  int object_id = 0;
};

struct PromptedObject {
  std::string name;
  int object_id = 0;
  bool visible = false;   // false: no training view shows it (no prompt)
  Prompt prompt;          // points, labels and box on training view prompt.reference_view
};

namespace detail {
inline std::size_t count_id(const IdImage& img, int id) {
  return static_cast<std::size_t>(std::count(img.id.begin(), img.id.end(), id));
}
}  // namespace detail

template <Renderer R>
std::vector<PromptedObject> prompt_objects(const World& w, const Rig& rig, R& renderer,
                                           const std::vector<NamedObject>& objects, int n_points = 3) {
  if (rig.reference >= rig.train.size()) throw Error("reference view out of range", "rig");
  const Camera& ref_cam = rig.train[rig.reference];
  const IdImage ref = raycast(w, ref_cam, renderer);
  // A click target a user could hit: 0.1% of the view (307 pixels at 640 x 480).
  const std::size_t enough = std::max<std::size_t>(1, ref.id.size() / 1000);
  std::vector<PromptedObject> out;
  std::vector<std::size_t> elsewhere;  // objects to look for in the other views
  for (const NamedObject& o : objects) {
    PromptedObject p{o.name, o.object_id, false, {}};
    p.prompt.reference_view = rig.reference;
    if (detail::count_id(ref, o.object_id) >= enough) p.visible = true;
    else elsewhere.push_back(out.size());
    out.push_back(std::move(p));
  }
  if (!elsewhere.empty()) {  // the view showing most of each such object (ties: the first view)
    std::vector<std::size_t> best(out.size(), 0);
    for (std::size_t k : elsewhere) best[k] = detail::count_id(ref, out[k].object_id);
    for (std::size_t v = 0; v < rig.train.size(); ++v) {
      if (v == rig.reference) continue;
      const IdImage img = raycast(w, rig.train[v], renderer);
      for (std::size_t k : elsewhere) {
        const std::size_t n = detail::count_id(img, out[k].object_id);
        if (n > best[k]) { best[k] = n; out[k].prompt.reference_view = v; }
      }
    }
    for (std::size_t k : elsewhere) out[k].visible = best[k] > 0;
  }
  for (PromptedObject& p : out) {
    if (!p.visible) continue;
    const std::size_t v = p.prompt.reference_view;
    const Mask m = mask_of(v == rig.reference ? ref : raycast(w, rig.train[v], renderer), p.object_id);
    const std::string where = "object '" + p.name + "' on view '" + rig.train[v].name + "'";
    p.prompt = prompt_points(m, v, n_points, where);
    p.prompt.box = mask_box(m, where);
  }
  return out;
}

}  // namespace vcar::synth
