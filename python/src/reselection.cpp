// vcar.Reselection: interactive re-selection (algo/reselection.hpp) for a viewer or notebook that
// holds masks and re-selects after every change: set_mask(view, mask) takes back the view's old
// votes and adds the new ones, select() reads the selection (vote, view completeness, ABR; no
// SSS, which needs a renderer and a segmenter: use vcar.segment). Both run with the GIL released.
//
// The Gaussians' geometry (means, rotations, log-scales) is copied when the object is made: the
// vote counters and ABR's state describe that geometry, so later edits of the scene's arrays do
// not leak into a session (make a new Reselection for an edited scene).
#include <pybind11/stl.h>

#include "common.hpp"
#include "params.hpp"
#include "result.hpp"
#include "vcar/algo/reselection.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"

namespace vcar::python {

namespace {

class ReselectionPy {
public:
  ReselectionPy(py::object scene, py::object cameras, py::object params)
      : params_(params.is_none() ? VcarParams::robust() : params_from(params)), cameras_(cameras_from(cameras)) {
    if (cameras_.empty()) throw Error("no cameras", "cameras");
    {
      SceneUse use(scene_from(scene));
      const GaussianScene& g = use.scene();
      geometry_.resize(g.size());
      geometry_.mean = g.mean;
      geometry_.rotation = g.rotation;
      geometry_.log_scale = g.log_scale;
      geometry_.opacity_logit = g.opacity_logit;
    }
    // The robust presets read each training view's alpha and depth, rendered once here on the
    // CPU (geometry and opacity are all a render's alpha and depth need); the paper presets none.
    py::gil_scoped_release nogil;
    cpu::TiledRenderer renderer;
    session_.emplace(geometry_, cameras_, renderer, params_);
  }

  void set_mask(std::size_t view, py::object mask) {
    if (view >= cameras_.size())
      throw Error("view " + std::to_string(view) + " out of range (" + std::to_string(cameras_.size()) + " views)",
                  "Reselection.set_mask");
    const Camera& cam = cameras_[view];
    if (mask.is_none()) {
      py::gil_scoped_release nogil;
      session_->set_mask(view, nullptr);
      return;
    }
    const Mask m = mask_from(mask, cam.width, cam.height, "view '" + cam.name + "': mask");
    py::gil_scoped_release nogil;
    session_->set_mask(view, &m);
  }

  py::dict select(std::size_t reference_view) {
    SegmentationResult r;
    {
      py::gil_scoped_release nogil;
      r = session_->select(reference_view);
    }
    py::dict out = result_dict(std::move(r), params_);
    const ReselectionStats& s = session_->last_stats();
    py::dict st;
    st["abr_incremental"] = s.abr_incremental;
    st["views_changed"] = s.views_changed;
    st["carried"] = s.carried;
    st["fresh"] = s.fresh;
    st["stale"] = s.stale;
    out["reselection"] = st;
    return out;
  }

  void set_incremental_abr(bool on) { session_->set_incremental_abr(on); }
  std::size_t views() const { return session_->views(); }
  std::size_t masks() const { return session_->masks(); }

private:
  VcarParams params_;
  std::vector<Camera> cameras_;
  GaussianScene geometry_;
  std::optional<Reselection> session_;
};

}  // namespace

void register_reselection(py::module_& m) {
  py::class_<ReselectionPy>(m, "Reselection",
                            "Interactive re-selection with masks in hand (docs/python.md): set_mask(view, mask) "
                            "replaces one view's mask (None clears it), select() returns the selection like "
                            "vcar.segment with SSS off, reusing the previous call's votes and ABR state.")
      .def(py::init<py::object, py::object, py::object>(), py::arg("scene"), py::arg("cameras"),
           py::arg("params") = py::none(),
           "params: as vcar.segment's; None = the default ('robust': each training view is rendered once "
           "on the CPU for its alpha and depth; 'nvos' needs no renders and votes incrementally)")
      .def("set_mask", &ReselectionPy::set_mask, py::arg("view"), py::arg("mask"),
           "Sets, replaces or (None) clears the mask of training view `view` (a bool or uint8 array, H x W).")
      .def("select", &ReselectionPy::select, py::arg("reference_view") = 0,
           "The selection for the masks set so far: a dict like vcar.segment's, plus 'reselection' "
           "(abr_incremental, views_changed, carried, fresh, stale).")
      .def("set_incremental_abr", &ReselectionPy::set_incremental_abr, py::arg("on"),
           "False: every select() refines from scratch (the same result; for comparisons).")
      .def_property_readonly("views", &ReselectionPy::views)
      .def_property_readonly("masks", &ReselectionPy::masks, "views that currently have a mask");
}

}  // namespace vcar::python
