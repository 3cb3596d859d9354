#pragma once
// The world's description as JSON (gt/scene.json of an exported dataset): primitives with pose,
// parameters, texture and object id; inserted Gaussian ranges; target / neighbour ids; up. The
// Gaussians and their ids live beside it (scene.ply, gt/gaussian_ids.bin), so the oracle and
// the ground truth can be rebuilt from disk. Floats round-trip exactly (printed as doubles).
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "vcar/core/error.hpp"
#include "vcar/synth/primitive.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

namespace detail {
template <class M>
nlohmann::json to_json_array(const M& m) {
  nlohmann::json a = nlohmann::json::array();
  for (int r = 0; r < m.rows(); ++r)
    for (int c = 0; c < m.cols(); ++c) a.push_back(static_cast<double>(m(r, c)));
  return a;
}
template <class M>
void from_json_array(const nlohmann::json& a, M& m, const std::string& where) {
  if (!a.is_array() || a.size() != static_cast<std::size_t>(m.rows() * m.cols()))
    throw Error("expected an array of " + std::to_string(m.rows() * m.cols()) + " numbers", where);
  for (int r = 0; r < m.rows(); ++r)
    for (int c = 0; c < m.cols(); ++c) m(r, c) = a[static_cast<std::size_t>(r * m.cols() + c)].get<float>();
}
inline const char* pattern_name(Pattern p) {
  switch (p) {
    case Pattern::solid: return "solid";
    case Pattern::stripes: return "stripes";
    case Pattern::checker: return "checker";
    case Pattern::noise: return "noise";
  }
  return "solid";
}
inline Pattern pattern_from(const std::string& s, const std::string& where) {
  for (auto p : {Pattern::solid, Pattern::stripes, Pattern::checker, Pattern::noise})
    if (s == pattern_name(p)) return p;
  throw Error("unknown texture pattern '" + s + "'", where);
}
}  // namespace detail

// Everything but the Gaussians and their ids.
inline nlohmann::json world_to_json(const World& w) {
  nlohmann::json j;
  j["target_id"] = w.target_id;
  j["neighbour_id"] = w.neighbour_id;
  j["up"] = detail::to_json_array(w.up);
  j["seed"] = w.seed;
  j["gaussian_count"] = w.scene.size();
  j["primitives"] = nlohmann::json::array();
  for (const auto& q : w.primitives) {
    nlohmann::json p;
    p["type"] = to_string(q.type);
    p["object_id"] = q.object_id;
    p["rotation"] = detail::to_json_array(q.R);  // local-to-world, row-major
    p["translation"] = detail::to_json_array(q.t);
    p["params"] = detail::to_json_array(q.params);
    p["texture"] = {{"pattern", detail::pattern_name(q.texture.pattern)},
                    {"colour_a", detail::to_json_array(q.texture.colour_a)},
                    {"colour_b", detail::to_json_array(q.texture.colour_b)},
                    {"frequency", static_cast<double>(q.texture.frequency)}};
    j["primitives"].push_back(p);
  }
  j["inserted"] = nlohmann::json::array();
  for (const auto& o : w.inserted)
    j["inserted"].push_back({{"object_id", o.object_id}, {"begin", o.begin}, {"count", o.count}});
  return j;
}

// The description back; the caller fills scene and object_id. `where` names the file in errors.
inline World world_from_json(const nlohmann::json& j, const std::string& where = "scene.json") {
  World w;
  try {
    w.target_id = j.at("target_id").get<int>();
    w.neighbour_id = j.at("neighbour_id").get<int>();
    detail::from_json_array(j.at("up"), w.up, where + ": up");
    w.seed = j.value("seed", std::uint64_t{0});
    for (const auto& p : j.at("primitives")) {
      Primitive q;
      q.type = primitive_type_from_string(p.at("type").get<std::string>());
      q.object_id = p.at("object_id").get<int>();
      detail::from_json_array(p.at("rotation"), q.R, where + ": rotation");
      detail::from_json_array(p.at("translation"), q.t, where + ": translation");
      detail::from_json_array(p.at("params"), q.params, where + ": params");
      const auto& t = p.at("texture");
      q.texture.pattern = detail::pattern_from(t.at("pattern").get<std::string>(), where);
      detail::from_json_array(t.at("colour_a"), q.texture.colour_a, where + ": colour_a");
      detail::from_json_array(t.at("colour_b"), q.texture.colour_b, where + ": colour_b");
      q.texture.frequency = t.at("frequency").get<float>();
      w.primitives.push_back(q);
    }
    for (const auto& o : j.value("inserted", nlohmann::json::array()))
      w.inserted.push_back({o.at("object_id").get<int>(), o.at("begin").get<std::size_t>(), o.at("count").get<std::size_t>()});
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("bad world description: ") + e.what(), where);
  }
  return w;
}

}  // namespace vcar::synth
