#pragma once
// Inria 3DGS `cameras.json`: an array of {id, img_name, width, height, position[3],
// rotation[3][3], fx, fy}. `rotation` lists the rows of the camera-to-world rotation and
// `position` is the camera centre, so R_w = rotation^T and t_w = -R_w position (conventions §2).
// The principal point is the image centre, unless the entry has `cx` / `cy` (a vcar extension,
// written only when the principal point is off-centre, so Inria files stay Inria files).
// Cameras keep the file's order.
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/json_file.hpp"

namespace vcar::io {

namespace detail {
inline std::vector<Camera> cameras_from_inria_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array()) throw Error("cameras.json must hold an array of cameras", where);
  std::vector<Camera> out;
  out.reserve(j.size());
  for (std::size_t k = 0; k < j.size(); ++k) {
    const auto& e = j[k];
    const std::string entry = "entry " + std::to_string(k);
    read_entry(entry, where, [&] {
      for (const char* key : {"img_name", "width", "height", "position", "rotation", "fx", "fy"})
        if (!e.contains(key)) throw Error(entry + " has no '" + key + "'", where);
      Camera c;
      c.name = e.at("img_name").get<std::string>();
      c.width = json_image_size(e.at("width"), "width");
      c.height = json_image_size(e.at("height"), "height");
      c.fx = e.at("fx").get<float>();
      c.fy = e.at("fy").get<float>();
      c.cx = e.contains("cx") ? e.at("cx").get<float>() : 0.5f * static_cast<float>(c.width);
      c.cy = e.contains("cy") ? e.at("cy").get<float>() : 0.5f * static_cast<float>(c.height);
      const auto& pos = e.at("position");
      const auto& rot = e.at("rotation");
      if (pos.size() != 3 || rot.size() != 3) throw Error(entry + ": position needs 3 values, rotation 3 rows", where);
      Eigen::Matrix3f R_c2w;
      Eigen::Vector3f centre;
      for (int r = 0; r < 3; ++r) {
        if (rot[r].size() != 3) throw Error(entry + ": rotation rows need 3 values", where);
        centre[r] = pos[r].get<float>();
        for (int c2 = 0; c2 < 3; ++c2) R_c2w(r, c2) = rot[r][c2].get<float>();
      }
      c.set_camera_to_world(R_c2w, centre);
      c.validate();
      out.push_back(std::move(c));
    });
  }
  return out;
}
}  // namespace detail

inline std::vector<Camera> read_cameras_json(const std::filesystem::path& path) {
  return detail::cameras_from_inria_json(read_json_file(path), path.string());
}

inline void write_cameras_json(const std::filesystem::path& path, const std::vector<Camera>& cams) {
  nlohmann::json j = nlohmann::json::array();
  for (std::size_t k = 0; k < cams.size(); ++k) {
    const Camera& c = cams[k];
    c.validate();
    const Eigen::Matrix3f R_c2w = c.R_w.transpose();
    const Eigen::Vector3f centre = c.position();
    nlohmann::json e;
    e["id"] = k;
    e["img_name"] = c.name;
    e["width"] = c.width;
    e["height"] = c.height;
    e["position"] = {json_float(centre.x()), json_float(centre.y()), json_float(centre.z())};
    nlohmann::json rot = nlohmann::json::array();
    for (int r = 0; r < 3; ++r) rot.push_back({json_float(R_c2w(r, 0)), json_float(R_c2w(r, 1)), json_float(R_c2w(r, 2))});
    e["rotation"] = rot;
    e["fy"] = json_float(c.fy);
    e["fx"] = json_float(c.fx);
    if (c.cx != 0.5f * static_cast<float>(c.width) || c.cy != 0.5f * static_cast<float>(c.height)) {
      e["cx"] = json_float(c.cx);
      e["cy"] = json_float(c.cy);
    }
    j.push_back(std::move(e));
  }
  write_json_file(path, j);
}

}  // namespace vcar::io
