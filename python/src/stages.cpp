// The stages of VCAR on their own, for experiments on one of them: visibility voting (Eq. 1-3),
// robust sphere and view completeness (Eq. 4-6, A.1-A.3), spiral sampling (Eq. 7-8) and
// axis-aware boundary refinement (Eq. 9-14, B).
#include <numeric>

#include <pybind11/stl.h>

#include "common.hpp"
#include "params.hpp"
#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/robust_sphere.hpp"
#include "vcar/algo/spiral_sampler.hpp"
#include "vcar/algo/view_completeness.hpp"
#include "vcar/algo/visibility_voting.hpp"

namespace vcar::python {

namespace {

const Camera& camera_arg(py::handle obj, const std::string& what) {
  if (!py::isinstance<Camera>(obj)) throw Error("expected a vcar.Camera", what);
  const Camera& c = obj.cast<const Camera&>();
  c.validate();
  return c;
}

std::vector<Index> all_or(py::handle indices, std::size_t n, const std::string& what) {
  if (!indices.is_none()) return index_vector(indices, n, what);
  std::vector<Index> all(n);
  std::iota(all.begin(), all.end(), Index{0});
  return all;
}

template <class T>
py::array_t<T> column(std::size_t n, auto&& value) {
  py::array_t<T> out(static_cast<py::ssize_t>(n));
  for (std::size_t k = 0; k < n; ++k) out.mutable_data()[k] = value(k);
  return out;
}

Directions directions_from(py::handle obj, const std::string& what) {
  const auto a = real_array(obj, {-1, 3}, what);
  Directions d;
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    d.push_back(Eigen::Vector3f(static_cast<float>(a.data()[i * 3]), static_cast<float>(a.data()[i * 3 + 1]),
                                static_cast<float>(a.data()[i * 3 + 2])));
  return d;
}

py::array_t<float> directions_array(const Directions& d) {
  py::array_t<float> out({static_cast<py::ssize_t>(d.size()), py::ssize_t{3}});
  for (std::size_t i = 0; i < d.size(); ++i) {
    out.mutable_data()[i * 3] = d.x[i];
    out.mutable_data()[i * 3 + 1] = d.y[i];
    out.mutable_data()[i * 3 + 2] = d.z[i];
  }
  return out;
}

py::dict gap_dict(const AngularGap& g) {
  py::dict d;
  d["Delta_max_deg"] = g.Delta_max_deg;
  d["Delta_max_rad"] = g.Delta_max_rad;
  d["direction"] = vec3_array(g.direction);
  d["probe"] = g.probe;
  d["valid_cameras"] = g.valid_cameras;
  return d;
}

ObjectSphere sphere_from(py::handle center, float radius) {
  ObjectSphere s;
  s.c = vec3_from(center, "center");
  if (!(radius > 0.f) || !std::isfinite(radius)) throw Error("must be positive", "radius");
  s.r = radius;
  return s;
}

// Eq. 1-3 for one object over a snapshot of the candidates' means.
class VotingPy {
public:
  VotingPy(Scene& s, py::object candidates) : n_scene_(s.size()) {
    if (!candidates.is_none()) candidates_ = index_vector(candidates, n_scene_, "candidates");
    const std::size_t n = candidates.is_none() ? n_scene_ : candidates_.size();
    SceneUse use(s);
    for (int d = 0; d < 3; ++d) {
      xyz_[d].resize(n);
      for (std::size_t k = 0; k < n; ++k)
        xyz_[d][k] = use.scene().mean[d][candidates.is_none() ? k : candidates_[k]];
    }
    v_.emplace(xyz_[0], xyz_[1], xyz_[2]);
  }

  void add_view(py::object camera, py::object mask, py::object depth, py::object alpha, float tolerance) {
    const Camera cam = camera_arg(camera, "camera");
    const std::string where = "view '" + cam.name + "'";
    if (mask.is_none()) {
      py::gil_scoped_release nogil;
      v_->add_view(cam, nullptr);
      return;
    }
    const Mask m = mask_from(mask, cam.width, cam.height, where + ": mask");
    if (depth.is_none() != alpha.is_none()) throw Error("the occlusion test needs both depth and alpha", where);
    if (!depth.is_none()) {
      const ImageF D = float_image(depth, cam.width, cam.height, 1, where + ": depth");
      const ImageF A = float_image(alpha, cam.width, cam.height, 1, where + ": alpha");
      py::gil_scoped_release nogil;
      v_->add_view(cam, &m, &D, &A, tolerance);
      return;
    }
    py::gil_scoped_release nogil;
    v_->add_view(cam, &m);
  }

  std::size_t size() const { return v_->size(); }
  Index scene_index(std::size_t k) const { return candidates_.empty() ? static_cast<Index>(k) : candidates_[k]; }
  py::array_t<std::int64_t> candidates() const {
    std::vector<Index> c(size());
    for (std::size_t k = 0; k < c.size(); ++k) c[k] = scene_index(k);
    return index_array(c);
  }
  py::array_t<std::int64_t> selected(float tau) const {
    std::vector<Index> out;
    for (std::size_t k = 0; k < size(); ++k)
      if (v_->ratio(k) >= tau) out.push_back(scene_index(k));  // Eq. 3
    std::sort(out.begin(), out.end());
    return index_array(out);
  }
  const VisibilityVoting& voting() const { return *v_; }

private:
  std::size_t n_scene_;
  std::vector<Index> candidates_;  // empty: every Gaussian
  std::array<std::vector<float>, 3> xyz_;
  std::optional<VisibilityVoting> v_;
};

class AbrPy {
public:
  AbrPy(Scene& s, py::object candidates, py::object params) {
    const std::vector<Index> c = all_or(candidates, s.size(), "candidates");
    const AbrParams p = params_from(params).abr();  // as the pipeline derives them
    SceneUse use(s);
    abr_.emplace(use.scene(), c, p);
  }
  void add_view(py::object camera, py::object mask) {
    const Camera cam = camera_arg(camera, "camera");
    const Mask m = mask_from(mask, cam.width, cam.height, "view '" + cam.name + "': mask");
    py::gil_scoped_release nogil;
    abr_->add_view(cam, m);
  }
  py::dict finish() const {
    AbrResult r;
    {
      py::gil_scoped_release nogil;
      r = abr_->finish();
    }
    const auto n = static_cast<py::ssize_t>(abr_->size());
    py::array_t<float> ls({n, py::ssize_t{3}});
    for (py::ssize_t k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d) ls.mutable_data()[k * 3 + d] = r.log_scale[d][k];
    py::dict out;
    out["log_scales"] = ls;
    out["flagged"] = r.flagged;
    out["compressed"] = r.compressed;
    out["axis_compressed"] = adopt(std::move(r.axis_compressed), {n});
    return out;
  }
  const BoundaryRefinement& abr() const { return *abr_; }

private:
  std::optional<BoundaryRefinement> abr_;
};

}  // namespace

void register_stages(py::module_& m) {
  py::class_<VotingPy>(m, "VisibilityVoting", R"doc(
Visibility-based weighted voting (Eq. 1-3) for one object, streaming: per candidate Gaussian
F_i (views with its centre visible and in the mask) and V_i (views with it visible),
R_i = F_i / max(V_i, 1). `candidates`: scene indices (None: every Gaussian); their means are
copied at construction. add_view(camera, mask=None): mask None is "no evidence" (conventions §4);
with depth and alpha ((H, W) float, sum z alpha T and 1 - T of a render of that view) a Gaussian
behind the rendered surface by more than `tolerance` does not count as visible.)doc")
      .def(py::init([](py::object scene, py::object candidates) {
             return std::make_unique<VotingPy>(scene_from(scene), candidates);
           }),
           py::arg("scene"), py::arg("candidates") = py::none())
      .def("add_view", &VotingPy::add_view, py::arg("camera"), py::arg("mask") = py::none(), py::kw_only(),
           py::arg("depth") = py::none(), py::arg("alpha") = py::none(), py::arg("tolerance") = 0.05f)
      .def("__len__", &VotingPy::size)
      .def_property_readonly("views", [](const VotingPy& v) { return v.voting().views(); })
      .def_property_readonly("candidates", &VotingPy::candidates, "int64 scene index of each candidate")
      .def("ratios", [](const VotingPy& v) { return column<float>(v.size(), [&](std::size_t k) { return v.voting().ratio(k); }); },
           "R_i per candidate (Eq. 3), float32")
      .def("visible", [](const VotingPy& v) { return column<std::uint16_t>(v.size(), [&](std::size_t k) { return v.voting().visible(k); }); },
           "V_i per candidate, uint16")
      .def("foreground", [](const VotingPy& v) { return column<std::uint16_t>(v.size(), [&](std::size_t k) { return v.voting().foreground(k); }); },
           "F_i per candidate, uint16")
      .def("selected", &VotingPy::selected, py::arg("tau"), "Scene indices (ascending, int64) with R_i >= tau (Eq. 3)");

  m.def(
      "robust_sphere",
      [](py::object scene, py::object indices, py::object reference_position, float eta) {
        Scene& s = scene_from(scene);
        const std::vector<Index> idx = index_vector(indices, s.size(), "indices");
        const Eigen::Vector3f ref = vec3_from(reference_position, "reference_position");
        SceneUse use(s);
        const ObjectSphere o = robust_sphere(use.scene(), idx, ref, eta);
        py::dict d;
        d["center"] = vec3_array(o.c);
        d["radius"] = o.r;
        d["inliers"] = o.inliers;
        return d;
      },
      py::arg("scene"), py::arg("indices"), py::arg("reference_position"), py::arg("eta") = 1.2f,
      "Eq. 4-5: centre of the inlier means (within mean + 3 std of the distances to their mean)\n"
      "and radius eta |reference_position - centre|.");
  m.def(
      "visible_fraction",
      [](py::object scene, py::object indices, py::object camera) {
        Scene& s = scene_from(scene);
        const std::vector<Index> idx = index_vector(indices, s.size(), "indices");
        const Camera cam = camera_arg(camera, "camera");
        SceneUse use(s);
        return visible_fraction(use.scene(), idx, cam);
      },
      py::arg("scene"), py::arg("indices"), py::arg("camera"), "A.1: rho^(j), the fraction of the means inside the view.");
  m.def(
      "valid_cameras",
      [](py::object scene, py::object indices, py::object cameras, float rho_min) {
        Scene& s = scene_from(scene);
        const std::vector<Index> idx = index_vector(indices, s.size(), "indices");
        const std::vector<Camera> cams = cameras_from(cameras);
        SceneUse use(s);
        std::vector<std::size_t> v;
        {
          py::gil_scoped_release nogil;
          v = valid_cameras(use.scene(), idx, cams, rho_min);
        }
        std::vector<Index> w(v.begin(), v.end());
        return index_array(w);
      },
      py::arg("scene"), py::arg("indices"), py::arg("cameras"), py::arg("rho_min") = 0.2f,
      "A.1: indices of the cameras with rho^(j) >= rho_min.");
  m.def(
      "fibonacci_lattice", [](int K) { return directions_array(fibonacci_lattice(K)); }, py::arg("K") = 2000,
      "A.3: K unit probe directions, (K, 3) float32.");
  m.def(
      "headings",
      [](py::object center, py::object positions) {
        const Directions p = directions_from(positions, "positions");
        std::vector<Eigen::Vector3f> pos;
        for (std::size_t i = 0; i < p.size(); ++i) pos.push_back(p[i]);
        return directions_array(headings(vec3_from(center, "center"), pos));
      },
      py::arg("center"), py::arg("positions"), "A.2: unit directions from the centre to each position (those at the centre skipped).");
  m.def(
      "max_angular_gap",
      [](py::object probes, py::object headings) {
        return gap_dict(max_angular_gap(directions_from(probes, "probes"), directions_from(headings, "headings")));
      },
      py::arg("probes"), py::arg("headings"),
      "Eq. 6: Delta_max = max_i acos(max_j t_i . h_j), with the probe direction of the largest gap.");
  m.def(
      "view_completeness",
      [](py::object scene, py::object indices, py::object cameras, py::object center, float rho_min, int K) {
        Scene& s = scene_from(scene);
        const std::vector<Index> idx = index_vector(indices, s.size(), "indices");
        const std::vector<Camera> cams = cameras_from(cameras);
        const Eigen::Vector3f c = vec3_from(center, "center");
        SceneUse use(s);
        std::vector<std::size_t> valid;
        AngularGap g;
        {
          py::gil_scoped_release nogil;
          valid = valid_cameras(use.scene(), idx, cams, rho_min);
          g = max_angular_gap(fibonacci_lattice(K), headings(cams, valid, c));
        }
        py::dict d = gap_dict(g);
        d["valid"] = index_array(std::vector<Index>(valid.begin(), valid.end()));
        return d;
      },
      py::arg("scene"), py::arg("indices"), py::arg("cameras"), py::arg("center"), py::arg("rho_min") = 0.2f,
      py::arg("K") = 2000, "Sec. 3.3.2: valid cameras (A.1), their headings (A.2) and Delta_max (Eq. 6).");
  m.def(
      "estimate_scene_up",
      [](py::object cameras) { return vec3_array(estimate_scene_up(cameras_from(cameras))); }, py::arg("cameras"),
      "The scene's up: the normalised mean of the cameras' up (-y) directions.");
  m.def(
      "spiral_cameras",
      [](py::object center, float radius, py::object up, py::object reference, py::object params) {
        const VcarParams p = params_from(params);
        return camera_list(spiral_cameras(sphere_from(center, radius), vec3_from(up, "up"),
                                          camera_arg(reference, "reference"), p));
      },
      py::arg("center"), py::arg("radius"), py::arg("up"), py::arg("reference"), py::arg("params") = py::none(),
      "Eq. 7-8: S1 x S2 cameras on a spherical spiral around the object, looking at its centre\n"
      "(S1, S2, phi_s_deg, phi_e_deg, spiral_variant, sampled_intrinsics from params), named sss_000...");
  m.def(
      "gap_directed_cameras",
      [](py::object center, float radius, py::object up, py::object gap_direction, py::object reference, py::object params) {
        const VcarParams p = params_from(params);
        const Intrinsics k = sampled_view_intrinsics(camera_arg(reference, "reference"), p.sampled_intrinsics, p.sampled_fov_deg);
        return camera_list(gap_directed_cameras(sphere_from(center, radius), vec3_from(up, "up"),
                                                vec3_from(gap_direction, "gap_direction"), k, p.gap_directed_views,
                                                p.gap_directed_cone_deg));
      },
      py::arg("center"), py::arg("radius"), py::arg("up"), py::arg("gap_direction"), py::arg("reference"),
      py::arg("params") = py::none(),
      "Beyond the paper: gap_directed_views cameras in a cone of gap_directed_cone_deg around the gap direction.");

  py::class_<AbrPy>(m, "BoundaryRefinement", R"doc(
Axis-aware boundary refinement (Eq. 9-14, B): for each candidate, the views whose mask holds
its centre; a candidate whose projected ellipse overflows the mask in more than rho of them gets
its dominant 3D axis shrunk by the smallest factor over the views (clamped to [f_min, 1]).
`params` as vcar.segment's (sigma_c, rho, f_min, boundary_samples, abr_variant, abr_lowpass).
The candidates' geometry is copied at construction.)doc")
      .def(py::init([](py::object scene, py::object candidates, py::object params) {
             return std::make_unique<AbrPy>(scene_from(scene), candidates, params);
           }),
           py::arg("scene"), py::arg("candidates") = py::none(), py::arg("params") = py::none())
      .def("add_view", &AbrPy::add_view, py::arg("camera"), py::arg("mask"))
      .def("finish", &AbrPy::finish,
           "{'log_scales': (M, 3) float32 refined (Eq. 14), 'flagged', 'compressed', 'axis_compressed': uint8 bit d = axis d}")
      .def("__len__", [](const AbrPy& a) { return a.abr().size(); })
      .def_property_readonly("views", [](const AbrPy& a) { return a.abr().views(); })
      .def_property_readonly("candidates", [](const AbrPy& a) { return index_array(a.abr().candidates()); })
      .def("n_vis", [](const AbrPy& a) { return column<std::uint16_t>(a.abr().size(), [&](std::size_t k) { return a.abr().n_vis(k); }); },
           "views whose mask holds each candidate's centre, uint16")
      .def("n_ovf", [](const AbrPy& a) { return column<std::uint16_t>(a.abr().size(), [&](std::size_t k) { return a.abr().n_ovf(k); }); },
           "of those, views where its ellipse overflows the mask, uint16");
}

}  // namespace vcar::python
