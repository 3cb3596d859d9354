// vcar's JavaScript API (embind). Built by examples/web/CMakeLists.txt with emscripten into
// vcar.js (WebAssembly embedded, ES module factory `createVcar`). docs/web.md documents it:
//
//   const vcar = await createVcar();
//   const s = new vcar.Session();
//   s.loadScene(bytes, "scene.ply");            // PLY, compressed PLY, SPZ (gunzipped v2/v3), .splat
//   s.loadCameras(bytes, "cameras.json");       // or transforms.json; optional
//   const cam = s.referenceView("NAME");        // or s.defaultView(w, h), or a camera from the viewer
//   s.segment(cam, u, v, {maxSide: 400}, p => postMessage(p));   // progress: {stage, view, views, elapsed}
//   s.segmentObjects(cam, [{click: [u, v]}, {box: [x0, y0, x1, y1]}], {}, null);  // several at once
//   s.objectIndices(k);                         // Uint32Array: object k of the latest segmentObjects
//   s.render(cam);                              // {width, height, rgb, alpha, depth}: vcar's own render
//   s.indices(); s.scores(); s.logScales();     // Uint32Array, Float32Array, Float32Array (3 x n)
//   s.scenePly();                               // the whole scene as Inria PLY (the viewer's fallback)
//   s.objectPly(); s.removedPly(); s.statePly();// Uint8Array (Inria PLY; state PLY for SuperSplat)
//
// A camera is {name, width, height, fx, fy, cx, cy, R: [9, world-to-camera, row-major], t: [3]}
// in the OpenCV axes of conventions §2 (x right, y down, z forward).
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include "web_flow.hpp"

using emscripten::val;

namespace {

std::vector<std::uint8_t> bytes_of(const val& a) { return emscripten::convertJSArrayToNumberVector<std::uint8_t>(a); }

template <class T>
val typed_copy(const std::vector<T>& v) {  // a JS-owned copy (the memory view dies with the vector)
  return val(emscripten::typed_memory_view(v.size(), v.data())).call<val>("slice");
}

val camera_to_js(const vcar::Camera& c) {
  val o = val::object();
  o.set("name", c.name);
  o.set("width", c.width); o.set("height", c.height);
  o.set("fx", c.fx); o.set("fy", c.fy); o.set("cx", c.cx); o.set("cy", c.cy);
  val R = val::array(), t = val::array();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R.call<void>("push", c.R_w(i, j));
    t.call<void>("push", c.t_w[i]);
  }
  o.set("R", R); o.set("t", t);
  return o;
}

vcar::Camera camera_from_js(const val& o) {
  vcar::Camera c;
  c.name = o["name"].isUndefined() ? std::string("viewer") : o["name"].as<std::string>();
  c.width = o["width"].as<int>(); c.height = o["height"].as<int>();
  c.fx = o["fx"].as<float>(); c.fy = o["fy"].as<float>(); c.cx = o["cx"].as<float>(); c.cy = o["cy"].as<float>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c.R_w(i, j) = o["R"][i * 3 + j].as<float>();
    c.t_w[i] = o["t"][i].as<float>();
  }
  return c;
}

class JsSession {
public:
  int loadScene(const val& bytes, const std::string& name) { return static_cast<int>(s_.load_scene(bytes_of(bytes), name)); }
  int loadCameras(const val& bytes, const std::string& name) { return static_cast<int>(s_.load_cameras(bytes_of(bytes), name)); }
  void clearCameras() { s_.clear_cameras(); }
  std::string format() const { return s_.format_name(); }
  int size() const { return static_cast<int>(s_.scene().size()); }
  val cameraNames() const {
    val a = val::array();
    for (const auto& c : s_.cameras()) a.call<void>("push", c.name);
    return a;
  }
  val referenceView(const std::string& name) const { return camera_to_js(vcar::web::reference_view(s_, name)); }
  val defaultView(int w, int h) const { return camera_to_js(s_.default_view(w, h)); }

  // Runs vcar::segment; `progress(p)` gets {stage, view, views, elapsed} between stages and views.
  // u or v NaN: no click (options.box is the prompt).
  val segment(const val& camera, float u, float v, const val& options, const val& progress) {
    const vcar::web::FrameMaskFn custom = frame_hook(options, val::null());
    const vcar::SegmentationResult& r = s_.segment(camera_from_js(camera), u, v, options_of(options), progress_of(progress), custom);
    val d = diagnostics_of(r);
    const vcar::web::TimingSplit split = vcar::web::timing_split(r.diagnostics);  // vcar::segment's seconds, three ways
    val sp = val::object();
    sp.set("renders", split.renders);
    sp.set("segmenter", split.segmenter);
    sp.set("vcar", split.vcar);
    sp.set("total", split.total);
    d.set("split", sp);
    return d;
  }
  // Several objects in one run (vcar::segment_objects): prompts = [{click: [u, v] | null,
  // box: [x0, y0, x1, y1] | null, name}], each on `camera`. Returns one diagnostics object per
  // prompt; objectIndices(k) gives object k's selection. The segmenter hook's frame gets
  // `object` (the prompt's index).
  val segmentObjects(const val& camera, const val& prompts, const val& options, const val& progress) {
    std::vector<vcar::web::ObjectClick> objects;
    const int count = prompts["length"].as<int>();
    for (int k = 0; k < count; ++k) {
      const val q = prompts[k];
      vcar::web::ObjectClick o;
      if (!q["click"].isUndefined() && !q["click"].isNull()) {
        const std::vector<float> c = emscripten::convertJSArrayToNumberVector<float>(q["click"]);
        if (c.size() != 2) throw vcar::Error("must be [u, v]", "prompts[" + std::to_string(k) + "].click");
        o.u = c[0], o.v = c[1];
      }
      o.box = box_of(q["box"], "prompts[" + std::to_string(k) + "].box");
      if (!q["name"].isUndefined()) o.name = q["name"].as<std::string>();
      objects.push_back(std::move(o));
    }
    vcar::web::ObjectFrameMaskFn custom;
    if (is_function(options, "segmenter")) {
      std::vector<vcar::web::FrameMaskFn> hooks;  // one per object, made once
      for (int k = 0; k < count; ++k) hooks.push_back(frame_hook(options, val(k)));
      custom = [hooks = std::move(hooks)](std::size_t object, std::size_t k, const vcar::Camera& cam,
                                          const vcar::ImageRGB8& rgb, const vcar::Prompt& p, bool subset,
                                          const vcar::web::FrameBox& box) {
        return hooks.at(object)(k, cam, rgb, p, subset, box);
      };
    }
    const vcar::MultiSegmentation& m = s_.segment_objects(camera_from_js(camera), objects, options_of(options),
                                                          progress_of(progress), custom);
    val out = val::array();
    for (const vcar::SegmentationResult& r : m.objects) out.call<void>("push", diagnostics_of(r));
    return out;
  }
  val objectIndices(int k) const {
    const auto& objects = s_.objects().objects;
    if (k < 0 || static_cast<std::size_t>(k) >= objects.size())
      throw vcar::Error("no object " + std::to_string(k) + " (" + std::to_string(objects.size()) + " segmented)", "objectIndices");
    const auto& ix = objects[static_cast<std::size_t>(k)].indices;
    return typed_copy(std::vector<std::uint32_t>(ix.begin(), ix.end()));
  }
  // {width, height, rgb: Uint8Array (w*h*3), alpha: Float32Array, depth: Float32Array (expected depth)}
  val render(const val& camera) const {
    const vcar::RenderOutput out = s_.render(camera_from_js(camera));
    std::vector<float> z(out.alpha.data.size());
    for (std::size_t i = 0; i < z.size(); ++i) z[i] = out.alpha.data[i] > 0.f ? out.depth.data[i] / out.alpha.data[i] : 0.f;
    val o = val::object();
    o.set("width", out.rgb.width);
    o.set("height", out.rgb.height);
    o.set("rgb", typed_copy(vcar::to_8bit(out.rgb).data));
    o.set("alpha", typed_copy(out.alpha.data));
    o.set("depth", typed_copy(z));
    return o;
  }
  val indices() const {
    const auto& ix = s_.result().indices;
    return typed_copy(std::vector<std::uint32_t>(ix.begin(), ix.end()));
  }
  val scores() const { return typed_copy(s_.result().scores); }
  val logScales() const {  // column-major: x of every selected Gaussian, then y, then z
    const auto& ls = s_.result().log_scale;
    std::vector<float> all;
    for (const auto& c : ls) all.insert(all.end(), c.begin(), c.end());
    return typed_copy(all);
  }
  val views() const {
    val a = val::array();
    for (const auto& c : s_.views()) a.call<void>("push", camera_to_js(c));
    return a;
  }
  val objectPly() { return typed_copy(s_.object_ply()); }
  val removedPly() { return typed_copy(s_.removed_ply()); }
  val statePly() { return typed_copy(s_.state_ply()); }
  val scenePly() { return typed_copy(s_.scene_ply()); }

private:
  static bool is_object(const val& v) { return v.typeOf().as<std::string>() == "object" && !v.isNull(); }
  static bool is_function(const val& options, const char* key) {
    return is_object(options) && options[key].typeOf().as<std::string>() == "function";
  }
  static std::optional<Eigen::Vector4f> box_of(const val& b, const std::string& where) {
    if (b.isUndefined() || b.isNull()) return std::nullopt;
    const std::vector<float> x = emscripten::convertJSArrayToNumberVector<float>(b);
    if (x.size() != 4) throw vcar::Error("must be [x0, y0, x1, y1]", where);
    return Eigen::Vector4f(x[0], x[1], x[2], x[3]);
  }
  static vcar::web::SegmentOptions options_of(const val& options) {
    vcar::web::SegmentOptions opt;
    if (!is_object(options)) return opt;
    if (!options["maxSide"].isUndefined()) opt.max_side = options["maxSide"].as<int>();
    if (!options["orbitViews"].isUndefined()) opt.orbit_views = options["orbitViews"].as<int>();
    if (!options["colourTol"].isUndefined()) opt.grow.colour_tol = options["colourTol"].as<float>();
    if (!options["depthStep"].isUndefined()) opt.grow.depth_step = options["depthStep"].as<float>();
    if (!options["clickBox"].isUndefined()) opt.click_box = options["clickBox"].as<bool>();
    opt.box = box_of(options["box"], "options.box");
    return opt;
  }
  // progress(p) gets {stage, view, views, elapsed}; returning false cancels.
  static vcar::ProgressCallback progress_of(const val& progress) {
    if (progress.typeOf().as<std::string>() != "function") return {};
    return [progress](const vcar::Progress& p) {
      val o = val::object();
      o.set("stage", std::string(p.stage));
      o.set("view", static_cast<int>(p.view));
      o.set("views", static_cast<int>(p.views));
      o.set("elapsed", p.elapsed_s);
      const val r = progress(o);
      return !(r.isFalse());
    };
  }
  // The JavaScript segmenter hook (docs/web.md): options.segmenter(frame) -> Uint8Array | null,
  // frame = {index, camera, width, height, rgb (Uint8Array, w*h*3), click: [u, v] | null,
  // box: [x0, y0, x1, y1] | null, fine, object} (fine: the fine round, whose frames render the
  // coarse selection only; box: the prompt's box in this frame, lifted from the reference view;
  // object: the prompt's index with segmentObjects, else null). None without options.segmenter.
  static vcar::web::FrameMaskFn frame_hook(const val& options, const val& object) {
    if (!is_function(options, "segmenter")) return {};
    const val fn = options["segmenter"];
    return [fn, object](std::size_t k, const vcar::Camera& cam, const vcar::ImageRGB8& rgb, const vcar::Prompt& p, bool subset,
                        const vcar::web::FrameBox& box) -> std::optional<vcar::Mask> {
      val f = val::object();
      f.set("index", static_cast<int>(k));
      f.set("camera", camera_to_js(cam));
      f.set("width", cam.width);
      f.set("height", cam.height);
      f.set("rgb", typed_copy(rgb.data));
      if (!p.points.empty()) {
        val click = val::array();
        click.call<void>("push", p.points.front()[0]);
        click.call<void>("push", p.points.front()[1]);
        f.set("click", click);
      } else {
        f.set("click", val::null());
      }
      if (box) {
        val b = val::array();
        for (int c = 0; c < 4; ++c) b.call<void>("push", (*box)[c]);
        f.set("box", b);
      } else {
        f.set("box", val::null());
      }
      f.set("fine", subset);
      f.set("object", object);
      const val m = fn(f);
      if (m.isNull() || m.isUndefined()) return std::nullopt;
      vcar::Mask mask(cam.width, cam.height, 1);
      mask.data = emscripten::convertJSArrayToNumberVector<std::uint8_t>(m);
      if (mask.data.size() != mask.pixels())
        throw vcar::Error("the JavaScript segmenter returned " + std::to_string(mask.data.size()) + " bytes for a " +
                          std::to_string(cam.width) + "x" + std::to_string(cam.height) + " frame", "options.segmenter");
      return mask;
    };
  }
  static val diagnostics_of(const vcar::SegmentationResult& r) {
    const auto& d = r.diagnostics;
    val o = val::object();
    o.set("selected", static_cast<int>(r.indices.size()));
    o.set("coarse", static_cast<int>(d.n_coarse));
    o.set("fine", static_cast<int>(d.n_fine));
    o.set("sss", d.sss_triggered);
    o.set("maxGapDeg", d.max_gap_deg);
    o.set("masksMissing", static_cast<int>(d.masks_missing));
    o.set("note", d.note);
    val t = val::object();
    for (const auto& [k, s] : d.timings_s) t.set(k, s);
    o.set("timings", t);
    return o;
  }
  vcar::web::Session s_;  // its own scratch folder in the in-memory file system
};

std::string simd_path() {
#if defined(VCAR_SIMD_SCALAR)
#if defined(__wasm_simd128__)
  return "scalar path, compiled with -msimd128 (LLVM auto-vectorises to WebAssembly SIMD)";
#else
  return "scalar path";
#endif
#else
  return vcar::simd::isa_name();
#endif
}

// The message of a C++ exception thrown through embind (emscripten passes its pointer).
std::string exception_message(std::intptr_t p) { return reinterpret_cast<std::exception*>(p)->what(); }

}  // namespace

EMSCRIPTEN_BINDINGS(vcar_web) {
  emscripten::class_<JsSession>("Session")
      .constructor<>()
      .function("loadScene", &JsSession::loadScene)
      .function("loadCameras", &JsSession::loadCameras)
      .function("clearCameras", &JsSession::clearCameras)
      .function("format", &JsSession::format)
      .function("size", &JsSession::size)
      .function("cameraNames", &JsSession::cameraNames)
      .function("referenceView", &JsSession::referenceView)
      .function("defaultView", &JsSession::defaultView)
      .function("segment", &JsSession::segment)
      .function("segmentObjects", &JsSession::segmentObjects)
      .function("objectIndices", &JsSession::objectIndices)
      .function("render", &JsSession::render)
      .function("indices", &JsSession::indices)
      .function("scores", &JsSession::scores)
      .function("logScales", &JsSession::logScales)
      .function("views", &JsSession::views)
      .function("objectPly", &JsSession::objectPly)
      .function("removedPly", &JsSession::removedPly)
      .function("statePly", &JsSession::statePly)
      .function("scenePly", &JsSession::scenePly);
  emscripten::function("simdPath", &simd_path);
  emscripten::function("exceptionMessage", &exception_message);
}
