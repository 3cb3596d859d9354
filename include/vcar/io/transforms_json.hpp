#pragma once
// nerfstudio / Blender `transforms.json`: {camera_angle_x | fl_x fl_y cx cy w h, frames: [
// {file_path, transform_matrix}]}. Intrinsics may be top-level or per frame (the frame wins).
// transform_matrix is camera-to-world in OpenGL axes (x right, y up, z backward): flipping its
// y and z columns gives the OpenCV camera-to-world, then R_w = R^T, t_w = -R_w centre.
// fx = fl_x, or 0.5 w / tan(camera_angle_x / 2); fy = fl_y, or from camera_angle_y, or fx;
// cx, cy default to the image centre. Without w/h (Blender), the size is read from the image
// file_path (with or without a `.png` suffix) next to the json. Nonzero distortion (k1..k4,
// p1, p2) or a fisheye/equirectangular camera_model is an error: undistort first.
// `applied_transform` / `applied_scale` (nerfstudio's dataparser state) are not applied.
// Camera::name is the stem of file_path; cameras keep the file's order.
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <stb_image.h>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/json_file.hpp"

namespace vcar::io {

namespace detail {
inline std::vector<Camera> cameras_from_transforms(const nlohmann::json& j, const std::filesystem::path& path) {
  const std::string where = path.string();
  if (!j.is_object() || !j.contains("frames") || !j.at("frames").is_array())
    throw Error("transforms.json needs a 'frames' array", where);
  const auto& frames = j.at("frames");
  std::vector<Camera> out;
  out.reserve(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const auto& f = frames[k];
    std::string entry = "frame " + std::to_string(k);
    read_entry(entry, where, [&] {
      auto get = [&](const char* key) -> std::optional<double> {
        if (f.contains(key)) return f.at(key).get<double>();
        if (j.contains(key)) return j.at(key).get<double>();
        return std::nullopt;
      };
      if (!f.contains("file_path") || !f.contains("transform_matrix"))
        throw Error(entry + " needs 'file_path' and 'transform_matrix'", where);
      const std::string file_path = f.at("file_path").get<std::string>();
      entry += " ('" + file_path + "')";
      for (const char* key : {"k1", "k2", "k3", "k4", "p1", "p2"})
        if (auto v = get(key); v && *v != 0.0)
          throw Error(entry + ": distortion " + key + " = " + std::to_string(*v) +
                      " is not supported, undistort the images first", where);
      const std::string model = f.contains("camera_model") ? f.at("camera_model").get<std::string>()
                                : j.contains("camera_model") ? j.at("camera_model").get<std::string>() : "";
      if (model.find("FISHEYE") != std::string::npos || model.find("EQUIRECT") != std::string::npos)
        throw Error(entry + ": camera_model " + model + " is not a pinhole camera", where);
      Camera c;
      c.name = std::filesystem::path(file_path).stem().string();
      auto w = get("w"), h = get("h");
      if (!w || !h) {  // Blender: the size of the image itself
        const auto base = path.parent_path() / file_path;
        int iw = 0, ih = 0, n = 0;
        bool found = false;
        for (const auto& p : {base, std::filesystem::path(base.string() + ".png")})
          if (!found && std::filesystem::is_regular_file(p) && stbi_info(p.string().c_str(), &iw, &ih, &n)) found = true;
        if (!found) throw Error(entry + ": no 'w'/'h' and the image is not readable to get its size", where);
        w = iw;
        h = ih;
      }
      c.width = json_image_size(*w, "w");
      c.height = json_image_size(*h, "h");
      if (auto fl = get("fl_x")) c.fx = static_cast<float>(*fl);
      else if (auto ax = get("camera_angle_x")) c.fx = static_cast<float>(0.5 * *w / std::tan(0.5 * *ax));
      else throw Error(entry + ": no focal length (fl_x or camera_angle_x)", where);
      if (auto fl = get("fl_y")) c.fy = static_cast<float>(*fl);
      else if (auto ay = get("camera_angle_y")) c.fy = static_cast<float>(0.5 * *h / std::tan(0.5 * *ay));
      else c.fy = c.fx;
      c.cx = get("cx") ? static_cast<float>(*get("cx")) : 0.5f * static_cast<float>(c.width);
      c.cy = get("cy") ? static_cast<float>(*get("cy")) : 0.5f * static_cast<float>(c.height);
      const auto& T = f.at("transform_matrix");
      if (T.size() < 3) throw Error(entry + ": transform_matrix needs 3 or 4 rows of 4", where);
      Eigen::Matrix3f R_gl;
      Eigen::Vector3f centre;
      for (int r = 0; r < 3; ++r) {
        if (T[r].size() != 4) throw Error(entry + ": transform_matrix rows need 4 values", where);
        for (int q = 0; q < 3; ++q) R_gl(r, q) = T[r][q].get<float>();
        centre[r] = T[r][3].get<float>();
      }
      Eigen::Matrix3f R_c2w = R_gl;
      R_c2w.col(1) *= -1.f;  // OpenGL y up -> OpenCV y down
      R_c2w.col(2) *= -1.f;  // OpenGL z backward -> OpenCV z forward
      c.set_camera_to_world(R_c2w, centre);
      c.validate();
      out.push_back(std::move(c));
    });
  }
  return out;
}
}  // namespace detail

inline std::vector<Camera> read_transforms_json(const std::filesystem::path& path) {
  return detail::cameras_from_transforms(read_json_file(path), path);
}

// Intrinsics go top-level when every camera shares them, else into each frame.
inline void write_transforms_json(const std::filesystem::path& path, const std::vector<Camera>& cams) {
  auto intrinsics = [](const Camera& c) {
    return nlohmann::json{{"fl_x", json_float(c.fx)}, {"fl_y", json_float(c.fy)}, {"cx", json_float(c.cx)},
                          {"cy", json_float(c.cy)}, {"w", c.width}, {"h", c.height}};
  };
  bool shared = !cams.empty();
  for (const auto& c : cams) {
    c.validate();
    shared = shared && intrinsics(c) == intrinsics(cams.front());
  }
  nlohmann::json j = shared ? intrinsics(cams.front()) : nlohmann::json::object();
  j["camera_model"] = "PINHOLE";
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& c : cams) {
    Eigen::Matrix3f R_gl = c.R_w.transpose();
    R_gl.col(1) *= -1.f;
    R_gl.col(2) *= -1.f;
    const Eigen::Vector3f centre = c.position();
    nlohmann::json T = nlohmann::json::array();
    for (int r = 0; r < 3; ++r)
      T.push_back({json_float(R_gl(r, 0)), json_float(R_gl(r, 1)), json_float(R_gl(r, 2)), json_float(centre[r])});
    T.push_back({0.0, 0.0, 0.0, 1.0});
    nlohmann::json f = shared ? nlohmann::json::object() : intrinsics(c);
    f["file_path"] = c.name;
    f["transform_matrix"] = T;
    frames.push_back(std::move(f));
  }
  j["frames"] = frames;
  write_json_file(path, j);
}

}  // namespace vcar::io
