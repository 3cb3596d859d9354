#pragma once
// Shared pieces of the Python module `vcar` (docs/python.md): numpy checks that turn wrong
// shapes, dtypes and NaN into vcar::Error (raised as vcar.Error), zero-copy arrays over C++
// buffers, and the Python-side Scene.
//
// GIL rules: every function here runs with the GIL held; C++ work that takes long (the
// pipeline, rendering, voting) releases it, and callbacks into Python take it back.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar::python {

namespace py = pybind11;

// ---- errors ---------------------------------------------------------------------------------

// A Python exception raised inside a callable (segmenter, renderer, progress) while C++ code ran
// it. The exception itself waits in an ErrorStash and is raised again, unchanged, when the C++
// call returns; this marker is a vcar::Error so that the pipeline passes it through untouched.
struct PythonRaised : Error {
  explicit PythonRaised(const std::string& where) : Error("a Python callable raised an exception", where) {}
};

// Holds the first Python exception of one C++ call. Lives in the binding's frame, so that it is
// destroyed with the GIL held.
struct ErrorStash {
  std::optional<py::error_already_set> error;
  std::string where;  // the round and view it came from, added to the exception as a note

  // Keeps `e` (the first one wins) and throws PythonRaised. Needs the GIL.
  [[noreturn]] void keep_and_throw(py::error_already_set&& e, const std::string& at);
  // Raises the kept exception in Python (with a note naming `where`). Needs the GIL.
  [[noreturn]] void raise();
};

// Registers vcar.Error (a ValueError, with `.where`) and vcar.Cancelled, and the translator.
void register_errors(py::module_& m);

// ---- numpy checks ---------------------------------------------------------------------------

// np.asarray(obj): lists, tuples, arrays, CPU torch tensors (through __array__).
py::array as_array(py::handle obj, const std::string& what);
// "(5, 3)"
std::string shape_text(const py::array& a);
// "float64"
std::string dtype_text(const py::array& a);

// A float32 array of exactly `shape` (-1: any extent); other dtypes are an error (a scene column
// is never converted silently). Returned C-contiguous: the same array when it already is.
py::array_t<float, py::array::c_style> float32_array(py::handle obj, std::vector<py::ssize_t> shape,
                                                     const std::string& what);
// Any real array of `shape`, converted to float64 (small inputs: matrices, points, colours).
py::array_t<double, py::array::c_style> real_array(py::handle obj, std::vector<py::ssize_t> shape,
                                                   const std::string& what);
// Throws vcar::Error naming the first row of `p` (n rows of `cols` values) holding NaN or Inf.
void check_finite(const float* p, std::size_t n, std::size_t cols, const std::string& what);

// Integer indices into a set of n items (any integer dtype), each checked to be in [0, n).
std::vector<Index> index_vector(py::handle obj, std::size_t n, const std::string& what);
// Index array for Python: int64 (numpy's index type).
py::array_t<std::int64_t> index_array(const std::vector<Index>& v);

// A mask from a bool or uint8 array of width x height (also (H, W, 1)); nonzero = foreground.
Mask mask_from(py::handle obj, int width, int height, const std::string& what);
// A mask of any size (bool or uint8, 2-D).
Mask mask_from(py::handle obj, const std::string& what);
// A float image width x height x channels from any float array of shape (H, W, C), or (H, W)
// when C is 1 (copied to float32); NaN/Inf are an error.
ImageF float_image(py::handle obj, int width, int height, int channels, const std::string& what);
// Mask -> bool (H, W) array (copy).
py::array_t<bool> mask_array(const Mask& m);

// A zero-copy numpy array over a vector that the array then owns.
template <class T>
py::array_t<T> adopt(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(v));
  py::capsule free_it(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, owned->data(), free_it);
}
// An image as (H, W) or (H, W, C) without a copy.
template <class T>
py::array_t<T> adopt(Image<T>&& img, bool squeeze_single_channel = true) {
  std::vector<py::ssize_t> shape{img.height, img.width};
  if (img.channels != 1 || !squeeze_single_channel) shape.push_back(img.channels);
  return adopt(std::move(img.data), shape);
}

// (3,) float32 <-> Eigen.
py::array_t<float> vec3_array(const Eigen::Vector3f& v);
Eigen::Vector3f vec3_from(py::handle obj, const std::string& what);

// ---- scene ----------------------------------------------------------------------------------

// vcar.Scene: the Gaussians in gsplat's layout for Python, the library's GaussianScene for C++.
//   means (N, 3), quats (N, 4) wxyz, log_scales (N, 3): numpy arrays, the storage of the
//     geometry; copied into g's columns (structure of arrays) by sync() before each C++ call.
//   opacities (N,), sh (N, K, 3), extra (N, E): views of g's own vectors (never reallocated).
class Scene {
public:
  GaussianScene g;
  py::array_t<float, py::array::c_style> means, quats, log_scales;
  // Held by C++ calls that read g, so that two threads never sync under each other; recursive: a
  // Python callable run by such a call (a renderer calling vcar.render) may use the scene again.
  std::recursive_mutex mutex;

  // Takes a scene read or built in C++ (its geometry columns are copied to the arrays once).
  static std::shared_ptr<Scene> from_cpp(GaussianScene&& s);
  // Copies the arrays into g's columns. Needs the GIL.
  void sync();
  std::size_t size() const noexcept { return g.size(); }
};

// Held for the duration of a C++ call on a scene: locks it (releasing the GIL while waiting),
// syncs its geometry and validates it (NaN/Inf, zero quaternions). Construct with the GIL held.
class SceneUse {
public:
  explicit SceneUse(Scene& s, bool validate = true);
  const GaussianScene& scene() const noexcept { return s_->g; }

private:
  Scene* s_;
  std::unique_lock<std::recursive_mutex> lock_;
};

Scene& scene_from(py::handle obj);

// ---- cameras --------------------------------------------------------------------------------

// A list (any iterable) of vcar.Camera, validated.
std::vector<Camera> cameras_from(py::handle obj, const std::string& what = "cameras");
py::list camera_list(const std::vector<Camera>& cams);

// ---- registration (one per source file) -----------------------------------------------------
void register_scene(py::module_& m);
void register_cameras(py::module_& m);
void register_params(py::module_& m);
void register_segment(py::module_& m);
void register_reselection(py::module_& m);
void register_stages(py::module_& m);
void register_synth(py::module_& m, py::module_& synth, py::module_& eval);

}  // namespace vcar::python
