// vcar's JavaScript API (embind). Built by examples/web/CMakeLists.txt with emscripten into
// vcar.js (WebAssembly embedded, ES module factory `createVcar`). docs/web.md documents it:
//
//   const vcar = await createVcar();
//   const s = new vcar.Session();
//   s.loadScene(bytes, "scene.ply");            // PLY, compressed PLY, SPZ (gunzipped v2/v3), .splat
//   s.loadCameras(bytes, "cameras.json");       // or transforms.json; optional
//   const cam = s.referenceView("NAME");        // or s.defaultView(w, h), or a camera from the viewer
//   s.segment(cam, u, v, {maxSide: 400}, p => postMessage(p));   // progress: {stage, view, views, elapsed}
//   s.render(cam);                              // {width, height, rgb, alpha, depth}: vcar's own render
//   s.indices(); s.scores(); s.logScales();     // Uint32Array, Float32Array, Float32Array (3 x n)
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
  val segment(const val& camera, float u, float v, const val& options, const val& progress) {
    vcar::web::SegmentOptions opt;
    if (options.typeOf().as<std::string>() == "object") {
      if (!options["maxSide"].isUndefined()) opt.max_side = options["maxSide"].as<int>();
      if (!options["orbitViews"].isUndefined()) opt.orbit_views = options["orbitViews"].as<int>();
      if (!options["colourTol"].isUndefined()) opt.grow.colour_tol = options["colourTol"].as<float>();
      if (!options["depthStep"].isUndefined()) opt.grow.depth_step = options["depthStep"].as<float>();
      if (!options["box"].isUndefined() && !options["box"].isNull()) {
        const std::vector<float> b = emscripten::convertJSArrayToNumberVector<float>(options["box"]);
        if (b.size() != 4) throw vcar::Error("must be [x0, y0, x1, y1]", "options.box");
        opt.box = Eigen::Vector4f(b[0], b[1], b[2], b[3]);
      }
    }
    vcar::ProgressCallback cb;
    if (progress.typeOf().as<std::string>() == "function")
      cb = [&](const vcar::Progress& p) {
        val o = val::object();
        o.set("stage", std::string(p.stage));
        o.set("view", static_cast<int>(p.view));
        o.set("views", static_cast<int>(p.views));
        o.set("elapsed", p.elapsed_s);
        const val r = progress(o);
        return !(r.isFalse());
      };
    // The JavaScript segmenter hook (docs/web.md): options.segmenter(frame) -> Uint8Array | null,
    // frame = {index, camera, width, height, rgb (Uint8Array, w*h*3), click: [u, v] | null,
    // box: [x0, y0, x1, y1] | null, fine} (fine: the fine round, whose frames render the coarse
    // selection only; box: the prompt's box in this frame, lifted from the reference view).
    // u or v NaN: no click (options.box is the prompt).
    vcar::web::FrameMaskFn custom;
    if (options.typeOf().as<std::string>() == "object" && options["segmenter"].typeOf().as<std::string>() == "function") {
      const val fn = options["segmenter"];
      custom = [fn](std::size_t k, const vcar::Camera& cam, const vcar::ImageRGB8& rgb, const vcar::Prompt& p, bool subset,
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
    const vcar::SegmentationResult& r = s_.segment(camera_from_js(camera), u, v, opt, cb, custom);
    return diagnostics_of(r);
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

private:
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
      .function("render", &JsSession::render)
      .function("indices", &JsSession::indices)
      .function("scores", &JsSession::scores)
      .function("logScales", &JsSession::logScales)
      .function("views", &JsSession::views)
      .function("objectPly", &JsSession::objectPly)
      .function("removedPly", &JsSession::removedPly)
      .function("statePly", &JsSession::statePly);
  emscripten::function("simdPath", &simd_path);
  emscripten::function("exceptionMessage", &exception_message);
}
