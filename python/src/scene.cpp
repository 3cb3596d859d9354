// vcar.Scene, the scene readers and writers, images and masks, and vcar.render (the CPU renderer).
#include <filesystem>
#include <string>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "common.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/scene_file.hpp"

namespace vcar::python {

namespace fs = std::filesystem;

// ---- Scene mechanics ------------------------------------------------------------------------

std::shared_ptr<Scene> Scene::from_cpp(GaussianScene&& s) {
  auto sc = std::make_shared<Scene>();
  sc->g = std::move(s);
  const auto n = static_cast<py::ssize_t>(sc->g.size());
  sc->means = py::array_t<float, py::array::c_style>({n, py::ssize_t{3}});
  sc->quats = py::array_t<float, py::array::c_style>({n, py::ssize_t{4}});
  sc->log_scales = py::array_t<float, py::array::c_style>({n, py::ssize_t{3}});
  float *m = sc->means.mutable_data(), *q = sc->quats.mutable_data(), *l = sc->log_scales.mutable_data();
  const GaussianScene& g = sc->g;
  for (py::ssize_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) { m[i * 3 + d] = g.mean[d][i]; l[i * 3 + d] = g.log_scale[d][i]; }
    for (int c = 0; c < 4; ++c) q[i * 4 + c] = g.rotation[c][i];
  }
  return sc;
}

void Scene::sync() {
  const std::size_t n = g.size();
  const float *m = means.data(), *q = quats.data(), *l = log_scales.data();
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) { g.mean[d][i] = m[i * 3 + d]; g.log_scale[d][i] = l[i * 3 + d]; }
    for (int c = 0; c < 4; ++c) g.rotation[c][i] = q[i * 4 + c];
  }
}

SceneUse::SceneUse(Scene& s, bool validate) : s_(&s), lock_(s.mutex, std::defer_lock) {
  if (!lock_.try_lock()) {
    py::gil_scoped_release nogil;
    lock_.lock();
  }
  s.sync();
  if (validate) s.g.validate("scene");
}

Scene& scene_from(py::handle obj) {
  if (!py::isinstance<Scene>(obj))
    throw Error("expected a vcar.Scene, got " + py::str(py::type::of(obj).attr("__name__")).cast<std::string>(), "scene");
  return obj.cast<Scene&>();
}

namespace {

// A Python UserWarning, once per file read: "<path>: N Gaussians had infinite opacity logits: ...".
void warn_infinite_opacities(const fs::path& path, const InfiniteOpacities& infinite) {
  const std::string text = path.string() + ": " + infinite.message();
  if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 1) != 0) throw py::error_already_set();
}

// A view of a vector owned by the Scene `self` (kept alive by the view).
py::array_t<float> view(py::handle self, std::vector<float>& v, std::vector<py::ssize_t> shape) {
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t s = sizeof(float);
  for (std::size_t d = shape.size(); d-- > 0;) { strides[d] = s; s *= shape[d]; }
  return py::array_t<float>(shape, strides, v.data(), self);
}

void copy_into(std::vector<float>& dst, const py::array_t<float, py::array::c_style>& src) {
  std::copy(src.data(), src.data() + src.size(), dst.begin());
}

int sh_degree_of(py::ssize_t coeffs) {
  for (int deg = 0; deg <= 3; ++deg)
    if ((deg + 1) * (deg + 1) == coeffs) return deg;
  throw Error("must have K = 1, 4, 9 or 16 coefficients per channel (SH degree 0-3), got K = " +
                  std::to_string(coeffs), "sh");
}

// The geometry arrays, checked: float32, (N, 3) / (N, 4), finite, no zero quaternion.
py::array_t<float, py::array::c_style> geometry(py::handle obj, py::ssize_t n, py::ssize_t cols, const char* what) {
  auto a = float32_array(obj, {n, cols}, what);
  check_finite(a.data(), static_cast<std::size_t>(a.shape(0)), static_cast<std::size_t>(cols), what);
  return a;
}

void check_quats(const py::array_t<float, py::array::c_style>& q) {
  const float* p = q.data();
  for (py::ssize_t i = 0; i < q.shape(0); ++i) {
    const float qq = p[i * 4] * p[i * 4] + p[i * 4 + 1] * p[i * 4 + 1] + p[i * 4 + 2] * p[i * 4 + 2] + p[i * 4 + 3] * p[i * 4 + 3];
    if (!(qq > 0.f)) throw Error("row " + std::to_string(i) + " is a zero quaternion", "quats");
  }
}

std::shared_ptr<Scene> make_scene(py::object means, py::object quats, py::object log_scales, py::object opacities,
                                  py::object sh, py::object extra, py::object extra_names) {
  auto m = geometry(means, -1, 3, "means");
  const py::ssize_t n = m.shape(0);
  auto q = geometry(quats, n, 4, "quats");
  check_quats(q);
  auto l = geometry(log_scales, n, 3, "log_scales");
  auto o = float32_array(opacities, {n}, "opacities");
  check_finite(o.data(), static_cast<std::size_t>(n), 1, "opacities");
  int degree = 0;
  std::optional<py::array_t<float, py::array::c_style>> s;
  if (!sh.is_none()) {
    s = float32_array(sh, {n, -1, 3}, "sh");
    degree = sh_degree_of(s->shape(1));
    check_finite(s->data(), static_cast<std::size_t>(n), static_cast<std::size_t>(s->shape(1) * 3), "sh");
  }
  std::vector<std::string> names;
  if (!extra_names.is_none()) names = extra_names.cast<std::vector<std::string>>();
  std::optional<py::array_t<float, py::array::c_style>> e;
  if (!extra.is_none() || !names.empty()) {
    if (extra.is_none()) throw Error("extra_names given without extra", "extra");
    e = float32_array(extra, {n, static_cast<py::ssize_t>(names.size())}, "extra");
  }

  auto sc = std::make_shared<Scene>();
  sc->g.extra_names = names;
  sc->g.resize(static_cast<std::size_t>(n), degree);
  copy_into(sc->g.opacity_logit, o);
  if (s) copy_into(sc->g.sh, *s);
  if (e) copy_into(sc->g.extra, *e);
  sc->means = m;
  sc->quats = q;
  sc->log_scales = l;
  sc->sync();
  sc->g.validate("scene");
  return sc;
}

LogScales log_scales_from(py::handle obj, std::size_t n, const std::string& what) {
  auto a = float32_array(obj, {static_cast<py::ssize_t>(n), 3}, what);
  check_finite(a.data(), n, 3, what);
  LogScales ls{std::vector<float>(n), std::vector<float>(n), std::vector<float>(n)};
  for (std::size_t k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) ls[d][k] = a.data()[k * 3 + d];
  return ls;
}

const Camera& camera_from(py::handle obj, const std::string& what) {
  if (!py::isinstance<Camera>(obj)) throw Error("expected a vcar.Camera", what);
  const Camera& c = obj.cast<const Camera&>();
  c.validate();
  return c;
}

}  // namespace

void register_scene(py::module_& m) {
  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", R"doc(
3D Gaussians in gsplat's layout (docs/python.md). Every array attribute is a numpy view of the
scene's own storage, never a copy: writing into it changes the scene.

  means       (N, 3) float32   centres, world units
  quats       (N, 4) float32   rotations as quaternions w, x, y, z (unnormalised)
  log_scales  (N, 3) float32   log of the per-axis standard deviations
  opacities   (N,)   float32   opacity logits (opacity = sigmoid)
  sh          (N, K, 3) float32 spherical-harmonics colour, K = (sh_degree + 1)^2, [:, 0] = DC
  extra       (N, E) float32   other PLY properties (named by extra_names), kept for writing

Scene(means, quats, log_scales, opacities, sh=None, extra=None, extra_names=None) takes
float32 arrays; means, quats and log_scales are kept without a copy when C-contiguous;
opacities, sh and extra are copied once into the scene. Wrong shapes, dtypes, NaN/Inf and zero
quaternions raise vcar.Error naming the array and row.)doc")
      .def(py::init(&make_scene), py::arg("means"), py::arg("quats"), py::arg("log_scales"), py::arg("opacities"),
           py::arg("sh") = py::none(), py::arg("extra") = py::none(), py::arg("extra_names") = py::none())
      .def("__len__", &Scene::size)
      .def_property_readonly("sh_degree", [](const Scene& s) { return s.g.sh_degree; })
      .def_property_readonly("extra_names", [](const Scene& s) { return s.g.extra_names; })
      .def_property(
          "means", [](const Scene& s) { return s.means; },
          [](Scene& s, py::object v) { s.means = geometry(v, static_cast<py::ssize_t>(s.size()), 3, "means"); })
      .def_property(
          "quats", [](const Scene& s) { return s.quats; },
          [](Scene& s, py::object v) {
            auto q = geometry(v, static_cast<py::ssize_t>(s.size()), 4, "quats");
            check_quats(q);
            s.quats = q;
          })
      .def_property(
          "log_scales", [](const Scene& s) { return s.log_scales; },
          [](Scene& s, py::object v) { s.log_scales = geometry(v, static_cast<py::ssize_t>(s.size()), 3, "log_scales"); })
      .def_property(
          "opacities",
          [](py::object self) {
            Scene& s = self.cast<Scene&>();
            return view(self, s.g.opacity_logit, {static_cast<py::ssize_t>(s.size())});
          },
          [](Scene& s, py::object v) {
            auto a = float32_array(v, {static_cast<py::ssize_t>(s.size())}, "opacities");
            check_finite(a.data(), s.size(), 1, "opacities");
            copy_into(s.g.opacity_logit, a);
          })
      .def_property(
          "sh",
          [](py::object self) {
            Scene& s = self.cast<Scene&>();
            return view(self, s.g.sh, {static_cast<py::ssize_t>(s.size()), s.g.sh_coeffs(), 3});
          },
          [](Scene& s, py::object v) {
            auto a = float32_array(v, {static_cast<py::ssize_t>(s.size()), s.g.sh_coeffs(), 3}, "sh");
            check_finite(a.data(), s.size(), static_cast<std::size_t>(s.g.sh_coeffs()) * 3, "sh");
            copy_into(s.g.sh, a);
          },
          "(N, K, 3) float32 view; assigning copies into it (same shape: a new SH degree needs a new Scene)")
      .def_property_readonly(
          "extra",
          [](py::object self) {
            Scene& s = self.cast<Scene&>();
            return view(self, s.g.extra, {static_cast<py::ssize_t>(s.size()), static_cast<py::ssize_t>(s.g.extra_names.size())});
          })
      .def(
          "subset",
          [](Scene& s, py::object indices) {
            const std::vector<Index> idx = index_vector(indices, s.size(), "indices");
            SceneUse use(s, false);
            return Scene::from_cpp(use.scene().subset(idx));
          },
          py::arg("indices"), "A new Scene of the Gaussians `indices`, in that order (every column copied).")
      .def(
          "copy",
          [](Scene& s) {
            SceneUse use(s, false);
            GaussianScene g = use.scene();
            return Scene::from_cpp(std::move(g));
          },
          "A deep copy.")
      .def(
          "validate", [](Scene& s) { SceneUse use(s, true); },
          "Raises vcar.Error naming the first Gaussian with a NaN/Inf value or a zero quaternion.")
      .def("__repr__", [](const Scene& s) {
        return "<vcar.Scene: " + std::to_string(s.size()) + " Gaussians, SH degree " + std::to_string(s.g.sh_degree) +
               (s.g.extra_names.empty() ? "" : ", " + std::to_string(s.g.extra_names.size()) + " extra properties") + ">";
      });

  m.def(
      "read_ply",
      [](const fs::path& path) {
        GaussianScene g;
        InfiniteOpacities infinite;
        {
          py::gil_scoped_release nogil;
          g = io::read_ply(path, &infinite);
        }
        if (infinite.total()) warn_infinite_opacities(path, infinite);
        return Scene::from_cpp(std::move(g));
      },
      py::arg("path"), "Reads an Inria 3DGS PLY (binary or ASCII, SH degree 0-3; docs/formats.md).");
  m.def(
      "read_scene",
      [](const fs::path& path) {
        GaussianScene g;
        InfiniteOpacities infinite;
        {
          py::gil_scoped_release nogil;
          g = io::read_scene(path, nullptr, &infinite);
        }
        if (infinite.total()) warn_infinite_opacities(path, infinite);
        return Scene::from_cpp(std::move(g));
      },
      py::arg("path"), "Reads any scene file vcar knows, by content: PLY, compressed PLY, SPZ, .splat.");
  m.def(
      "write_ply",
      [](const fs::path& path, Scene& s, py::object indices, py::object log_scales, bool binary) {
        SceneUse use(s, false);
        if (indices.is_none()) {
          if (!log_scales.is_none()) throw Error("log_scales needs indices (aligned with them)", "write_ply");
          py::gil_scoped_release nogil;
          io::write_ply(path, use.scene(), binary);
          return;
        }
        const std::vector<Index> idx = index_vector(indices, s.size(), "indices");
        std::optional<LogScales> ls;
        if (!log_scales.is_none()) ls = log_scales_from(log_scales, idx.size(), "log_scales");
        py::gil_scoped_release nogil;
        io::write_ply(path, use.scene(), idx, ls ? &*ls : nullptr, binary);
      },
      py::arg("path"), py::arg("scene"), py::arg("indices") = py::none(), py::arg("log_scales") = py::none(),
      py::arg("binary") = true,
      "Writes an Inria PLY (atomically): the whole scene, or the Gaussians `indices` with, optionally,\n"
      "their refined log_scales (M, 3) (a segmentation result).");
  m.def(
      "write_scene",
      [](const fs::path& path, Scene& s) {
        SceneUse use(s, false);
        py::gil_scoped_release nogil;
        io::write_scene(path, use.scene());
      },
      py::arg("path"), py::arg("scene"), "Writes by extension: .splat, .spz, otherwise Inria PLY.");

  m.def(
      "render",
      [](Scene& s, py::object camera, py::object subset, py::object log_scales, py::object background, bool depth) {
        const Camera cam = camera_from(camera, "camera");
        std::optional<std::vector<Index>> idx;
        if (!subset.is_none()) idx = index_vector(subset, s.size(), "subset");
        std::optional<LogScales> ls;
        if (!log_scales.is_none())
          ls = log_scales_from(log_scales, idx ? idx->size() : s.size(), "log_scales");
        const Eigen::Vector3f bg = vec3_from(background, "background");
        SceneUse use(s);
        RenderOutput out;
        {
          py::gil_scoped_release nogil;
          RenderRequest q;
          q.scene = &use.scene();
          q.camera = &cam;
          q.subset = idx ? &*idx : nullptr;
          q.log_scale = ls ? &*ls : nullptr;
          q.background = bg;
          q.want_depth = depth;
          cpu::TiledRenderer renderer;
          out = renderer.render(q);
        }
        py::dict d;
        d["rgb"] = adopt(std::move(out.rgb));
        d["alpha"] = adopt(std::move(out.alpha));
        d["depth"] = depth ? py::object(adopt(std::move(out.depth))) : py::object(py::none());
        return d;
      },
      py::arg("scene"), py::arg("camera"), py::arg("subset") = py::none(), py::arg("log_scales") = py::none(),
      py::arg("background") = py::make_tuple(0.0, 0.0, 0.0), py::arg("depth") = false,
      R"doc(Renders one view with the built-in CPU renderer (gsplat's rules, conventions §3).

Returns {"rgb": (H, W, 3) float32 in [0, 1], "alpha": (H, W) float32, "depth": (H, W) float32
sum z alpha T, or None}. `subset`: indices of the Gaussians to draw (None: all); `log_scales`:
(M, 3) replacing their log-scales (aligned with subset), e.g. a segmentation's refined scales.)doc");

  m.def(
      "read_mask",
      [](const fs::path& path) {
        Mask mk;
        {
          py::gil_scoped_release nogil;
          mk = io::read_mask(path);
        }
        return mask_array(mk);
      },
      py::arg("path"), "A mask file (PNG/JPEG, any channels) as a bool (H, W) array, nonzero = foreground.");
  m.def(
      "read_image",
      [](const fs::path& path) {
        ImageRGB8 img;
        {
          py::gil_scoped_release nogil;
          img = io::read_image_rgb8(path);
        }
        return adopt(std::move(img), false);
      },
      py::arg("path"), "An image file as uint8 (H, W, 3).");
  m.def(
      "write_png",
      [](const fs::path& path, py::object image) {
        py::array a = as_array(image, "image");
        const char k = a.dtype().kind();
        if (a.ndim() != 2 && a.ndim() != 3) throw Error("must be (H, W) or (H, W, C), got " + shape_text(a), "image");
        if (k == 'b') {  // a mask: 0 / 255
          const Mask m8 = mask_from(a, "image");
          Mask out(m8.width, m8.height, 1);
          for (std::size_t i = 0; i < out.data.size(); ++i) out.data[i] = m8.data[i] ? 255 : 0;
          io::write_png(path, out);
          return;
        }
        const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
        const int c = a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1;
        if (a.dtype().is(py::dtype::of<std::uint8_t>())) {
          auto u = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(a);
          Image<std::uint8_t> img(w, h, c);
          std::copy(u.data(), u.data() + u.size(), img.data.begin());
          io::write_png(path, img);
        } else if (k == 'f') {
          auto f = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
          ImageF img(w, h, c);
          std::copy(f.data(), f.data() + f.size(), img.data.begin());
          io::write_png(path, img);
        } else {
          throw Error("must be bool, uint8 or float in [0, 1], got " + dtype_text(a), "image");
        }
      },
      py::arg("path"), py::arg("image"),
      "Writes a PNG (atomically): bool masks as 0/255, uint8 as is, floats in [0, 1] rounded to 8 bits.");

  m.def("set_num_threads", &set_num_threads, py::arg("n"), "Threads of vcar's parallel loops (OpenMP); results do not depend on it.");
  m.def("max_threads", &max_threads, "Threads vcar's parallel loops use.");
}

}  // namespace vcar::python
