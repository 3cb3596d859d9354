#pragma once
// COLMAP sparse models (cameras + images, .bin or .txt) to vcar cameras (conventions §2).
//
// COLMAP stores per image the world-to-camera pose (qw qx qy qz, tx ty tz) in the OpenCV frame,
// and pixel centres at +0.5, exactly our convention: R_w = rot(q / |q|), t_w = t, cx and cy as
// given. Only undistorted pinhole models are accepted (SIMPLE_PINHOLE f cx cy, PINHOLE fx fy cx
// cy); any model with distortion is an error naming the camera id and model (undistort first,
// e.g. `colmap image_undistorter`). Camera::name is the image name; cameras are ordered by name.
// Points (points3D, 2D observations) are not read. Every size read from a .bin file is checked
// against the file size before anything is allocated.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/atomic_file.hpp"

namespace vcar::io {

namespace detail {

struct ColmapModel { int id; const char* name; int num_params; };
inline constexpr std::array<ColmapModel, 12> colmap_models = {{
    {0, "SIMPLE_PINHOLE", 3}, {1, "PINHOLE", 4}, {2, "SIMPLE_RADIAL", 4}, {3, "RADIAL", 5},
    {4, "OPENCV", 8}, {5, "OPENCV_FISHEYE", 8}, {6, "FULL_OPENCV", 12}, {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4}, {9, "RADIAL_FISHEYE", 5}, {10, "THIN_PRISM_FISHEYE", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16}}};

struct ColmapCamera { int width = 0, height = 0; float fx = 0, fy = 0, cx = 0, cy = 0; };

// Intrinsics of a pinhole model; other models are rejected (they need undistortion).
inline ColmapCamera colmap_intrinsics(std::int64_t id, const ColmapModel& m, std::uint64_t w,
                                      std::uint64_t h, const std::vector<double>& p,
                                      const std::string& where) {
  const std::string cam = "camera " + std::to_string(id);
  if (m.id != 0 && m.id != 1)
    throw Error(cam + " uses model " + m.name + ": lens distortion is not supported, undistortion "
                "is required (e.g. colmap image_undistorter); accepted models: PINHOLE, SIMPLE_PINHOLE", where);
  if (w == 0 || h == 0 || w > (1u << 30) || h > (1u << 30))
    throw Error(cam + " has an invalid image size " + std::to_string(w) + " x " + std::to_string(h), where);
  ColmapCamera c;
  c.width = static_cast<int>(w);
  c.height = static_cast<int>(h);
  if (m.id == 0) { c.fx = c.fy = static_cast<float>(p[0]); c.cx = static_cast<float>(p[1]); c.cy = static_cast<float>(p[2]); }
  else { c.fx = static_cast<float>(p[0]); c.fy = static_cast<float>(p[1]); c.cx = static_cast<float>(p[2]); c.cy = static_cast<float>(p[3]); }
  if (!(c.fx > 0 && c.fy > 0) || !std::isfinite(c.fx) || !std::isfinite(c.fy) || !std::isfinite(c.cx) || !std::isfinite(c.cy))
    throw Error(cam + " has invalid intrinsics (focal lengths must be positive and finite)", where);
  return c;
}

inline const ColmapModel* colmap_model_by_id(std::int64_t id) {
  for (const auto& m : colmap_models) if (m.id == id) return &m;
  return nullptr;
}
inline const ColmapModel* colmap_model_by_name(std::string_view name) {
  for (const auto& m : colmap_models) if (name == m.name) return &m;
  return nullptr;
}

struct ColmapImage {
  std::string name;
  std::int64_t camera_id = 0;
  double q[4] = {1, 0, 0, 0};  // qw qx qy qz, world-to-camera
  double t[3] = {0, 0, 0};
};

// Little-endian reader that knows how many bytes are left.
class BinReader {
public:
  explicit BinReader(const std::filesystem::path& p) : where_(p.string()), in_(p, std::ios::binary) {
    std::error_code ec;
    size_ = std::filesystem::file_size(p, ec);
    if (ec || !in_) throw Error("cannot open file", where_);
  }
  std::uint64_t left() const { return size_ - pos_; }
  const std::string& where() const { return where_; }
  void need(std::uint64_t n, const std::string& what) {
    if (n > left())
      throw Error("truncated at byte " + std::to_string(pos_) + " while reading " + what, where_);
  }
  template <class T>
  T get(const std::string& what) {
    need(sizeof(T), what);
    T v;
    in_.read(reinterpret_cast<char*>(&v), sizeof(T));
    pos_ += sizeof(T);
    return v;  // COLMAP writes little-endian; x86-64 and ARM hosts are little-endian
  }
  void skip(std::uint64_t n, const std::string& what) {
    need(n, what);
    in_.seekg(static_cast<std::streamoff>(n), std::ios::cur);
    pos_ += n;
  }
  std::string cstring(const std::string& what) {
    std::string s;
    for (;;) {
      const char c = get<char>(what);
      if (c == '\0') return s;
      s.push_back(c);
    }
  }

private:
  std::string where_;
  std::ifstream in_;
  std::uint64_t size_ = 0, pos_ = 0;
};

inline std::map<std::int64_t, ColmapCamera> read_colmap_cameras_bin(const std::filesystem::path& p) {
  BinReader r(p);
  const auto n = r.get<std::uint64_t>("the number of cameras");
  if (n > r.left() / 24) throw Error("declares " + std::to_string(n) + " cameras, more than the file holds", r.where());
  std::map<std::int64_t, ColmapCamera> out;
  for (std::uint64_t k = 0; k < n; ++k) {
    const std::string what = "camera " + std::to_string(k);
    const auto id = r.get<std::int32_t>(what);
    const auto model = r.get<std::int32_t>(what);
    const auto w = r.get<std::uint64_t>(what);
    const auto h = r.get<std::uint64_t>(what);
    const ColmapModel* m = colmap_model_by_id(model);
    if (!m) throw Error("camera " + std::to_string(id) + " has unknown model id " + std::to_string(model), r.where());
    std::vector<double> params(static_cast<std::size_t>(m->num_params));
    for (auto& v : params) v = r.get<double>(what);
    if (!out.emplace(id, colmap_intrinsics(id, *m, w, h, params, r.where())).second)
      throw Error("duplicate camera id " + std::to_string(id), r.where());
  }
  return out;
}

inline std::vector<ColmapImage> read_colmap_images_bin(const std::filesystem::path& p) {
  BinReader r(p);
  const auto n = r.get<std::uint64_t>("the number of images");
  if (n > r.left() / 73) throw Error("declares " + std::to_string(n) + " images, more than the file holds", r.where());
  std::vector<ColmapImage> out(static_cast<std::size_t>(n));
  for (std::uint64_t k = 0; k < n; ++k) {
    const std::string what = "image " + std::to_string(k);
    ColmapImage& im = out[static_cast<std::size_t>(k)];
    r.get<std::int32_t>(what);  // image id: unused, images are named
    for (double& v : im.q) v = r.get<double>(what);
    for (double& v : im.t) v = r.get<double>(what);
    im.camera_id = r.get<std::int32_t>(what);
    im.name = r.cstring(what);
    const auto points = r.get<std::uint64_t>(what);
    if (points > r.left() / 24) throw Error("image '" + im.name + "' declares more 2D points than the file holds", r.where());
    r.skip(points * 24, what);  // x, y (double), point3D id (int64)
  }
  return out;
}

inline bool colmap_data_line(const std::string& line) {
  const auto i = line.find_first_not_of(" \t\r");
  return i != std::string::npos && line[i] != '#';
}

inline std::map<std::int64_t, ColmapCamera> read_colmap_cameras_txt(const std::filesystem::path& p) {
  const std::string where = p.string();
  std::ifstream in(p);
  if (!in) throw Error("cannot open file", where);
  std::map<std::int64_t, ColmapCamera> out;
  std::string line;
  for (std::size_t ln = 1; std::getline(in, line); ++ln) {
    if (!colmap_data_line(line)) continue;
    std::istringstream s(line);
    std::int64_t id;
    std::string model;
    std::uint64_t w, h;
    if (!(s >> id >> model >> w >> h)) throw Error("malformed camera line " + std::to_string(ln), where);
    const ColmapModel* m = colmap_model_by_name(model);
    if (!m) throw Error("camera " + std::to_string(id) + " has unknown model '" + model + "'", where);
    std::vector<double> params;
    for (double v; s >> v;) params.push_back(v);
    if (m->id <= 1 && params.size() != static_cast<std::size_t>(m->num_params))
      throw Error("camera " + std::to_string(id) + " (" + model + ") needs " + std::to_string(m->num_params) +
                  " parameters, line " + std::to_string(ln) + " has " + std::to_string(params.size()), where);
    if (!out.emplace(id, colmap_intrinsics(id, *m, w, h, params, where)).second)
      throw Error("duplicate camera id " + std::to_string(id), where);
  }
  return out;
}

inline std::vector<ColmapImage> read_colmap_images_txt(const std::filesystem::path& p) {
  const std::string where = p.string();
  std::ifstream in(p);
  if (!in) throw Error("cannot open file", where);
  std::vector<ColmapImage> out;
  std::string line, points;
  for (std::size_t ln = 1; std::getline(in, line); ++ln) {
    if (!colmap_data_line(line)) continue;
    std::istringstream s(line);
    ColmapImage im;
    std::int64_t image_id;
    if (!(s >> image_id >> im.q[0] >> im.q[1] >> im.q[2] >> im.q[3] >> im.t[0] >> im.t[1] >> im.t[2] >> im.camera_id >> im.name))
      throw Error("malformed image line " + std::to_string(ln), where);
    out.push_back(im);
    if (std::getline(in, points)) ++ln;  // the 2D points line (may be empty): not used
  }
  return out;
}

// The cameras of a COLMAP model, .bin preferred over .txt for each of the two files.
inline std::filesystem::path colmap_file(const std::filesystem::path& dir, const char* stem) {
  for (const char* ext : {".bin", ".txt"}) {
    const auto p = dir / (std::string(stem) + ext);
    if (std::filesystem::is_regular_file(p)) return p;
  }
  throw Error(std::string("no ") + stem + ".bin or " + stem + ".txt (not a COLMAP sparse model folder)", dir.string());
}

inline std::vector<Camera> read_colmap_impl(const std::filesystem::path& sparse_dir,
                                            const std::filesystem::path* images_dir) {
  const auto cam_file = colmap_file(sparse_dir, "cameras");
  const auto img_file = colmap_file(sparse_dir, "images");
  const auto intr = cam_file.extension() == ".bin" ? read_colmap_cameras_bin(cam_file) : read_colmap_cameras_txt(cam_file);
  const auto images = img_file.extension() == ".bin" ? read_colmap_images_bin(img_file) : read_colmap_images_txt(img_file);
  const std::string where = img_file.string();
  std::vector<Camera> out;
  out.reserve(images.size());
  for (const auto& im : images) {
    const auto it = intr.find(im.camera_id);
    if (it == intr.end())
      throw Error("image '" + im.name + "' references camera id " + std::to_string(im.camera_id) +
                  ", which is not in " + cam_file.filename().string(), where);
    if (images_dir && !std::filesystem::exists(*images_dir / im.name))
      throw Error("image file " + (*images_dir / im.name).string() + " does not exist", where);
    const double qn = std::sqrt(im.q[0] * im.q[0] + im.q[1] * im.q[1] + im.q[2] * im.q[2] + im.q[3] * im.q[3]);
    if (!(qn > 0) || !std::isfinite(qn) || !std::isfinite(im.t[0] + im.t[1] + im.t[2]))
      throw Error("image '" + im.name + "' has a zero or non-finite pose", where);
    Camera c;
    c.name = im.name;
    const auto& k = it->second;
    c.set_intrinsics({k.width, k.height, k.fx, k.fy, k.cx, k.cy});
    c.R_w = Eigen::Quaterniond(im.q[0], im.q[1], im.q[2], im.q[3]).normalized().toRotationMatrix().cast<float>();
    c.t_w = Eigen::Vector3d(im.t[0], im.t[1], im.t[2]).cast<float>();
    out.push_back(std::move(c));
  }
  std::stable_sort(out.begin(), out.end(), [](const Camera& a, const Camera& b) { return a.name < b.name; });
  for (std::size_t k = 1; k < out.size(); ++k)
    if (out[k].name == out[k - 1].name) throw Error("image name '" + out[k].name + "' appears twice", where);
  return out;
}

inline std::string float_text(double v) {
  char buf[40];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}
inline std::string float_text(float v) {
  char buf[40];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

}  // namespace detail

// Reads `sparse_dir`/{cameras,images}.{bin,txt}; cameras ordered by image name.
inline std::vector<Camera> read_colmap(const std::filesystem::path& sparse_dir) {
  return detail::read_colmap_impl(sparse_dir, nullptr);
}

// As above, and every image must exist as `images_dir`/name (error naming the first missing one).
inline std::vector<Camera> read_colmap(const std::filesystem::path& sparse_dir,
                                       const std::filesystem::path& images_dir) {
  return detail::read_colmap_impl(sparse_dir, &images_dir);
}

// Writes cameras.txt (one PINHOLE camera per image), images.txt and an empty points3D.txt into
// `sparse_dir` (created when missing), each atomically.
inline void write_colmap_text(const std::filesystem::path& sparse_dir, const std::vector<Camera>& cams) {
  for (const auto& c : cams) {
    c.validate();
    if (c.name.empty() || c.name.find_first_of(" \t\r\n") != std::string::npos)
      throw Error("COLMAP text needs image names without spaces", "camera '" + c.name + "'");
  }
  std::error_code ec;
  std::filesystem::create_directories(sparse_dir, ec);
  if (ec) throw Error("cannot create folder: " + ec.message(), sparse_dir.string());
  using detail::float_text;
  atomic_write(sparse_dir / "cameras.txt", [&](std::ostream& out) {
    out << "# Camera list with one line of data per camera:\n"
        << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
        << "# Number of cameras: " << cams.size() << "\n";
    for (std::size_t k = 0; k < cams.size(); ++k) {
      const auto& c = cams[k];
      out << k + 1 << " PINHOLE " << c.width << " " << c.height << " " << float_text(c.fx) << " "
          << float_text(c.fy) << " " << float_text(c.cx) << " " << float_text(c.cy) << "\n";
    }
  });
  atomic_write(sparse_dir / "images.txt", [&](std::ostream& out) {
    out << "# Image list with two lines of data per image:\n"
        << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
        << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
        << "# Number of images: " << cams.size() << ", mean observations per image: 0\n";
    for (std::size_t k = 0; k < cams.size(); ++k) {
      const auto& c = cams[k];
      Eigen::Quaterniond q(c.R_w.cast<double>());
      q.normalize();
      if (q.w() < 0) q.coeffs() *= -1.0;  // canonical sign, as COLMAP writes it
      out << k + 1 << " " << float_text(q.w()) << " " << float_text(q.x()) << " " << float_text(q.y())
          << " " << float_text(q.z()) << " " << float_text(c.t_w.x()) << " " << float_text(c.t_w.y())
          << " " << float_text(c.t_w.z()) << " " << k + 1 << " " << c.name << "\n\n";
    }
  });
  atomic_write(sparse_dir / "points3D.txt", [&](std::ostream& out) {
    out << "# 3D point list with one line of data per point:\n"
        << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
        << "# Number of points: 0, mean track length: 0\n";
  });
}

}  // namespace vcar::io
