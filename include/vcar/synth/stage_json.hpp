#pragma once
// The stage file (JSON) of `vcar synth --stage`: the objects of a synth/stage.hpp Stage, the
// target, the floor and, optionally, the rig. Example: examples/stages/three_objects.json;
// format: docs/cli.md ("Stage files").
//
//   {"objects": [{"name": "biker", "file": "biker.spz", "up": "-y", "yaw": 0, "height": 1.75,
//                 "position": [0, 0], "id": 1}, ...],
//    "target": "biker", "floor": {"half_size": 4, "gaussians": 100000},
//    "rig": "forward", "width": 640, "height": 480, "views": 20}
//
// Per object: "name", "file" and one of "height" / "width" / "scale" are required; "up"
// (default "+z"), "yaw" (degrees, default 0), "position" (default [0, 0]) and "id" (default its
// place, 1, 2, ...) are optional. A relative "file" is relative to the stage file's folder.
// Everything else is optional; "comment" (any value) is allowed anywhere and ignored. Unknown
// keys, a missing file, a bad up axis, a size that is not positive or given twice are errors
// naming the stage file and the field (vcar::Error).
#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "vcar/core/error.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/synth/stage.hpp"

namespace vcar::synth {

// What a stage file holds: the stage and the rig settings it gives (0 / empty: not given).
struct StageFile {
  Stage stage;
  std::string rig;          // "forward", "orbit", "sparse" or "hemisphere"
  int width = 0, height = 0;
  int views = 0;
};

namespace detail {

inline void check_keys(const nlohmann::json& j, std::initializer_list<const char*> known, const std::string& where) {
  if (!j.is_object()) throw Error("expected a JSON object", where);
  for (const auto& item : j.items()) {
    bool ok = item.key() == "comment";
    for (const char* k : known) ok = ok || item.key() == k;
    if (!ok) {
      std::string list;
      for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
      throw Error("unknown key \"" + item.key() + "\" (known: " + list + ")", where);
    }
  }
}

inline float stage_number(const nlohmann::json& v, const std::string& where) {
  if (!v.is_number()) throw Error("expected a number", where);
  const double x = v.get<double>();
  if (!std::isfinite(x) || std::abs(x) > 1e30) throw Error("expected a finite number", where);
  return static_cast<float>(x);
}

inline float positive_number(const nlohmann::json& v, const std::string& where) {
  const float x = stage_number(v, where);
  if (!(x > 0.f)) throw Error("must be > 0, got " + v.dump(), where);
  return x;
}

inline int positive_integer(const nlohmann::json& v, long long max, const std::string& where) {
  if (!v.is_number_integer() || v.get<long long>() < 1 || v.get<long long>() > max)
    throw Error("expected a whole number from 1 to " + std::to_string(max) + ", got " + v.dump(), where);
  return static_cast<int>(v.get<long long>());
}

inline std::string stage_string(const nlohmann::json& v, const std::string& where) {
  if (!v.is_string()) throw Error("expected a string, got " + v.dump(), where);
  return v.get<std::string>();
}

inline StageObject parse_stage_object(const nlohmann::json& j, const std::filesystem::path& folder,
                                      const std::string& where) {
  if (!j.is_object()) throw Error("expected a JSON object", where);
  StageObject o;
  if (!j.contains("name")) throw Error("missing \"name\"", where);
  o.name = stage_string(j["name"], where + ".name");
  if (!valid_stage_name(o.name)) throw Error("name '" + o.name + "' must be letters, digits, _ . - (it names a folder)", where + ".name");
  const std::string at = where + " ('" + o.name + "')";
  check_keys(j, {"name", "file", "up", "yaw", "height", "width", "scale", "position", "id"}, at);
  if (!j.contains("file")) throw Error("missing \"file\"", at);
  const std::filesystem::path file = stage_string(j["file"], at + ".file");
  o.file = file.is_relative() ? folder / file : file;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(o.file, ec))
    throw Error("no such file: " + o.file.string() + (file.is_relative() ? " (relative to the stage file's folder)" : ""), at + ".file");
  if (j.contains("up")) {
    o.up = stage_string(j["up"], at + ".up");
    up_rotation(o.up, at + ".up");  // refuses a bad axis here, naming the field
  }
  if (j.contains("yaw")) o.yaw_deg = stage_number(j["yaw"], at + ".yaw");
  int sizes = 0;
  for (auto [key, field] : {std::pair{"height", &o.height}, {"width", &o.width}, {"scale", &o.scale}}) {
    if (!j.contains(key)) continue;
    ++sizes;
    *field = positive_number(j[key], at + "." + key);
  }
  if (sizes != 1) throw Error("give exactly one size: \"height\", \"width\" or \"scale\"", at);
  if (j.contains("position")) {
    const auto& p = j["position"];
    if (!p.is_array() || p.size() != 2) throw Error("expected [x, y]", at + ".position");
    o.position = {stage_number(p[0], at + ".position[0]"), stage_number(p[1], at + ".position[1]")};
  }
  if (j.contains("id")) o.object_id = positive_integer(j["id"], 1 << 30, at + ".id");
  return o;
}

}  // namespace detail

inline StageFile read_stage_file(const std::filesystem::path& path) {
  const std::string file = path.string();
  const nlohmann::json j = io::read_json_file(path);
  detail::check_keys(j, {"objects", "target", "floor", "rig", "width", "height", "views"}, file);
  StageFile sf;
  if (!j.contains("objects") || !j["objects"].is_array() || j["objects"].empty())
    throw Error("\"objects\" must be a non-empty array", file + ": objects");
  const std::filesystem::path folder = path.parent_path();
  std::set<std::string> names;
  std::set<int> ids;
  for (std::size_t k = 0; k < j["objects"].size(); ++k) {
    const std::string where = file + ": objects[" + std::to_string(k) + "]";
    StageObject o = detail::parse_stage_object(j["objects"][k], folder, where);
    if (!names.insert(o.name).second) throw Error("two objects are named '" + o.name + "'", where + ".name");
    const int id = o.object_id != 0 ? o.object_id : static_cast<int>(k) + 1;
    if (!ids.insert(id).second) throw Error("two objects have id " + std::to_string(id), where + ".id");
    sf.stage.objects.push_back(std::move(o));
  }
  if (j.contains("target")) {
    sf.stage.target = detail::stage_string(j["target"], file + ": target");
    if (!names.count(sf.stage.target)) throw Error("no object is named '" + sf.stage.target + "'", file + ": target");
  }
  if (j.contains("floor")) {
    const auto& f = j["floor"];
    detail::check_keys(f, {"half_size", "gaussians"}, file + ": floor");
    if (f.contains("half_size")) sf.stage.floor_half_size = detail::positive_number(f["half_size"], file + ": floor.half_size");
    if (f.contains("gaussians"))
      sf.stage.floor_gaussians = static_cast<std::size_t>(detail::positive_integer(f["gaussians"], 50000000, file + ": floor.gaussians"));
  }
  if (j.contains("rig")) {
    sf.rig = detail::stage_string(j["rig"], file + ": rig");
    if (sf.rig != "forward" && sf.rig != "orbit" && sf.rig != "sparse" && sf.rig != "hemisphere")
      throw Error("unknown rig '" + sf.rig + "' (forward, orbit, sparse, hemisphere)", file + ": rig");
  }
  if (j.contains("width")) sf.width = detail::positive_integer(j["width"], 1 << 15, file + ": width");
  if (j.contains("height")) sf.height = detail::positive_integer(j["height"], 1 << 15, file + ": height");
  if ((sf.width > 0) != (sf.height > 0)) throw Error("give both \"width\" and \"height\", or neither", file);
  if (j.contains("views")) sf.views = detail::positive_integer(j["views"], 100000, file + ": views");
  return sf;
}

}  // namespace vcar::synth
