#pragma once
// read_cameras: one entry point for every camera format, detected from the path.
//   a folder with cameras.{bin,txt}, or its sparse/0 or sparse/ subfolder -> COLMAP;
//   a folder with transforms.json or cameras.json -> that file;
//   a .json file: an array -> Inria cameras.json, an object with `frames` -> transforms.json;
//   a COLMAP cameras.* / images.* file -> the model in its folder.
// From bytes in memory (a browser's upload): the two JSON formats, told apart by content.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/cameras_json.hpp"
#include "vcar/io/colmap.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/transforms_json.hpp"

namespace vcar::io {

inline std::vector<Camera> read_cameras(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  const std::string where = path.string();
  auto is_colmap = [](const fs::path& d) {
    return fs::is_regular_file(d / "cameras.bin") || fs::is_regular_file(d / "cameras.txt");
  };
  if (fs::is_directory(path)) {
    for (const auto& d : {path, path / "sparse" / "0", path / "sparse"})
      if (is_colmap(d)) return read_colmap(d);
    if (fs::is_regular_file(path / "transforms.json")) return read_transforms_json(path / "transforms.json");
    if (fs::is_regular_file(path / "cameras.json")) return read_cameras_json(path / "cameras.json");
    throw Error("no cameras found: expected COLMAP cameras.{bin,txt} (here, in sparse/0 or sparse), "
                "transforms.json or cameras.json", where);
  }
  if (!fs::is_regular_file(path)) throw Error("no such file or folder", where);
  const std::string stem = path.stem().string(), ext = path.extension().string();
  if ((stem == "cameras" || stem == "images") && (ext == ".bin" || ext == ".txt"))
    return read_colmap(path.parent_path());
  if (ext == ".json") {
    const nlohmann::json j = read_json_file(path);
    if (j.is_array()) return detail::cameras_from_inria_json(j, where);
    if (j.is_object() && j.contains("frames")) return detail::cameras_from_transforms(j, path);
    throw Error("JSON is neither an Inria cameras.json (array) nor a transforms.json (frames)", where);
  }
  throw Error("unknown camera format (expected a COLMAP folder, cameras.json or transforms.json)", where);
}

// The cameras of a JSON file's bytes in memory: an array -> Inria cameras.json, an object with
// `frames` -> transforms.json. `name` stands for the file in errors. (COLMAP models are two
// files: read them from a folder.)
inline std::vector<Camera> read_cameras(std::span<const std::uint8_t> bytes, const std::string& name) {
  const nlohmann::json j = parse_json_bytes(bytes, name);
  if (j.is_array()) return detail::cameras_from_inria_json(j, name);
  if (j.is_object() && j.contains("frames")) return detail::cameras_from_transforms(j, name);
  throw Error("JSON is neither an Inria cameras.json (array) nor a transforms.json (frames)", name);
}

}  // namespace vcar::io
