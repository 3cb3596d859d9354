// VcarParams <-> Python: presets by name (VcarParams::preset) and overrides by key through
// io::set_parameter, so that Python reads values exactly as `vcar segment --preset P --set k=v`;
// back to Python through io::params_json (the names and values report.json holds).
#include "params.hpp"

#include <string>

#include "common.hpp"
#include "vcar/io/params_text.hpp"

namespace vcar::python {

namespace {

// The text `--set key=value` would carry for a Python value.
std::string value_text(py::handle v, const std::string& where) {
  py::module_ np = py::module_::import("numpy");
  if (py::isinstance(v, np.attr("generic"))) return value_text(v.attr("item")(), where);  // numpy scalars
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(v)) return py::str(v).cast<std::string>();
  if (py::isinstance<py::float_>(v)) return py::repr(v).cast<std::string>();  // shortest round-trip text
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v) || py::isinstance(v, np.attr("ndarray"))) {
    std::string s;
    for (py::handle x : py::iter(v)) s += (s.empty() ? "" : ",") + value_text(x, where);
    return s;
  }
  throw Error("unsupported value type " + py::str(py::type::of(v).attr("__name__")).cast<std::string>() +
                  " (numbers, bools, strings, or 3 numbers for a colour)", where);
}

void set_one(VcarParams& p, const std::string& key, py::handle value) {
  const std::string where = "params['" + key + "']";
  const std::string text = value_text(value, where);
  try {
    io::set_parameter(p, key, text);
  } catch (const Error& e) {
    // Name the dict entry, not the command-line flag.
    std::string msg = e.what();
    if (!e.where().empty() && msg.rfind(e.where() + ": ", 0) == 0) msg = msg.substr(e.where().size() + 2);
    throw Error(msg, e.where() == "--set" ? std::string("params") : where);
  }
}

}  // namespace

VcarParams params_from(py::handle obj) {
  if (obj.is_none()) return VcarParams::preset(default_preset);
  if (py::isinstance<py::str>(obj)) return VcarParams::preset(obj.cast<std::string>());
  py::object preset = py::str(default_preset), overrides = py::dict();
  if (py::isinstance<py::dict>(obj)) {
    overrides = py::reinterpret_borrow<py::object>(obj);
    if (overrides.contains("preset")) preset = overrides["preset"];
  } else if ((py::isinstance<py::tuple>(obj) || py::isinstance<py::list>(obj)) && py::len(obj) == 2) {
    preset = obj[py::int_(0)];
    overrides = obj[py::int_(1)];
    if (!py::isinstance<py::dict>(overrides)) throw Error("expected (preset name, dict of overrides)", "params");
  } else {
    throw Error("expected None, a preset name (robust, nvos, lerf, reference_code), a dict of key=value "
                "overrides (optionally with 'preset'), or (preset, dict)", "params");
  }
  if (!py::isinstance<py::str>(preset)) throw Error("the preset must be a name", "params['preset']");
  VcarParams p = VcarParams::preset(preset.cast<std::string>());
  for (auto item : py::reinterpret_borrow<py::dict>(overrides)) {
    if (!py::isinstance<py::str>(item.first)) throw Error("keys must be parameter names (strings)", "params");
    const std::string key = item.first.cast<std::string>();
    if (key == "preset") continue;
    set_one(p, key, item.second);
  }
  p.validate();
  return p;
}

py::dict params_dict(const VcarParams& p) {
  // Floats as their shortest text (0.7, not 0.699999988), enums by the names set_parameter takes.
  return py::module_::import("json").attr("loads")(io::params_json(p).dump());
}

void register_params(py::module_& m) {
  m.attr("DEFAULT_PRESET") = default_preset;
  m.attr("PRESETS") = py::make_tuple("robust", "nvos", "lerf", "reference_code");
  m.def(
      "params", [](py::object params) { return params_dict(params_from(params)); }, py::arg("params") = py::none(),
      R"doc(Every parameter of VCAR by name (docs/conventions.md §5) for a `params` argument:
None (the default preset, vcar.DEFAULT_PRESET), a preset name (vcar.PRESETS), a dict of
overrides {"tau_fine": 0.7, ...} (with an optional "preset" key), or (preset, dict).
Values are read as `vcar segment --preset P --set key=value` reads them.)doc");
}

}  // namespace vcar::python
