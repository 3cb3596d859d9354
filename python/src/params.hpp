#pragma once
// VcarParams from Python: None (the default preset), a preset name, a dict of overrides (with an
// optional "preset" key), or a (preset, dict) pair; and every field back as a dict.
#include <pybind11/pybind11.h>

#include "vcar/algo/params.hpp"

namespace vcar::python {

// The preset `params=None` means (docs/python.md).
inline constexpr const char* default_preset = "robust";

VcarParams params_from(pybind11::handle obj);
pybind11::dict params_dict(const VcarParams& p);

}  // namespace vcar::python
