// vcar.segment: the pipeline (algo/pipeline.hpp) with Python or built-in segmenters and renderers.
//
// The pipeline runs with the GIL released. A Python segmenter, renderer or progress callable is
// called back with the GIL taken again; an exception it raises waits in an ErrorStash while the
// C++ stack unwinds (as PythonRaised, a vcar::Error the pipeline passes through) and is raised
// again, unchanged, when vcar.segment returns. Ctrl-C: the progress hook, called between views
// and stages, runs Python's signal handlers (KeyboardInterrupt stops the pipeline the same way).
#include <pybind11/stl.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "common.hpp"
#include "params.hpp"
#include "result.hpp"
#include "segmenters.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/algo/segment_objects.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"

namespace vcar::python {

namespace {

// What a Python renderer receives.
struct RenderRequestPy {
  py::object camera;      // vcar.Camera
  py::object subset;      // int64 (M,) scene indices, or None (every Gaussian)
  py::object log_scales;  // float32 (M, 3) replacing those Gaussians' log-scales, or None
  py::object background;  // float32 (3,)
  py::object scene;       // vcar.Scene
  bool want_depth = false;
};

// What a progress callable receives.
struct ProgressPy {
  std::string stage;
  std::size_t view = 0, views = 0;
  double elapsed_s = 0;
};

class PythonRenderer {
public:
  PythonRenderer(py::object fn, py::object scene, ErrorStash& stash) : fn_(std::move(fn)), scene_(std::move(scene)), stash_(&stash) {}

  RenderOutput render(const RenderRequest& q) {
    py::gil_scoped_acquire gil;
    const Camera& cam = *q.camera;
    const std::string where = "renderer, view '" + cam.name + "'";
    auto req = std::make_shared<RenderRequestPy>();
    req->camera = py::cast(cam);
    req->subset = q.subset ? py::object(index_array(*q.subset)) : py::object(py::none());
    if (q.log_scale) {
      const auto m = static_cast<py::ssize_t>((*q.log_scale)[0].size());
      py::array_t<float> ls({m, py::ssize_t{3}});
      for (py::ssize_t k = 0; k < m; ++k)
        for (int d = 0; d < 3; ++d) ls.mutable_data()[k * 3 + d] = (*q.log_scale)[d][k];
      req->log_scales = ls;
    } else {
      req->log_scales = py::none();
    }
    req->background = vec3_array(q.background);
    req->scene = scene_;
    req->want_depth = q.want_depth;
    py::object out;
    try {
      out = fn_(py::cast(req));
    } catch (py::error_already_set& e) {
      stash_->keep_and_throw(std::move(e), where);
    }
    py::object rgb, alpha, depth = py::none();
    if (py::isinstance<py::dict>(out)) {
      py::dict d = out;
      if (!d.contains("rgb") || !d.contains("alpha")) throw Error("the returned dict needs 'rgb' and 'alpha'", where);
      rgb = d["rgb"];
      alpha = d["alpha"];
      if (d.contains("depth")) depth = d["depth"];
    } else if ((py::isinstance<py::tuple>(out) || py::isinstance<py::list>(out)) && (py::len(out) == 2 || py::len(out) == 3)) {
      rgb = out[py::int_(0)];
      alpha = out[py::int_(1)];
      if (py::len(out) == 3) depth = out[py::int_(2)];
    } else {
      throw Error("must return {'rgb', 'alpha'[, 'depth']} or (rgb, alpha[, depth]), got a " +
                      py::str(py::type::of(out).attr("__name__")).cast<std::string>(), where);
    }
    RenderOutput r;
    r.rgb = float_image(rgb, cam.width, cam.height, 3, where + ": rgb");
    r.alpha = float_image(alpha, cam.width, cam.height, 1, where + ": alpha");
    if (q.want_depth && !depth.is_none()) r.depth = float_image(depth, cam.width, cam.height, 1, where + ": depth");
    return r;
  }

private:
  py::object fn_, scene_;
  ErrorStash* stash_;
};
static_assert(Renderer<PythonRenderer>);

class PythonSegmenter {
public:
  PythonSegmenter(py::object fn, py::dict prompt, ErrorStash& stash) : fn_(std::move(fn)), prompt_(std::move(prompt)), stash_(&stash) {}

  void segment(const FrameSequence& frames, const Prompt&, const MaskSink& sink) {
    py::gil_scoped_acquire gil;
    const std::string round = frames.subset ? "fine round" : "coarse round";
    auto req = std::make_shared<SegmentationRequest>();
    req->frames = &frames;
    req->stash = stash_;
    req->cameras = camera_list(std::vector<Camera>(frames.cameras.begin(), frames.cameras.end()));
    req->prompt = prompt_;
    req->round = frames.subset ? "fine" : "coarse";
    struct Close {  // the request's frames die with this call
      SegmentationRequest* r;
      ~Close() { r->frames = nullptr; }
    } close{req.get()};

    py::object result;
    try {
      result = fn_(py::cast(req));
    } catch (py::error_already_set& e) {
      stash_->keep_and_throw(std::move(e), "segmenter, " + round);
    }
    if (result.is_none())
      throw Error("the segmenter returned None; it must return one mask (or None) per frame", round);
    py::object it = py::reinterpret_steal<py::object>(PyObject_GetIter(result.ptr()));
    if (!it) {
      PyErr_Clear();
      throw Error("the segmenter returned a " + py::str(py::type::of(result).attr("__name__")).cast<std::string>() +
                      ", expected a list (or iterable) of masks, one per frame", round);
    }
    const std::size_t n = frames.size();
    std::size_t k = 0;
    for (;; ++k) {
      py::object item = py::reinterpret_steal<py::object>(PyIter_Next(it.ptr()));
      if (!item) {
        if (PyErr_Occurred()) stash_->keep_and_throw(py::error_already_set(), "segmenter, " + round + ", frame " + std::to_string(k));
        break;
      }
      if (k >= n) throw Error("the segmenter returned more than " + std::to_string(n) + " masks for " + std::to_string(n) + " frames", round);
      const Camera& cam = frames.cameras[k];
      if (item.is_none()) {
        py::gil_scoped_release nogil;
        sink(k, nullptr);
        continue;
      }
      const Mask m = mask_from(item, cam.width, cam.height,
                               "mask of frame " + std::to_string(k) + " (view '" + cam.name + "', " + round + ")");
      py::gil_scoped_release nogil;
      sink(k, &m);
    }
    if (k != n)
      throw Error("the segmenter returned " + std::to_string(k) + " masks for " + std::to_string(n) +
                      " frames (give None for a frame without a mask)", round);
  }

private:
  py::object fn_;
  py::dict prompt_;
  ErrorStash* stash_;
};
static_assert(Segmenter<PythonSegmenter>);

// The prompt dict -> Prompt, and its normalised form for request.prompt.
Prompt prompt_from(py::handle obj, const std::vector<Camera>& cams, py::dict& normalised) {
  Prompt p;
  py::dict d;
  if (!obj.is_none()) {
    if (!py::isinstance<py::dict>(obj))
      throw Error("must be a dict (reference_view, points, point_labels, box, text) or None", "prompt");
    d = py::reinterpret_borrow<py::dict>(obj);
  }
  for (auto item : d) {
    const std::string key = py::str(item.first).cast<std::string>();
    if (key != "reference_view" && key != "points" && key != "point_labels" && key != "box" && key != "text")
      throw Error("unknown key '" + key + "'; valid: reference_view, points, point_labels, box, text", "prompt");
  }
  if (d.contains("reference_view")) {
    py::object r = d["reference_view"];
    if (py::isinstance<py::str>(r)) {
      const std::string name = r.cast<std::string>();
      std::size_t k = 0;
      while (k < cams.size() && cams[k].name != name) ++k;
      if (k == cams.size())
        throw Error("no camera named '" + name + "' (" + std::to_string(cams.size()) + " cameras, the first '" +
                        cams.front().name + "')", "prompt['reference_view']");
      p.reference_view = k;
    } else {
      const std::vector<Index> k = index_vector(py::make_tuple(r), cams.size(), "prompt['reference_view']");
      p.reference_view = k.front();
    }
  }
  const Camera& ref = cams[p.reference_view];
  py::array_t<float> points(std::vector<py::ssize_t>{0, 2});
  py::array_t<std::int32_t> labels(py::ssize_t{0});
  if (d.contains("points")) {
    const auto a = real_array(d["points"], {-1, 2}, "prompt['points']");
    const py::ssize_t n = a.shape(0);
    points = py::array_t<float>({n, py::ssize_t{2}});
    for (py::ssize_t i = 0; i < n; ++i) {
      const float u = static_cast<float>(a.data()[i * 2]), v = static_cast<float>(a.data()[i * 2 + 1]);
      if (!inside_image(u, v, ref.width, ref.height))
        throw Error("point " + std::to_string(i) + " (" + std::to_string(u) + ", " + std::to_string(v) +
                        ") lies outside view '" + ref.name + "' (" + std::to_string(ref.width) + "x" +
                        std::to_string(ref.height) + ")", "prompt['points']");
      points.mutable_data()[i * 2] = u;
      points.mutable_data()[i * 2 + 1] = v;
      p.points.emplace_back(u, v);
    }
    labels = py::array_t<std::int32_t>(n);
    for (py::ssize_t i = 0; i < n; ++i) labels.mutable_data()[i] = 1;
  }
  if (d.contains("point_labels")) {
    const auto a = real_array(d["point_labels"], {static_cast<py::ssize_t>(p.points.size())}, "prompt['point_labels']");
    for (std::size_t i = 0; i < p.points.size(); ++i) {
      const double l = a.data()[i];
      if (l != 0.0 && l != 1.0) throw Error("labels are 1 (positive) or 0 (negative), got " + std::to_string(l), "prompt['point_labels']");
      labels.mutable_data()[i] = static_cast<std::int32_t>(l);
    }
  }
  for (std::size_t i = 0; i < p.points.size(); ++i) p.point_labels.push_back(labels.data()[i]);
  py::object box = py::none();
  if (d.contains("box") && !d["box"].is_none()) {
    const auto a = real_array(d["box"], {4}, "prompt['box']");
    const double* b = a.data();
    if (!(b[0] <= b[2] && b[1] <= b[3])) throw Error("must be (x0, y0, x1, y1) with x0 <= x1 and y0 <= y1", "prompt['box']");
    p.box = Eigen::Vector4f(static_cast<float>(b[0]), static_cast<float>(b[1]), static_cast<float>(b[2]), static_cast<float>(b[3]));
    py::array_t<float> bx(4);
    for (int i = 0; i < 4; ++i) bx.mutable_data()[i] = (*p.box)[i];
    box = bx;
  }
  if (d.contains("text")) {
    if (!py::isinstance<py::str>(d["text"])) throw Error("must be a string", "prompt['text']");
    p.text = d["text"].cast<std::string>();
  }
  normalised["reference_view"] = p.reference_view;
  normalised["reference_name"] = ref.name;
  normalised["points"] = points;
  normalised["point_labels"] = labels;
  normalised["box"] = box;
  normalised["text"] = p.text;
  return p;
}

// The pipeline's progress callback: Python's signal handlers (Ctrl-C) and the user's callable,
// with the GIL taken.
ProgressCallback progress_hook(py::object progress, ErrorStash& stash) {
  return [progress, &stash](const Progress& pg) -> bool {
    py::gil_scoped_acquire gil;
    const std::string at = std::string(pg.stage) + (pg.views ? ", view " + std::to_string(pg.view) + "/" + std::to_string(pg.views) : "");
    if (PyErr_CheckSignals() != 0) stash.keep_and_throw(py::error_already_set(), at);  // Ctrl-C
    if (progress.is_none()) return true;
    py::object r;
    try {
      r = progress(ProgressPy{std::string(pg.stage), pg.view, pg.views, pg.elapsed_s});
    } catch (py::error_already_set& e) {
      stash.keep_and_throw(std::move(e), "progress, " + at);
    }
    return !(py::isinstance<py::bool_>(r) && !r.cast<bool>());
  };
}

// One object's segmenter (an oracle or a mask folder run in C++, or a Python callable) behind a
// function: vcar::EachObject takes one type for all objects.
struct ObjectSegmenter {
  std::function<void(const FrameSequence&, const Prompt&, const MaskSink&)> fn;
  void segment(const FrameSequence& f, const Prompt& p, const MaskSink& sink) { fn(f, p, sink); }
};

// vcar.segment's `segmenter` argument (named `where` in errors) as an ObjectSegmenter; a Python
// callable is held in `keep`, with the request's normalised `prompt`.
ObjectSegmenter segmenter_from(py::object seg, py::dict prompt, ErrorStash& stash,
                               std::vector<std::unique_ptr<PythonSegmenter>>& keep, const std::string& where) {
  if (py::isinstance<OracleSegmenterPy>(seg)) {
    synth::OracleSegmenter* s = &*seg.cast<OracleSegmenterPy&>().seg;
    return {[s](const FrameSequence& f, const Prompt& pr, const MaskSink& k) { s->segment(f, pr, k); }};
  }
  if (py::isinstance<MaskFolderSegmenterPy>(seg)) {
    io::MaskFolderSegmenter* s = &*seg.cast<MaskFolderSegmenterPy&>().seg;
    return {[s](const FrameSequence& f, const Prompt& pr, const MaskSink& k) { s->segment(f, pr, k); }};
  }
  if (!PyCallable_Check(seg.ptr()))
    throw Error("must be a callable taking a request (or vcar.synth.OracleSegmenter / vcar.MaskFolderSegmenter)", where);
  keep.push_back(std::make_unique<PythonSegmenter>(seg, prompt, stash));
  PythonSegmenter* s = keep.back().get();
  return {[s](const FrameSequence& f, const Prompt& pr, const MaskSink& k) { s->segment(f, pr, k); }};
}

// The optional callables of vcar.segment and vcar.segment_objects.
void check_callables(const py::object& renderer, const py::object& progress) {
  if (!renderer.is_none() && !PyCallable_Check(renderer.ptr()))
    throw Error("must be None (the CPU renderer) or a callable taking a request", "renderer");
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw Error("must be None or a callable", "progress");
}

// Runs `run(scene, renderer)` with the GIL released on the Python renderer (or the built-in CPU
// one) and returns its result; an exception a Python callable raised inside comes out unchanged.
template <class Run>
auto run_without_gil(py::object scene_obj, Scene& scene, py::object renderer, ErrorStash& stash, Run&& run) {
  std::optional<PythonRenderer> py_renderer;
  if (!renderer.is_none()) py_renderer.emplace(renderer, scene_obj, stash);
  cpu::TiledRenderer cpu_renderer;
  decltype(run(std::declval<const GaussianScene&>(), cpu_renderer)) result{};
  bool raised = false;
  {
    SceneUse use(scene);
    py::gil_scoped_release nogil;
    try {
      result = py_renderer ? run(use.scene(), *py_renderer) : run(use.scene(), cpu_renderer);
    } catch (const PythonRaised&) {
      raised = true;
    }
  }
  if (raised) stash.raise();
  return result;
}

py::dict segment(py::object scene_obj, py::object cameras, py::object prompt, py::object segmenter,
                 py::object renderer, py::object params, py::object progress) {
  Scene& scene = scene_from(scene_obj);
  const std::vector<Camera> cams = cameras_from(cameras);
  if (cams.empty()) throw Error("no cameras", "cameras");
  py::dict prompt_dict;
  const Prompt pr = prompt_from(prompt, cams, prompt_dict);
  const VcarParams p = params_from(params);
  check_callables(renderer, progress);

  ErrorStash stash;  // before the GIL is released: destroyed after it is taken back
  std::vector<std::unique_ptr<PythonSegmenter>> keep;
  ObjectSegmenter seg = segmenter_from(segmenter, prompt_dict, stash, keep, "segmenter");
  const ProgressCallback hook = progress_hook(progress, stash);
  SegmentationResult result = run_without_gil(scene_obj, scene, renderer, stash, [&](const GaussianScene& s, auto& r) {
    return vcar::segment(s, cams, pr, r, seg, p, hook);
  });
  return result_dict(std::move(result), p);
}


py::dict segment_objects(py::object scene_obj, py::object cameras, py::object objects, py::object renderer,
                         py::object params, py::object progress) {
  Scene& scene = scene_from(scene_obj);
  const std::vector<Camera> cams = cameras_from(cameras);
  if (cams.empty()) throw Error("no cameras", "cameras");
  if (!py::isinstance<py::list>(objects) || py::len(objects) == 0)
    throw Error("must be a non-empty list of dicts {name, prompt, segmenter}", "objects");
  const VcarParams p = params_from(params);
  check_callables(renderer, progress);

  ErrorStash stash;  // before the GIL is released: destroyed after it is taken back
  std::vector<ObjectPrompt> prompts;
  std::vector<ObjectSegmenter> per;
  std::vector<std::unique_ptr<PythonSegmenter>> py_segmenters;
  py::list names;
  for (std::size_t o = 0; o < py::len(objects); ++o) {
    const std::string where = "objects[" + std::to_string(o) + "]";
    py::handle item = py::list(objects)[o];
    if (!py::isinstance<py::dict>(item)) throw Error("must be a dict {name, prompt, segmenter}", where);
    const py::dict d = py::reinterpret_borrow<py::dict>(item);
    for (auto kv : d) {
      const std::string key = py::str(kv.first).cast<std::string>();
      if (key != "name" && key != "prompt" && key != "segmenter")
        throw Error("unknown key '" + key + "' (name, prompt, segmenter)", where);
    }
    if (!d.contains("segmenter")) throw Error("needs a 'segmenter'", where);
    ObjectPrompt op;
    op.name = d.contains("name") ? py::str(d["name"]).cast<std::string>() : "object_" + std::to_string(o);
    py::dict normalised;
    op.prompt = prompt_from(d.contains("prompt") ? py::object(d["prompt"]) : py::object(py::none()), cams, normalised);
    per.push_back(segmenter_from(d["segmenter"], normalised, stash, py_segmenters, where + "['segmenter']"));
    names.append(op.name);
    prompts.push_back(std::move(op));
  }
  const ProgressCallback hook = progress_hook(progress, stash);
  MultiSegmentation result = run_without_gil(scene_obj, scene, renderer, stash, [&](const GaussianScene& s, auto& r) {
    EachObject<ObjectSegmenter> each(per);
    return vcar::segment_objects(s, cams, prompts, r, each, p, hook);
  });
  py::list out_objects;
  for (std::size_t o = 0; o < result.objects.size(); ++o) {
    py::dict r = result_dict(std::move(result.objects[o]), p);
    r["name"] = names[o];
    r["lost_to_others"] = result.lost[o];
    out_objects.append(r);
  }
  py::dict t;
  for (const auto& [stage, sec] : result.timings_s) t[py::str(stage)] = sec;
  py::dict out;
  out["objects"] = out_objects;
  out["conflicts"] = result.conflicts;
  out["segmenter_calls"] = result.segmenter_calls;
  out["timings_s"] = t;
  return out;
}
}  // namespace

py::dict result_dict(SegmentationResult&& r, const VcarParams& params) {
  const auto m = static_cast<py::ssize_t>(r.indices.size());
  py::dict out;
  out["indices"] = index_array(r.indices);
  py::array_t<float> ls({m, py::ssize_t{3}});
  for (py::ssize_t k = 0; k < m; ++k)
    for (int d = 0; d < 3; ++d) ls.mutable_data()[k * 3 + d] = r.log_scale[d].empty() ? 0.f : r.log_scale[d][k];
  r.scores.resize(static_cast<std::size_t>(m));
  out["scores"] = adopt(std::move(r.scores), {m});
  out["log_scales"] = ls;
  py::dict d;  // every field of Diagnostics::for_each_field, by its declared name
  Diagnostics::for_each_field(r.diagnostics, [&](const char* name, const char*, const auto& v) {
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, Eigen::Vector3f>) {
      d[name] = vec3_array(v);
    } else if constexpr (std::is_same_v<T, std::vector<Camera>>) {
      d[name] = camera_list(v);
    } else if constexpr (std::is_same_v<T, ObjectSphere>) {
      py::dict sphere;
      sphere["center"] = vec3_array(v.c);
      sphere["radius"] = v.r;
      sphere["inliers"] = v.inliers;
      d[name] = sphere;
    } else if constexpr (std::is_same_v<T, std::vector<std::pair<std::string, double>>>) {
      py::dict t;
      for (const auto& [stage, s] : v) t[py::str(stage)] = s;
      d[name] = t;
    } else {
      d[name] = v;
    }
  });
  d["params"] = params_dict(params);
  out["diagnostics"] = d;
  return out;
}

void register_segment(py::module_& m) {
  py::class_<SegmentationRequest, std::shared_ptr<SegmentationRequest>>(m, "SegmentationRequest", R"doc(
What a segmenter callable receives, once per segmentation round:
  request.cameras   list of vcar.Camera; frame 0 is the reference (prompt) view
  request.image(k)  renders frame k now, (H, W, 3) uint8 (on every call: ask once per frame)
  request.prompt    dict: reference_view (int), reference_name, points (P, 2) float32,
                    point_labels (P,) int32, box (4,) float32 or None, text
  request.round     "coarse" (renders of the whole scene) or "fine" (renders of the coarse
                    selection only: occluders are not drawn)
  request.subset    True in the fine round
  len(request)      the number of frames
It is valid while the segmenter runs.)doc")
      .def("__len__", &SegmentationRequest::size)
      .def_readonly("cameras", &SegmentationRequest::cameras)
      .def_readonly("prompt", &SegmentationRequest::prompt)
      .def_readonly("round", &SegmentationRequest::round)
      .def_property_readonly("subset", [](const SegmentationRequest& r) { return r.round == "fine"; })
      .def(
          "image",
          [](SegmentationRequest& r, std::int64_t k) {
            r.check();
            if (k < 0 || static_cast<std::size_t>(k) >= r.frames->size())
              throw Error("frame " + std::to_string(k) + " out of range (" + std::to_string(r.frames->size()) + " frames)",
                          "request.image");
            ImageRGB8 img;
            try {
              py::gil_scoped_release nogil;
              img = r.frames->image(static_cast<std::size_t>(k));
            } catch (const PythonRaised&) {
              r.stash->raise();  // the Python renderer's own exception, to the segmenter that asked
            }
            return adopt(std::move(img), false);
          },
          py::arg("k"))
      .def("__repr__", [](const SegmentationRequest& r) {
        return "<vcar.SegmentationRequest: " + r.round + " round, " + std::to_string(r.size()) + " frames>";
      });

  py::class_<RenderRequestPy, std::shared_ptr<RenderRequestPy>>(m, "RenderRequest", R"doc(
What a renderer callable receives:
  request.camera      vcar.Camera (OpenCV axes: world_to_camera and K are gsplat's viewmat and K)
  request.subset      int64 (M,) indices of the Gaussians to draw, or None for all
  request.log_scales  float32 (M, 3) log-scales replacing theirs, or None
  request.background  float32 (3,) colour composited behind, in [0, 1]
  request.want_depth  also return depth
  request.scene       the vcar.Scene
The renderer returns {"rgb": (H, W, 3), "alpha": (H, W), "depth": (H, W)} or a tuple (rgb,
alpha[, depth]) of float arrays; rgb in [0, 1], alpha = 1 - final transmittance, depth =
sum z alpha T (gsplat's "D" / "RGB+D", not the alpha-normalised "ED").)doc")
      .def_readonly("camera", &RenderRequestPy::camera)
      .def_readonly("subset", &RenderRequestPy::subset)
      .def_readonly("log_scales", &RenderRequestPy::log_scales)
      .def_readonly("background", &RenderRequestPy::background)
      .def_readonly("want_depth", &RenderRequestPy::want_depth)
      .def_readonly("scene", &RenderRequestPy::scene);

  py::class_<ProgressPy>(m, "Progress", "What a progress callable receives: stage, view, views (0 between stages), elapsed_s.")
      .def_readonly("stage", &ProgressPy::stage)
      .def_readonly("view", &ProgressPy::view)
      .def_readonly("views", &ProgressPy::views)
      .def_readonly("elapsed_s", &ProgressPy::elapsed_s)
      .def("__repr__", [](const ProgressPy& p) {
        return "<vcar.Progress " + p.stage + " " + std::to_string(p.view) + "/" + std::to_string(p.views) + " " +
               std::to_string(p.elapsed_s) + " s>";
      });

  py::class_<MaskFolderSegmenterPy>(m, "MaskFolderSegmenter", R"doc(
Masks from a folder: frame k gets the file whose stem is the stem of its camera's name (.png
before .jpg/.jpeg); no file = no mask (as `vcar segment --masks DIR`). The files are masks of the
captures: frames that render a subset (request.subset, the fine round) get no mask, and the
pipeline keeps G_coarse. Runs in C++ when given to vcar.segment; also a callable taking a
request.)doc")
      .def(py::init([](const std::string& dir) {
             MaskFolderSegmenterPy s;
             s.seg.emplace(dir);
             return s;
           }),
           py::arg("folder"))
      .def("__call__", [](MaskFolderSegmenterPy& s, SegmentationRequest& r) { return run_on_request(*s.seg, r); },
           py::arg("request"));

  m.def("segment_objects", &segment_objects, py::arg("scene"), py::arg("cameras"), py::arg("objects"),
        py::arg("renderer") = py::none(), py::arg("params") = py::none(), py::arg("progress") = py::none(),
        R"doc(Segments several objects in one run (vcar::segment_objects): one coarse round for all
(each training view rendered once), each object's sphere, SSS and fine round, the fine rounds
in one batch, then ABR; a Gaussian two objects select stays with the higher score.

  objects    list of dicts {"name": str, "prompt": as vcar.segment's, "segmenter": as
             vcar.segment's (a callable taking a request, or an oracle / mask folder)}; each
             segmenter is asked about its own object only
  scene, cameras, renderer, params, progress: as vcar.segment

Returns {"objects": [vcar.segment's result dict + "name", "lost_to_others" (Gaussians it
gave up to another object)], "conflicts": Gaussians selected by more than one object,
"segmenter_calls": the rounds (2 with fine rounds; each object's segmenter is called once a round), "timings_s": the
shared coarse round}. Each object's result equals vcar.segment's with the same masks, less
what it lost to others.)doc");

  m.def("segment", &segment, py::arg("scene"), py::arg("cameras"), py::arg("prompt"), py::arg("segmenter"),
        py::arg("renderer") = py::none(), py::arg("params") = py::none(), py::arg("progress") = py::none(),
        R"doc(Segments the object prompted on one view: the VCAR pipeline (paper Sec. 3.1).

  scene      vcar.Scene
  cameras    list of vcar.Camera (the training views)
  prompt     dict: reference_view (camera name or index, default 0), points [[u, v], ...]
             (pixels of the reference view), point_labels (1 positive, 0 negative; default 1),
             box [x0, y0, x1, y1], text; or None
  segmenter  callable(request) -> one mask (bool/uint8 (H, W)) or None per frame, as a list or
             any iterable (a generator streams); or vcar.synth.OracleSegmenter /
             vcar.MaskFolderSegmenter (run in C++)
  renderer   None (the built-in CPU renderer) or callable(render_request) -> rgb/alpha/depth
  params     None (vcar.DEFAULT_PRESET), a preset name, a dict of overrides, (preset, dict)
  progress   callable(vcar.Progress) between views and stages; returning False cancels
             (vcar.Cancelled)

Returns {"indices": int64 (M,) ascending scene indices, "scores": float32 (M,) vote ratios,
"log_scales": float32 (M, 3) refined by ABR, "diagnostics": dict}. Runs without the GIL except
inside the callables; Ctrl-C raises KeyboardInterrupt between views; an exception raised by a
callable comes out unchanged (with a note naming the round and view).)doc");
}

}  // namespace vcar::python
