#pragma once
// The state behind vcar's JavaScript API (vcar_wasm.cpp) and its native twin (vcar_web_native.cpp):
// a scene, its cameras, one segmentation and the files written from it. Everything here is plain
// C++ on vcar::vcar and vcar::io, so the browser build and the native build run the same code.
//
// Flow: load_scene(bytes) -> load_cameras(bytes) (optional) -> segment(reference, click) ->
// indices / scores / log-scales -> object_ply / removed_ply / state_ply (bytes); or
// segment_objects(reference, clicks) -> objects() (one result per object, vcar::segment_objects).
// Scenes and cameras are read from bytes (vcar::io's readers take both); the PLY downloads are
// written through a scratch folder (emscripten's in-memory file system in the browser), because
// vcar::io's writers write files.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "region_grow_segmenter.hpp"
#include "vcar/algo/click_box.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/algo/prompt_lift.hpp"
#include "vcar/algo/segment_objects.hpp"
#include "vcar/concepts/multi_segmenter.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/state_ply.hpp"

namespace vcar::web {

// A mask source written by the host (the browser's JavaScript hook, docs/web.md): called once
// per frame with the frame's camera and 8-bit render, whether the frame renders a subset (the
// fine round renders G_coarse only) and the prompt's box in this frame: on the reference view
// the user's box when there is one; elsewhere (and for a click) the prompt lifted to 3D on the
// reference view and boxed in the frame (vcar::lift_prompt, algo/prompt_lift.hpp), nullopt when
// the lift failed or the object is out of the frame. Returns the mask or nothing (no evidence).
using FrameBox = std::optional<Eigen::Vector4f>;
using FrameMaskFn =
    std::function<std::optional<Mask>(std::size_t frame, const Camera&, const ImageRGB8&, const Prompt&, bool subset, const FrameBox& box)>;

// One object's prompt on the reference view for Session::segment_objects: a click (u, v; NaN:
// none), a box, or both; `name` names it in the result (default object_K).
struct ObjectClick {
  float u = NAN, v = NAN;
  std::optional<Eigen::Vector4f> box;
  std::string name;
};
// segment_objects' host segmenter: FrameMaskFn for one object, `object` its index.
using ObjectFrameMaskFn = std::function<std::optional<Mask>(std::size_t object, std::size_t frame, const Camera&,
                                                            const ImageRGB8&, const Prompt&, bool subset, const FrameBox& box)>;

struct SegmentOptions {
  int max_side = 400;       // vcar renders the views at most this many pixels on the long side
  int orbit_views = 16;     // views around the clicked point when no cameras were loaded
  RegionGrowOptions grow{};
  // A box prompt (x0, y0, x1, y1; pixels of the reference at its own size), with the click or
  // instead of it (then the views circle the box's centre). Only the host's segmenter uses it:
  // the region-growing one needs the click.
  std::optional<Eigen::Vector4f> box;
  float box_margin = 0.1f;    // lifted boxes padded by this share of their size (a box prompt)
  float point_margin = 0.5f;  // the same for a click without click_box (it lifts part of the object)
  // A click alone (no box) becomes a box on the reference view found by the host's segmenter
  // itself (vcar::box_from_click, algo/click_box.hpp), lifted like a box prompt; false: the
  // click's neighbourhood is lifted (boxes of part of the object, padded by point_margin).
  bool click_box = true;
};

// The host's FrameMaskFn as a Segmenter: each frame asked with the prompt's box in it, the
// prompt lifted to 3D on the reference view (`lifted`; none: the reference's own box only) and
// boxed in the frame (training and sampled) with `margin` of its size.
struct HostSegmenter {
  std::optional<LiftedPrompt> lifted;
  float margin = 0.f;
  FrameMaskFn custom;
  void segment(const FrameSequence& f, const Prompt& p, const MaskSink& sink) {
    for (std::size_t k = 0; k < f.size(); ++k) {
      const FrameBox box = lifted ? lifted->box_for(f.cameras[k], margin) : k == 0 ? p.box : FrameBox{};
      const std::optional<Mask> m = custom(k, f.cameras[k], f.image(k), p, f.subset, box);
      sink(k, m ? &*m : nullptr);
    }
  }
};

// The seconds of one vcar::segment run (its diagnostics' timings) split three ways, for the
// page's and the native twin's reports: `renders`, the frames rendered for the segmenter (the
// coarse and fine rounds' "_render"); `segmenter`, the rest of those rounds but their votes (the
// masks: GrabCut, the region grower or the host's hook, with the hand-over of each frame);
// `vcar`, the rest of vcar::segment (votes with their visibility passes, sphere, view
// completeness, SSS cameras, ABR); `total`, its "total". Caller-side work before vcar::segment
// (the views, the prompt's lift, loading a segmenter) is in none of them.
struct TimingSplit {
  double renders = 0, segmenter = 0, vcar = 0, total = 0;
};
inline TimingSplit timing_split(const Diagnostics& d) {
  TimingSplit s;
  for (const auto& [stage, t] : d.timings_s) {
    if (stage == "coarse_render" || stage == "fine_render") s.renders += t;
    else if (stage == "coarse_segment" || stage == "fine_segment") s.segmenter += t;
    else if (stage == "total") s.total = t;
  }
  s.vcar = s.total - s.renders - s.segmenter;
  return s;
}

class Session {
public:
  // `scratch`: a folder of its own (created, and removed with the session); by default a new
  // one under the temporary directory, so that sessions of concurrent processes never meet.
  explicit Session(std::filesystem::path scratch = {}) : dir_(std::move(scratch)) {
    if (dir_.empty())
      dir_ = std::filesystem::temp_directory_path() /
             ("vcar-web-" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()) + "-" +
              std::to_string(reinterpret_cast<std::uintptr_t>(this)));
    std::filesystem::create_directories(dir_);
  }
  ~Session() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  const std::filesystem::path& scratch() const { return dir_; }

  // Any format vcar::io::read_scene reads (by content; `name` matters only for .splat).
  // SPZ v2/v3 may also come already gunzipped (the browser inflates with DecompressionStream).
  std::size_t load_scene(const std::vector<std::uint8_t>& bytes, const std::string& name) {
    InfiniteOpacities infinite;
    scene_ = io::read_scene(bytes, name, &format_, &infinite);
    if (infinite.total()) std::fprintf(stderr, "vcar: warning: %s: %s\n", name.c_str(), infinite.message().c_str());
    if (scene_.empty()) throw Error("the scene has no Gaussians", name);
    result_.reset();
    return scene_.size();
  }

  // cameras.json (Inria) or transforms.json (nerfstudio/Blender with w, h).
  std::size_t load_cameras(const std::vector<std::uint8_t>& bytes, const std::string& name) {
    cameras_ = io::read_cameras(bytes, name);
    for (const Camera& c : cameras_) c.validate();
    return cameras_.size();
  }
  void clear_cameras() { cameras_.clear(); }

  const GaussianScene& scene() const { return scene_; }
  const std::vector<Camera>& cameras() const { return cameras_; }
  const char* format_name() const { return io::scene_format_name(format_); }

  // A view of the whole scene when the user brings no camera: from the robust centre (median of
  // the means), at a distance that fits the central 90% of the Gaussians in a 50 degree field of
  // view, looking along +z with -y up (the OpenCV axes 3DGS training uses).
  Camera default_view(int width, int height) const {
    require_scene();
    Eigen::Vector3f c;
    for (int d = 0; d < 3; ++d) c[d] = median(scene_.mean[d]);
    std::vector<float> r(scene_.size());
    for (std::size_t i = 0; i < r.size(); ++i) r[i] = (scene_.mu(i) - c).norm();
    std::nth_element(r.begin(), r.begin() + r.size() * 9 / 10, r.end());
    const float radius = std::max(r[r.size() * 9 / 10], 1e-3f);
    const float f = 0.5f * static_cast<float>(std::max(width, height)) / std::tan(0.5f * 50.f * 3.14159265f / 180.f);
    Intrinsics k{width, height, f, f, 0.5f * width, 0.5f * height};
    return Camera::look_at(c - Eigen::Vector3f(0, 0, 3.f * radius), c, Eigen::Vector3f(0, -1, 0), k, "default");
  }

  // Segments the object under pixel (u, v) of `reference` (pixels of reference's own size).
  // With cameras loaded, they are the training views and `reference` is added as the prompt
  // view (it may be one of them); without cameras, `options.orbit_views` views circle the
  // clicked point at the reference's distance. Views are rendered at most max_side pixels wide.
  // With `custom`, the masks come from it instead of the region-growing segmenter.
  // No click (u or v not finite): options.box alone is the prompt.
  const SegmentationResult& segment(const Camera& reference, float u, float v, const SegmentOptions& options = {},
                                    const ProgressCallback& progress = {}, const FrameMaskFn& custom = {}) {
    Setup setup = prepare(reference, {ObjectClick{u, v, options.box, {}}}, options, !custom);
    objects_.reset();
    if (custom) {
      auto host = host_segmenter(setup, 0, options, custom);
      result_ = vcar::segment(scene_, views_, setup.prompts[0], *setup.renderer, host, VcarParams::robust(), progress);
    } else {
      RegionGrowSegmenter<cpu::TiledRenderer> segmenter(*setup.renderer, options.grow);
      result_ = vcar::segment(scene_, views_, setup.prompts[0], *setup.renderer, segmenter, VcarParams::robust(), progress);
    }
    return *result_;
  }

  // Several objects at once (vcar::segment_objects: one coarse round for all, conflicts resolved
  // by score), each prompted on `reference` like segment's (options.box is not read: each object
  // has its own). Without cameras the views circle the first object. `custom(object, frame, ...)`
  // answers for one object at a time (object: its index in `objects`).
  const MultiSegmentation& segment_objects(const Camera& reference, const std::vector<ObjectClick>& objects,
                                           const SegmentOptions& options = {}, const ProgressCallback& progress = {},
                                           const ObjectFrameMaskFn& custom = {}) {
    if (objects.empty()) throw Error("no object: give at least one click or box", "prompt");
    Setup setup = prepare(reference, objects, options, !custom);
    result_.reset();
    std::vector<HostSegmenter> hosts;
    if (custom)  // first: a click's box (host_segmenter) is part of the object's prompt
      for (std::size_t o = 0; o < objects.size(); ++o)
        hosts.push_back(host_segmenter(setup, o, options, [&custom, o](std::size_t k, const Camera& c, const ImageRGB8& im,
                                                                      const Prompt& p, bool subset, const FrameBox& b) {
          return custom(o, k, c, im, p, subset, b);
        }));
    std::vector<ObjectPrompt> prompts;
    for (std::size_t o = 0; o < objects.size(); ++o)
      prompts.push_back({objects[o].name.empty() ? "object_" + std::to_string(o) : objects[o].name, setup.prompts[o], -1});
    if (custom) {
      EachObject<HostSegmenter> each{std::span<HostSegmenter>(hosts)};
      objects_ = vcar::segment_objects(scene_, views_, prompts, *setup.renderer, each, VcarParams::robust(), progress);
    } else {
      std::vector<RegionGrowSegmenter<cpu::TiledRenderer>> grow(objects.size(), {*setup.renderer, options.grow});
      EachObject<RegionGrowSegmenter<cpu::TiledRenderer>> each{std::span(grow)};
      objects_ = vcar::segment_objects(scene_, views_, prompts, *setup.renderer, each, VcarParams::robust(), progress);
    }
    return *objects_;
  }

  // The scene seen from `cam` (vcar's CPU renderer, the images the segmenter sees).
  RenderOutput render(const Camera& cam) const {
    require_scene();
    cam.validate();
    cpu::TiledRenderer r;
    RenderRequest q;
    q.scene = &scene_;
    q.camera = &cam;
    q.want_depth = true;
    return r.render(q);
  }

  const SegmentationResult& result() const {
    if (!result_) throw Error("no segmentation yet: call segment first", "result");
    return *result_;
  }
  const std::vector<Camera>& views() const { return views_; }
  // The latest segment_objects call's objects (aligned with its prompts).
  const MultiSegmentation& objects() const {
    if (!objects_) throw Error("no several-object segmentation yet: call segment_objects first", "objects");
    return *objects_;
  }

  // The whole scene as Inria PLY bytes (for a viewer that cannot read the file it came in).
  std::vector<std::uint8_t> scene_ply() {
    require_scene();
    return write_and_read([&](const auto& p) { io::write_ply(p, scene_); });
  }
  // The selected Gaussians with their refined log-scales (ABR), as Inria PLY bytes.
  std::vector<std::uint8_t> object_ply() { return write_and_read([&](const auto& p) { io::write_ply(p, scene_, result().indices, &result().log_scale); }); }
  // Every Gaussian but the selection (the scene with the object deleted).
  std::vector<std::uint8_t> removed_ply() {
    std::vector<Index> rest;
    std::vector<bool> sel(scene_.size(), false);
    for (Index i : result().indices) sel[i] = true;
    for (std::size_t i = 0; i < sel.size(); ++i)
      if (!sel[i]) rest.push_back(static_cast<Index>(i));
    return write_and_read([&](const auto& p) { io::write_ply(p, scene_, rest); });
  }
  // The whole scene with SuperSplat's `state` byte: bit 0 (selected) on the selection.
  std::vector<std::uint8_t> state_ply() {
    return write_and_read([&](const auto& p) { io::write_state_ply(p, scene_, io::selection_state(scene_.size(), result().indices)); });
  }

private:
  // What segment and segment_objects share: the views, each object's prompt on view 0 (the
  // reference at the render size) and the renderer that keeps depth for the prompt's lift.
  struct Setup {
    Camera ref;
    float s = 1.f;
    std::vector<Prompt> prompts;
    std::unique_ptr<cpu::TiledRenderer> base = std::make_unique<cpu::TiledRenderer>();
    std::unique_ptr<DepthKeepingRenderer<cpu::TiledRenderer>> renderer =
        std::make_unique<DepthKeepingRenderer<cpu::TiledRenderer>>(*base);
  };
  Setup prepare(const Camera& reference, const std::vector<ObjectClick>& objects, const SegmentOptions& options,
                bool region_grow) {
    require_scene();
    reference.validate();
    Setup st;
    st.s = std::min(1.f, static_cast<float>(options.max_side) / static_cast<float>(std::max(reference.width, reference.height)));
    st.ref = scaled(reference, st.s);
    for (const ObjectClick& o : objects) {
      Prompt prompt;
      if (std::isfinite(o.u) && std::isfinite(o.v)) {
        prompt.points = {Eigen::Vector2f(o.u * st.s, o.v * st.s)};
        prompt.point_labels = {1};
      }
      if (o.box) {
        const Eigen::Vector4f& b = *o.box;
        if (!b.allFinite() || !(b[2] > b[0] && b[3] > b[1])) throw Error("the box is empty or not finite (needs x0 < x1, y0 < y1)", "prompt");
        prompt.box = b * st.s;
      }
      if (prompt.points.empty() && !prompt.box) throw Error("no prompt: give a click or a box", "prompt");
      if (prompt.points.empty() && region_grow) throw Error("the region-growing segmenter needs a click (a box needs another segmenter)", "prompt");
      prompt.reference_view = 0;
      st.prompts.push_back(std::move(prompt));
    }
    // Where the views circle (without cameras): the first object's click, else its box's centre.
    const Prompt& first = st.prompts.front();
    const Eigen::Vector2f anchor = !first.points.empty() ? first.points[0] : Eigen::Vector2f(0.5f * ((*first.box)[0] + (*first.box)[2]), 0.5f * ((*first.box)[1] + (*first.box)[3]));
    std::vector<Camera> views;
    if (!cameras_.empty()) {
      views.push_back(st.ref);
      for (const Camera& c : cameras_)
        if (!(c.name == reference.name && c.R_w.isApprox(reference.R_w) && c.t_w.isApprox(reference.t_w)))
          views.push_back(scaled(c, std::min(1.f, static_cast<float>(options.max_side) / static_cast<float>(std::max(c.width, c.height)))));
    } else {
      views = orbit_around_click(st.ref, anchor, *st.renderer, options.orbit_views);
    }
    views_ = views;
    return st;
  }

  // The host's segmenter for object `o`: its prompt lifted to 3D on the reference view. A click
  // alone gets its box first (options.click_box): the host's segmenter on the reference view's
  // render, asked by vcar::box_from_click; the box joins the object's prompt in `st`.
  HostSegmenter host_segmenter(Setup& st, std::size_t o, const SegmentOptions& options, FrameMaskFn custom) const {
    Prompt& prompt = st.prompts[o];
    if (options.click_box && !prompt.box && !prompt.points.empty()) {
      const ImageRGB8 image = to_8bit(detail::render_view(*st.base, scene_, st.ref, nullptr, VcarParams::robust().background).rgb);
      const std::optional<ClickBox> found = box_from_click(
          [&](const Eigen::Vector4f& b) { return custom(0, st.ref, image, prompt, false, FrameBox(b)); },
          prompt.points.front(), st.ref.width, st.ref.height);
      if (found) prompt.box = found->box;
      else std::fprintf(stderr, "vcar: warning: the segmenter found no object at the click: its neighbourhood is lifted\n");
    }
    HostSegmenter h{std::nullopt, prompt.box ? options.box_margin : options.point_margin, std::move(custom)};
    try {
      h.lifted = lift_prompt(scene_, st.ref, st.prompts[o], *st.base);
    } catch (const Error& e) {
      std::fprintf(stderr, "vcar: warning: the prompt could not be lifted to 3D (%s): frames get no box\n", e.what());
    }
    return h;
  }

  static Camera scaled(const Camera& c, float s) {
    if (s >= 1.f) return c;
    Camera o = c;
    o.width = std::max(1, static_cast<int>(std::lround(c.width * s)));
    o.height = std::max(1, static_cast<int>(std::lround(c.height * s)));
    o.fx = c.fx * s; o.fy = c.fy * s; o.cx = c.cx * s; o.cy = c.cy * s;
    return o;
  }

  // Views around the clicked point: the click lifted with the reference's rendered depth, then
  // `n` cameras on two rings (at the reference's elevation and 30 degrees above it, 2:1) at the
  // reference's distance, looking at the point, the reference's intrinsics, up = its up.
  std::vector<Camera> orbit_around_click(const Camera& ref, const Eigen::Vector2f& click,
                                         DepthKeepingRenderer<cpu::TiledRenderer>& renderer, int n) const {
    RenderRequest q;
    q.scene = &scene_;
    q.camera = &ref;
    (void)renderer.render(q);
    const auto p = RegionGrowSegmenter<cpu::TiledRenderer>::lift(
        ref, renderer.depth(), renderer.alpha(), static_cast<int>(click[0]), static_cast<int>(click[1]));
    if (!p) throw Error("the clicked pixel shows no Gaussian (alpha < 0.5): click on the object", "prompt");
    const Eigen::Vector3f up = ref.up();
    const Eigen::Vector3f off = ref.position() - *p;
    const float dist = off.norm();
    Eigen::Vector3f h = off - off.dot(up) * up;  // horizontal direction to the reference
    if (h.squaredNorm() < 1e-12f) h = ref.right().cross(up);
    h.normalize();
    const Eigen::Vector3f side = up.cross(h);
    const float elev0 = std::asin(std::clamp(off.dot(up) / dist, -1.f, 1.f));
    std::vector<Camera> views{ref};
    const int n_low = std::max(1, n * 2 / 3), n_high = std::max(0, n - n_low);
    auto ring = [&](int count, float elev, int skip) {  // skip: the reference's own azimuth
      for (int k = skip; k < count + skip; ++k) {
        const float az = 2.f * 3.14159265f * static_cast<float>(k) / static_cast<float>(count + skip);
        const Eigen::Vector3f dir = std::cos(elev) * (std::cos(az) * h + std::sin(az) * side) + std::sin(elev) * up;
        views.push_back(Camera::look_at(*p + dist * dir, *p, up, ref.intrinsics(), "orbit_" + std::to_string(views.size())));
      }
    };
    ring(n_low, elev0, 1);
    ring(n_high, std::min(elev0 + 0.5236f, 1.3f), 0);
    return views;
  }

  void require_scene() const { if (scene_.empty()) throw Error("no scene loaded: call load_scene first", "session"); }
  static float median(std::vector<float> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
  template <class F>
  std::vector<std::uint8_t> write_and_read(F&& write) {
    const auto p = dir_ / "out.ply";
    write(p);
    std::ifstream in(p, std::ios::binary);
    std::vector<std::uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(p);
    return b;
  }

  std::filesystem::path dir_;
  GaussianScene scene_;
  io::SceneFormat format_ = io::SceneFormat::ply;
  std::vector<Camera> cameras_, views_;
  std::optional<SegmentationResult> result_;
  std::optional<MultiSegmentation> objects_;
};

}  // namespace vcar::web
