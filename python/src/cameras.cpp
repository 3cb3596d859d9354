// vcar.Camera (pinhole, OpenCV axes) with OpenGL / nerfstudio helpers, and the camera readers.
#include <filesystem>
#include <string>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "common.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/cameras_json.hpp"
#include "vcar/io/colmap.hpp"
#include "vcar/io/transforms_json.hpp"

namespace vcar::python {

namespace fs = std::filesystem;

std::vector<Camera> cameras_from(py::handle obj, const std::string& what) {
  if (py::isinstance<Camera>(obj)) throw Error("expected a list of vcar.Camera, got one camera", what);
  std::vector<Camera> out;
  std::size_t k = 0;
  for (py::handle c : py::iter(obj)) {
    if (!py::isinstance<Camera>(c))
      throw Error("[" + std::to_string(k) + "] is a " + py::str(py::type::of(c).attr("__name__")).cast<std::string>() +
                      ", expected vcar.Camera", what);
    out.push_back(c.cast<const Camera&>());
    out.back().validate();
    ++k;
  }
  return out;
}

py::list camera_list(const std::vector<Camera>& cams) {
  py::list l;
  for (const Camera& c : cams) l.append(py::cast(c));
  return l;
}

namespace {

// K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew: the model has none).
void set_intrinsics(Camera& c, py::handle K, int width, int height) {
  const std::string where = "camera '" + c.name + "': K";
  const auto k = real_array(K, {3, 3}, where);
  const double* a = k.data();
  if (a[1] != 0.0) throw Error("has skew K[0, 1] = " + std::to_string(a[1]) + "; vcar's pinhole model has none", where);
  if (a[3] != 0.0 || a[6] != 0.0 || a[7] != 0.0 || a[8] != 1.0)
    throw Error("must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]", where);
  if (!(a[0] > 0.0 && a[4] > 0.0)) throw Error("focal lengths K[0, 0] and K[1, 1] must be positive", where);
  if (width <= 0 || height <= 0)
    throw Error("image size must be positive, got " + std::to_string(width) + "x" + std::to_string(height),
                "camera '" + c.name + "'");
  c.width = width;
  c.height = height;
  c.fx = static_cast<float>(a[0]);
  c.fy = static_cast<float>(a[4]);
  c.cx = static_cast<float>(a[2]);
  c.cy = static_cast<float>(a[5]);
}

// A 4x4 (or 3x4) rigid transform: rotation block and translation column, in float like the model.
void read_rigid(py::handle M, const std::string& what, Eigen::Matrix3f& R, Eigen::Vector3f& t) {
  py::array a = as_array(M, what);
  if (a.ndim() != 2 || (a.shape(0) != 3 && a.shape(0) != 4) || a.shape(1) != 4)
    throw Error("must have shape (4, 4) or (3, 4), got " + shape_text(a), what);
  const bool rows3 = a.shape(0) == 3;
  const auto m = real_array(a, {rows3 ? 3 : 4, 4}, what);
  const double* p = m.data();
  if (!rows3 && (p[12] != 0.0 || p[13] != 0.0 || p[14] != 0.0 || p[15] != 1.0))
    throw Error("last row must be [0, 0, 0, 1]", what);
  for (int r = 0; r < 3; ++r) {
    for (int q = 0; q < 3; ++q) R(r, q) = static_cast<float>(p[r * 4 + q]);
    t[r] = static_cast<float>(p[r * 4 + 3]);
  }
}

py::array_t<float> matrix4(const Eigen::Matrix3f& R, const Eigen::Vector3f& t) {
  py::array_t<float> out({4, 4});
  float* p = out.mutable_data();
  for (int r = 0; r < 4; ++r)
    for (int q = 0; q < 4; ++q) p[r * 4 + q] = r < 3 ? (q < 3 ? R(r, q) : t[r]) : (q == 3 ? 1.f : 0.f);
  return out;
}

Camera from_world_to_camera(py::handle K, py::handle W, int width, int height, const std::string& name) {
  Camera c;
  c.name = name;
  set_intrinsics(c, K, width, height);
  read_rigid(W, "camera '" + name + "': world_to_camera", c.R_w, c.t_w);
  c.validate();
  return c;
}

// camera-to-world in OpenCV axes (opengl = false) or OpenGL / nerfstudio axes (x right, y up,
// z backward: columns 1 and 2 flipped), as io/transforms_json.hpp reads transform_matrix.
Camera from_camera_to_world(py::handle K, py::handle C2W, int width, int height, const std::string& name, bool opengl) {
  Camera c;
  c.name = name;
  set_intrinsics(c, K, width, height);
  Eigen::Matrix3f R;
  Eigen::Vector3f centre;
  read_rigid(C2W, "camera '" + name + "': camera_to_world", R, centre);
  if (opengl) {
    R.col(1) *= -1.f;
    R.col(2) *= -1.f;
  }
  c.set_camera_to_world(R, centre);
  c.validate();
  return c;
}

}  // namespace

void register_cameras(py::module_& m) {
  py::class_<Camera>(m, "Camera", R"doc(
A pinhole camera in OpenCV axes (x right, y down, z forward; conventions §2), as gsplat's
`viewmats` and `Ks`: world-to-camera W = [R | t] and K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]].

  Camera(K, world_to_camera, width, height, name="")       W: (4, 4) or (3, 4)
  Camera.from_camera_to_world(K, c2w, width, height, name)  OpenCV axes
  Camera.from_opengl(K, c2w, width, height, name)           OpenGL / nerfstudio / Blender axes
  Camera.look_at(eye, target, up, K, width, height, name)

Matrices are returned as float32 (the model's precision).)doc")
      .def(py::init(&from_world_to_camera), py::arg("K"), py::arg("world_to_camera"), py::arg("width"),
           py::arg("height"), py::arg("name") = "")
      .def_static(
          "from_camera_to_world",
          [](py::object K, py::object c2w, int w, int h, const std::string& name) {
            return from_camera_to_world(K, c2w, w, h, name, false);
          },
          py::arg("K"), py::arg("camera_to_world"), py::arg("width"), py::arg("height"), py::arg("name") = "")
      .def_static(
          "from_opengl",
          [](py::object K, py::object c2w, int w, int h, const std::string& name) {
            return from_camera_to_world(K, c2w, w, h, name, true);
          },
          py::arg("K"), py::arg("camera_to_world"), py::arg("width"), py::arg("height"), py::arg("name") = "",
          "From a camera-to-world matrix in OpenGL axes (x right, y up, z backward): nerfstudio's and\n"
          "Blender's transform_matrix (nerfstudio's dataparser transform and scale are not applied).")
      .def_static(
          "from_nerfstudio",
          [](py::object K, py::object c2w, int w, int h, const std::string& name) {
            return from_camera_to_world(K, c2w, w, h, name, true);
          },
          py::arg("K"), py::arg("camera_to_world"), py::arg("width"), py::arg("height"), py::arg("name") = "",
          "Same as from_opengl.")
      .def_static(
          "look_at",
          [](py::object eye, py::object target, py::object up, py::object K, int w, int h, const std::string& name) {
            Camera k;
            k.name = name;
            set_intrinsics(k, K, w, h);
            Camera c = Camera::look_at(vec3_from(eye, "eye"), vec3_from(target, "target"), vec3_from(up, "up"),
                                       k.intrinsics(), name);
            c.validate();
            return c;
          },
          py::arg("eye"), py::arg("target"), py::arg("up"), py::arg("K"), py::arg("width"), py::arg("height"),
          py::arg("name") = "")
      .def_readwrite("name", &Camera::name)
      .def_readwrite("width", &Camera::width)
      .def_readwrite("height", &Camera::height)
      .def_readwrite("fx", &Camera::fx)
      .def_readwrite("fy", &Camera::fy)
      .def_readwrite("cx", &Camera::cx)
      .def_readwrite("cy", &Camera::cy)
      .def_property_readonly("K",
                             [](const Camera& c) {
                               py::array_t<float> K({3, 3});
                               float* p = K.mutable_data();
                               const float v[9] = {c.fx, 0.f, c.cx, 0.f, c.fy, c.cy, 0.f, 0.f, 1.f};
                               std::copy(v, v + 9, p);
                               return K;
                             })
      .def_property_readonly("intrinsics",
                             [](const Camera& c) { return py::make_tuple(c.fx, c.fy, c.cx, c.cy); },
                             "(fx, fy, cx, cy) in pixels")
      .def_property_readonly("world_to_camera", [](const Camera& c) { return matrix4(c.R_w, c.t_w); })
      .def_property_readonly("camera_to_world",
                             [](const Camera& c) { return matrix4(c.R_w.transpose(), c.position()); },
                             "(4, 4) camera-to-world, OpenCV axes")
      .def("to_opengl",
           [](const Camera& c) {
             Eigen::Matrix3f R = c.R_w.transpose();
             R.col(1) *= -1.f;
             R.col(2) *= -1.f;
             return matrix4(R, c.position());
           },
           "(4, 4) camera-to-world in OpenGL / nerfstudio axes (a transforms.json transform_matrix).")
      .def_property_readonly("position", [](const Camera& c) { return vec3_array(c.position()); })
      .def_property_readonly("forward", [](const Camera& c) { return vec3_array(c.forward()); })
      .def_property_readonly("up", [](const Camera& c) { return vec3_array(c.up()); })
      .def_property_readonly("right", [](const Camera& c) { return vec3_array(c.right()); })
      .def(
          "project",
          [](const Camera& c, py::object points) {
            const auto p = real_array(points, {-1, 3}, "points");
            const py::ssize_t n = p.shape(0);
            py::array_t<float> out({n, py::ssize_t{3}});
            float* o = out.mutable_data();
            for (py::ssize_t i = 0; i < n; ++i) {
              const Eigen::Vector3f x(static_cast<float>(p.data()[i * 3]), static_cast<float>(p.data()[i * 3 + 1]),
                                      static_cast<float>(p.data()[i * 3 + 2]));
              const Eigen::Vector3f t = c.to_camera(x);
              o[i * 3] = c.fx * t.x() / t.z() + c.cx;
              o[i * 3 + 1] = c.fy * t.y() / t.z() + c.cy;
              o[i * 3 + 2] = t.z();
            }
            return out;
          },
          py::arg("points"),
          "(N, 3) world points -> (N, 3): pixel u, v (continuous, pixel (j, i) covers [j, j+1) x [i, i+1))\n"
          "and camera depth z (behind the camera when z <= 0).")
      .def("validate", [](const Camera& c) { c.validate(); })
      .def("copy", [](const Camera& c) { return c; })
      .def("__eq__",
           [](const Camera& a, py::object other) {
             if (!py::isinstance<Camera>(other)) return false;
             const Camera& b = other.cast<const Camera&>();
             return a.name == b.name && a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
                    a.cx == b.cx && a.cy == b.cy && a.R_w == b.R_w && a.t_w == b.t_w;
           })
      .def("__repr__", [](const Camera& c) {
        const Eigen::Vector3f p = c.position();
        return "<vcar.Camera '" + c.name + "' " + std::to_string(c.width) + "x" + std::to_string(c.height) +
               " fx=" + std::to_string(c.fx) + " at (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
               std::to_string(p.z()) + ")>";
      });

  m.def(
      "read_cameras",
      [](const fs::path& path) {
        std::vector<Camera> cams;
        {
          py::gil_scoped_release nogil;
          cams = io::read_cameras(path);
        }
        return camera_list(cams);
      },
      py::arg("path"),
      "Cameras of a COLMAP model (folder, sparse/0), an Inria cameras.json or a nerfstudio/Blender\n"
      "transforms.json, as vcar.Camera in the file's order, named by their image names.");
  m.def(
      "write_cameras_json", [](const fs::path& p, py::object cams) { io::write_cameras_json(p, cameras_from(cams)); },
      py::arg("path"), py::arg("cameras"), "Inria cameras.json.");
  m.def(
      "write_transforms_json",
      [](const fs::path& p, py::object cams) { io::write_transforms_json(p, cameras_from(cams)); }, py::arg("path"),
      py::arg("cameras"), "nerfstudio transforms.json (OpenGL camera-to-world).");
  m.def(
      "write_colmap_text", [](const fs::path& p, py::object cams) { io::write_colmap_text(p, cameras_from(cams)); },
      py::arg("folder"), py::arg("cameras"), "COLMAP text model (cameras.txt, images.txt, empty points3D.txt).");
}

}  // namespace vcar::python
