#pragma once
// selection.json, the file `vcar segment` writes and `render`, `eval` and the Python module
// read: {"indices": [...ascending], "scores": [...], "log_scales": [[l0, l1, l2], ...],
// "scene_gaussians": n, "identity": {"hash", "scene": {"gaussians", "ordered", "unordered"},
// "gaussians": [hex, ...]}}. Scores, log_scales and identity.gaussians are aligned with indices;
// the identity (io/selection_identity.hpp) says which Gaussians of which scene were selected.
// Several objects (`vcar segment --prompts`): {"objects": [{"name", "object_id", "indices",
// ...}, ...]}, each entry a selection of its own. A state PLY (`vcar segment --state-ply`, or
// saved by SuperSplat) reads as a selection too: the Gaussians flagged selected and not deleted.
// Errors throw vcar::Error naming the file (and the object).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/selection_identity.hpp"
#include "vcar/io/state_ply.hpp"

namespace vcar::io {

struct Selection {
  std::vector<Index> indices;
  std::vector<float> scores;
  LogScales log_scale;              // empty columns: the scene's own scales
  std::size_t scene_gaussians = 0;  // 0 = unknown
  std::optional<SelectionIdentity> identity;  // absent in files of vcar before 0.2
  bool has_log_scales() const { return !log_scale[0].empty(); }
};

// One object of a selection.json of several objects; a one-object file (or a state PLY) reads
// as one entry named "".
struct ObjectSelection {
  std::string name;
  int object_id = -1;  // the synthetic world's object, when the prompts named it
  Selection selection;
};

// The JSON of one selection (the top level of selection.json, or an entry of its "objects").
inline nlohmann::json selection_json(const Selection& s) {
  nlohmann::json ls = nlohmann::json::array();
  if (s.has_log_scales())
    for (std::size_t k = 0; k < s.indices.size(); ++k)
      ls.push_back({s.log_scale[0][k], s.log_scale[1][k], s.log_scale[2][k]});
  nlohmann::json j = {{"indices", s.indices}, {"scores", s.scores}, {"log_scales", ls},
                      {"scene_gaussians", s.scene_gaussians}};
  if (s.identity) {
    nlohmann::json ids = nlohmann::json::array();
    for (std::uint64_t id : s.identity->gaussians) ids.push_back(identity_hex(id));
    j["identity"] = {{"hash", "FNV-1a 64 of the float32 mean, log-scale, rotation, opacity logit and SH (io/selection_identity.hpp)"},
                     {"scene", {{"gaussians", s.identity->scene.gaussians},
                                {"ordered", identity_hex(s.identity->scene.ordered)},
                                {"unordered", identity_hex(s.identity->scene.unordered)}}},
                     {"gaussians", ids}};
  }
  return j;
}

namespace detail {

inline bool starts_with_ply(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  unsigned char head[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(head), 4);
  return ply_signature(head, static_cast<std::size_t>(in.gcount()));
}

// A state PLY as a selection: the Gaussians selected and not deleted, identified in that file.
inline Selection selection_from_state_ply(const std::filesystem::path& file) {
  const std::string where = file.string();
  const GaussianScene st = read_scene(file);
  const std::vector<std::uint8_t> state = state_of(st, where);
  if (state.empty())
    throw Error("PLY without a 'state' property: not a selection (write one with vcar segment --state-ply)", where);
  Selection s;
  for (std::size_t i = 0; i < state.size(); ++i)
    if ((state[i] & splat_state::selected) && !(state[i] & splat_state::deleted)) s.indices.push_back(static_cast<Index>(i));
  s.scene_gaussians = st.size();
  s.identity = selection_identity(gaussian_identities(st), s.indices);
  return s;
}

inline void read_identity(const nlohmann::json& j, Selection& s, const std::string& where) {
  if (!j.contains("identity")) return;
  const auto& id = j["identity"];
  if (!id.is_object() || !id.contains("scene") || !id.contains("gaussians") || !id["gaussians"].is_array())
    throw Error("\"identity\" must hold \"scene\" and \"gaussians\"", where);
  SelectionIdentity out;
  const auto& sc = id["scene"];
  out.scene.gaussians = sc.at("gaussians").get<std::uint64_t>();
  out.scene.ordered = identity_from_hex(sc.at("ordered").get<std::string>(), where);
  out.scene.unordered = identity_from_hex(sc.at("unordered").get<std::string>(), where);
  for (const auto& g : id["gaussians"]) out.gaussians.push_back(identity_from_hex(g.get<std::string>(), where));
  if (out.gaussians.size() != s.indices.size())
    throw Error("\"identity\" names " + std::to_string(out.gaussians.size()) + " Gaussians, \"indices\" has " +
                                       std::to_string(s.indices.size()), where);
  s.identity = std::move(out);
}

// Applies `s` to `scene` by identity: entry k becomes Gaussian loc[k]; the entries are then
// sorted by their new index (scores and scales follow).
inline void apply_identity(Selection& s, const GaussianScene& scene, const std::string& where) {
  const LocatedSelection loc = locate_selection(gaussian_identities(scene), s.indices, *s.identity, where);
  if (!loc.reordered) return;
  std::vector<std::size_t> order(s.indices.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return loc.index[a] < loc.index[b]; });
  Selection r = s;
  for (std::size_t k = 0; k < order.size(); ++k) {
    r.indices[k] = loc.index[order[k]];
    r.identity->gaussians[k] = s.identity->gaussians[order[k]];
    if (!s.scores.empty()) r.scores[k] = s.scores[order[k]];
    if (s.has_log_scales())
      for (int d = 0; d < 3; ++d) r.log_scale[d][k] = s.log_scale[d][order[k]];
  }
  r.identity->scene = scene_fingerprint(gaussian_identities(scene));
  s = std::move(r);
}


// One selection object (the top level of selection.json, or an entry of its "objects").
inline Selection parse_selection(const nlohmann::json& j, const std::string& where) {
  Selection s;
  try {
    if (!j.is_object() || !j.contains("indices") || !j["indices"].is_array())
      throw Error("expected an object with an \"indices\" array", where);
    s.indices = j["indices"].get<std::vector<Index>>();
    if (j.contains("scores") && j["scores"].is_array()) s.scores = j["scores"].get<std::vector<float>>();
    if (j.contains("scene_gaussians") && j["scene_gaussians"].is_number_unsigned())
      s.scene_gaussians = j["scene_gaussians"].get<std::size_t>();
    if (j.contains("log_scales") && j["log_scales"].is_array() && !j["log_scales"].empty()) {
      const auto& ls = j["log_scales"];
      if (ls.size() != s.indices.size())
        throw Error("\"log_scales\" has " + std::to_string(ls.size()) +
                                           " entries, \"indices\" " + std::to_string(s.indices.size()), where);
      for (auto& c : s.log_scale) c.resize(ls.size());
      for (std::size_t k = 0; k < ls.size(); ++k) {
        if (!ls[k].is_array() || ls[k].size() != 3)
          throw Error("\"log_scales\"[" + std::to_string(k) + "] is not [l0, l1, l2]", where);
        for (int d = 0; d < 3; ++d) s.log_scale[d][k] = ls[k][d].get<float>();
      }
    }
    read_identity(j, s, where);
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("malformed selection: ") + e.what(), where);
  }
  if (!s.scores.empty() && s.scores.size() != s.indices.size())
    throw Error("\"scores\" and \"indices\" differ in length", where);
  for (std::size_t k = 1; k < s.indices.size(); ++k)
    if (s.indices[k] <= s.indices[k - 1])
      throw Error("\"indices\" must be strictly ascending (entry " + std::to_string(k) + ")", where);
  return s;
}

inline void apply_to_scene(Selection& s, const GaussianScene* scene, const std::string& where) {
  if (scene && s.identity) {
    apply_identity(s, *scene, where);
    return;
  }
  const std::size_t scene_size = scene ? scene->size() : 0;
  if (scene_size > 0) {
    if (s.scene_gaussians != 0 && s.scene_gaussians != scene_size)
      throw Error("selection was made on a scene of " + std::to_string(s.scene_gaussians) +
                                         " Gaussians, this scene has " + std::to_string(scene_size), where);
    if (!s.indices.empty() && s.indices.back() >= scene_size)
      throw Error("index " + std::to_string(s.indices.back()) + " out of range (" +
                                         std::to_string(scene_size) + " Gaussians)", where);
  }
}
}  // namespace detail

// Reads and checks a selection: selection.json, or a state PLY. With `scene`, applies it to
// that scene: by identity, so a re-sorted copy of the selection's scene gets the same Gaussians
// (indices, scores and scales re-ordered to match) and any other scene is refused (saying why);
// a file without identity is applied by index after a size check. A selection.json of several
// objects reads as the union of its objects.
inline Selection read_selection(const std::filesystem::path& file, const GaussianScene* scene = nullptr);

// Each object of a selection.json of several objects, applied to `scene` like read_selection.
inline std::vector<ObjectSelection> read_object_selections(const std::filesystem::path& file,
                                                          const GaussianScene* scene = nullptr) {
  const std::string where = file.string();
  std::vector<ObjectSelection> out;
  if (detail::starts_with_ply(file)) {
    out.push_back({"", -1, read_selection(file, scene)});
    return out;
  }
  const nlohmann::json j = read_json_file(file);
  if (!j.is_object() || !j.contains("objects")) {
    out.push_back({"", -1, read_selection(file, scene)});
    return out;
  }
  if (!j["objects"].is_array() || j["objects"].empty())
    throw Error("\"objects\" must be a non-empty array", where);
  for (std::size_t k = 0; k < j["objects"].size(); ++k) {
    const auto& e = j["objects"][k];
    const std::string w = where + ", object " + std::to_string(k);
    ObjectSelection o;
    try {
      o.name = e.at("name").get<std::string>();
      if (e.contains("object_id") && e["object_id"].is_number_integer()) o.object_id = e["object_id"].get<int>();
    } catch (const nlohmann::json::exception& x) {
      throw Error(std::string("malformed object: ") + x.what(), w);
    }
    o.selection = detail::parse_selection(e, w + " ('" + o.name + "')");
    detail::apply_to_scene(o.selection, scene, w + " ('" + o.name + "')");
    out.push_back(std::move(o));
  }
  return out;
}

inline Selection read_selection(const std::filesystem::path& file, const GaussianScene* scene) {
  const std::string where = file.string();
  Selection s;
  if (detail::starts_with_ply(file)) {
    s = detail::selection_from_state_ply(file);
    if (scene) detail::apply_identity(s, *scene, where);
    return s;
  }
  const nlohmann::json j = read_json_file(file);
  if (j.is_object() && j.contains("objects")) {
    // Several objects (vcar segment --prompts): their union, each with its refined scales.
    std::vector<ObjectSelection> objs = read_object_selections(file, scene);
    std::vector<std::pair<Index, std::pair<std::size_t, std::size_t>>> all;  // index -> (object, entry)
    bool scaled = true;
    for (std::size_t o = 0; o < objs.size(); ++o) {
      scaled = scaled && objs[o].selection.has_log_scales();
      for (std::size_t k = 0; k < objs[o].selection.indices.size(); ++k) all.push_back({objs[o].selection.indices[k], {o, k}});
    }
    std::sort(all.begin(), all.end());
    for (std::size_t k = 0; k < all.size(); ++k) {
      if (k > 0 && all[k].first == all[k - 1].first) continue;  // conflicts are resolved when written; keep the first
      const Selection& src = objs[all[k].second.first].selection;
      const std::size_t e = all[k].second.second;
      s.indices.push_back(all[k].first);
      s.scores.push_back(e < src.scores.size() ? src.scores[e] : 0.f);
      if (scaled)
        for (int d = 0; d < 3; ++d) s.log_scale[d].push_back(src.log_scale[d][e]);
    }
    s.scene_gaussians = scene ? scene->size() : objs.front().selection.scene_gaussians;
    return s;
  }
  s = detail::parse_selection(j, where);
  detail::apply_to_scene(s, scene, where);
  return s;
}

}  // namespace vcar::io
