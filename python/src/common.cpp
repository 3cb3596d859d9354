// Errors and numpy checks of the Python module (common.hpp).
#include "common.hpp"

#include <cmath>
#include <cstring>

#include "vcar/algo/pipeline.hpp"  // vcar::Cancelled

namespace vcar::python {

namespace {

PyObject* error_type = nullptr;      // vcar.Error (a ValueError)
PyObject* cancelled_type = nullptr;  // vcar.Cancelled (a vcar.Error)

void set_error(PyObject* type, const Error& e) {
  py::object inst = py::reinterpret_borrow<py::object>(type)(e.what());
  inst.attr("where") = e.where();
  PyErr_SetObject(type, inst.ptr());
}

py::object numpy() { return py::module_::import("numpy"); }

std::string expected_shape(const std::vector<py::ssize_t>& shape) {
  std::string s = "(";
  for (std::size_t d = 0; d < shape.size(); ++d) {
    if (d) s += ", ";
    s += shape[d] >= 0 ? std::to_string(shape[d]) : (d == 0 ? "N" : "*");
  }
  return s + (shape.size() == 1 ? ",)" : ")");
}

void check_shape(const py::array& a, const std::vector<py::ssize_t>& shape, const std::string& what) {
  bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t d = 0; ok && d < shape.size(); ++d) ok = shape[d] < 0 || a.shape(d) == shape[d];
  if (!ok) throw Error("must have shape " + expected_shape(shape) + ", got " + shape_text(a), what);
}

char dtype_kind(const py::array& a) { return a.dtype().kind(); }

py::array contiguous(const py::array& a) {
  if (a.flags() & py::array::c_style) return a;
  return numpy().attr("ascontiguousarray")(a);
}

}  // namespace

// ---- errors ---------------------------------------------------------------------------------

void ErrorStash::keep_and_throw(py::error_already_set&& e, const std::string& at) {
  if (!error) {
    error.emplace(std::move(e));
    where = at;
  }
  throw PythonRaised(at);
}

void ErrorStash::raise() {
  if (!error) throw Error("a Python callable raised an exception that was lost", where);
  py::error_already_set e = std::move(*error);
  error.reset();
  if (!where.empty() && py::hasattr(e.value(), "add_note")) {  // Python 3.11+
    try {
      e.value().attr("add_note")("raised inside vcar: " + where);
    } catch (py::error_already_set&) {  // an exception type that refuses notes: keep it as it is
    }
  }
  throw e;
}

void register_errors(py::module_& m) {
  error_type = PyErr_NewExceptionWithDoc(
      "vcar.Error",
      "Bad input or a failed step of vcar: the message names what is at fault (file and offset, view,\n"
      "parameter, array and row); `where` holds that part alone. A ValueError.",
      PyExc_ValueError, nullptr);
  cancelled_type = PyErr_NewExceptionWithDoc(
      "vcar.Cancelled", "The progress callback returned False: the call was cancelled.", error_type, nullptr);
  if (!error_type || !cancelled_type) throw py::error_already_set();
  m.attr("Error") = py::reinterpret_borrow<py::object>(error_type);
  m.attr("Cancelled") = py::reinterpret_borrow<py::object>(cancelled_type);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Cancelled& e) {
      set_error(cancelled_type, e);
    } catch (const Error& e) {
      set_error(error_type, e);
    }
  });
}

// ---- numpy checks ---------------------------------------------------------------------------

py::array as_array(py::handle obj, const std::string& what) {
  if (obj.is_none()) throw Error("is None, expected an array", what);
  try {
    return numpy().attr("asarray")(obj);
  } catch (py::error_already_set& e) {
    throw Error(std::string("is not an array: ") + e.what(), what);
  }
}

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtype_text(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

py::array_t<float, py::array::c_style> float32_array(py::handle obj, std::vector<py::ssize_t> shape,
                                                     const std::string& what) {
  py::array a = as_array(obj, what);
  if (!a.dtype().is(py::dtype::of<float>()))
    throw Error("must be float32, got " + dtype_text(a) + " (convert with .astype(numpy.float32))", what);
  check_shape(a, shape, what);
  return py::reinterpret_borrow<py::array_t<float, py::array::c_style>>(contiguous(a));
}

py::array_t<double, py::array::c_style> real_array(py::handle obj, std::vector<py::ssize_t> shape,
                                                   const std::string& what) {
  py::array a = as_array(obj, what);
  const char k = dtype_kind(a);
  if (a.size() > 0 && k != 'f' && k != 'i' && k != 'u')
    throw Error("must hold real numbers, got " + dtype_text(a), what);
  check_shape(a, shape, what);
  py::array d = numpy().attr("ascontiguousarray")(a, py::arg("dtype") = numpy().attr("float64"));
  auto r = py::reinterpret_borrow<py::array_t<double, py::array::c_style>>(d);
  const double* p = r.data();
  for (py::ssize_t i = 0; i < r.size(); ++i)
    if (!std::isfinite(p[i])) throw Error("holds a NaN or infinite value", what);
  return r;
}

void check_finite(const float* p, std::size_t n, std::size_t cols, const std::string& what) {
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < cols; ++c)
      if (!std::isfinite(p[i * cols + c]))
        throw Error("row " + std::to_string(i) + " holds a NaN or infinite value", what);
}

std::vector<Index> index_vector(py::handle obj, std::size_t n, const std::string& what) {
  py::array a = as_array(obj, what);
  if (a.size() == 0) return {};
  const char k = dtype_kind(a);
  if (k != 'i' && k != 'u') throw Error("must hold integers, got " + dtype_text(a), what);
  if (a.ndim() != 1) throw Error("must be one-dimensional, got shape " + shape_text(a), what);
  auto v = py::reinterpret_borrow<py::array_t<std::int64_t, py::array::c_style>>(
      numpy().attr("ascontiguousarray")(a, py::arg("dtype") = numpy().attr("int64")));
  std::vector<Index> out(static_cast<std::size_t>(v.size()));
  const std::int64_t* p = v.data();
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (p[i] < 0 || static_cast<std::uint64_t>(p[i]) >= n)
      throw Error("[" + std::to_string(i) + "] = " + std::to_string(p[i]) + " is out of range (" +
                      std::to_string(n) + " items)", what);
    out[i] = static_cast<Index>(p[i]);
  }
  return out;
}

py::array_t<std::int64_t> index_array(const std::vector<Index>& v) {
  std::vector<std::int64_t> w(v.begin(), v.end());
  const auto n = static_cast<py::ssize_t>(w.size());
  return adopt(std::move(w), {n});
}

namespace {
Mask mask_impl(py::handle obj, int width, int height, const std::string& what) {
  py::array a = as_array(obj, what);
  const bool is_bool = a.dtype().is(py::dtype::of<bool>()), is_u8 = a.dtype().is(py::dtype::of<std::uint8_t>());
  if (!is_bool && !is_u8)
    throw Error("must be bool or uint8, got " + dtype_text(a) +
                    " (threshold scores or probabilities first, e.g. prob > 0.5)", what);
  if (!(a.ndim() == 2 || (a.ndim() == 3 && a.shape(2) == 1)))
    throw Error("must have shape (H, W) or (H, W, 1), got " + shape_text(a), what);
  const auto h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
  if (width >= 0 && (w != width || h != height))
    throw Error("is " + std::to_string(w) + "x" + std::to_string(h) + " (W x H), the view is " +
                    std::to_string(width) + "x" + std::to_string(height), what);
  py::array c = contiguous(a);
  Mask m(w, h, 1);
  if (!m.data.empty()) std::memcpy(m.data.data(), c.data(), m.data.size());
  return m;
}
}  // namespace

Mask mask_from(py::handle obj, int width, int height, const std::string& what) {
  return mask_impl(obj, width, height, what);
}
Mask mask_from(py::handle obj, const std::string& what) { return mask_impl(obj, -1, -1, what); }

ImageF float_image(py::handle obj, int width, int height, int channels, const std::string& what) {
  py::array a = as_array(obj, what);
  if (a.dtype().kind() != 'f') throw Error("must be a float array, got " + dtype_text(a), what);
  const bool ok = (a.ndim() == 3 && a.shape(2) == channels) || (channels == 1 && a.ndim() == 2);
  if (!ok || a.shape(0) != height || a.shape(1) != width)
    throw Error("must have shape (" + std::to_string(height) + ", " + std::to_string(width) +
                    (channels == 1 ? "" : ", " + std::to_string(channels)) + ") for this view, got " + shape_text(a),
                what);
  auto f = py::reinterpret_borrow<py::array_t<float, py::array::c_style>>(
      numpy().attr("ascontiguousarray")(a, py::arg("dtype") = numpy().attr("float32")));
  ImageF img(width, height, channels);
  std::copy(f.data(), f.data() + f.size(), img.data.begin());
  check_finite(img.data.data(), img.pixels(), static_cast<std::size_t>(channels), what);
  return img;
}

py::array_t<bool> mask_array(const Mask& m) {
  py::array_t<bool> out({static_cast<py::ssize_t>(m.height), static_cast<py::ssize_t>(m.width)});
  bool* p = out.mutable_data();
  for (std::size_t k = 0; k < m.data.size(); ++k) p[k] = m.data[k] != 0;
  return out;
}

py::array_t<float> vec3_array(const Eigen::Vector3f& v) {
  py::array_t<float> out(3);
  for (int d = 0; d < 3; ++d) out.mutable_data()[d] = v[d];
  return out;
}

Eigen::Vector3f vec3_from(py::handle obj, const std::string& what) {
  const auto a = real_array(obj, {3}, what);
  return {static_cast<float>(a.data()[0]), static_cast<float>(a.data()[1]), static_cast<float>(a.data()[2])};
}

}  // namespace vcar::python
