// The Python module vcar._vcar (imported by python/vcar/__init__.py; docs/python.md).
#include "common.hpp"

PYBIND11_MODULE(_vcar, m) {
  namespace vp = vcar::python;
  m.doc() = "vcar: training-free segmentation of 3D Gaussian Splatting scenes (VCAR). See docs/python.md.";
  vp::register_errors(m);
  vp::register_scene(m);
  vp::register_cameras(m);
  vp::register_params(m);
  vp::register_segment(m);
  vp::register_reselection(m);
  vp::register_stages(m);
  auto synth = m.def_submodule("synth", "The synthetic world with exact ground truth, rigs, the oracle segmenter.");
  auto eval = m.def_submodule("eval", "The metrics of conventions §6.");
  vp::register_synth(m, synth, eval);
}
