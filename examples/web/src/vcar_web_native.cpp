// The browser flow run natively: the same Session, segmenter and parameters as the WebAssembly
// build, for the browser test (same selection?) and the browser-vs-native benchmark.
//   vcar_web_native --scene FILE [--cameras FILE] [--view NAME] (--click U,V | --box X0,Y0,X1,Y1 | both
//                   | --objects U,V;U,V;...) [--segmenter region|grabcut] [--quality full|fast]
//                   [--max-side N] [--orbit-views N] [--grabcut-context C] [--grabcut-iterations N]
//                   [--click-box on|off] [--out result.json]
// --segmenter grabcut (where OpenCV is found): vcar::opencv::grabcut on each frame's box, what
// the page's grabcut.js does with OpenCV's WebAssembly build; region (the default here): vcar's
// colour + depth region growing, as the page's fallback. --quality: the page's quality (web_flow.hpp
// quality_of: the views' size, GrabCut's crop and iterations), which --max-side, --grabcut-context
// and --grabcut-iterations override one at a time. --grabcut-context: GrabCutParams::context
// (the page's vcarGrabCutParams.context; negative: the whole frame); --grabcut-iterations:
// GrabCutParams::iterations (vcarGrabCutParams.iterations). --click-box off: a click lifts its
// neighbourhood (SegmentOptions::click_box; the page's clickBox=off).
//   vcar_web_native --convert IN OUT      (any scene format -> .ply / .splat / .spz by OUT's
//                                          extension: inputs for the browser format tests)
// Prints (and writes to --out) {"selected": n, "seconds": t, "indices": [...], "split": {...}}:
// the page's #vcar-result format; seconds covers the Session's segment call (vcar::segment, the
// prompt's lift, the views), split as web::timing_split says. With --objects (a click
// per object, vcar::segment_objects as the page's objects=): {"objects": [{"selected": n,
// "indices": [...]}, ...], "seconds": t}.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>

#include "web_flow.hpp"
#ifdef VCAR_WEB_NATIVE_HAS_OPENCV
#include "vcar/opencv/grabcut_segmenter.hpp"
#endif

namespace {
std::vector<std::uint8_t> slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw vcar::Error("cannot open", p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
}  // namespace

int main(int argc, char** argv) {
  std::string scene, cameras, view, click, box, objects, segmenter = "region", out;
  vcar::web::SegmentOptions opt;
  std::string quality = "full";
  std::optional<int> max_side, grabcut_iterations;
  std::optional<float> grabcut_context;
  if (argc == 4 && std::string(argv[1]) == "--convert") {
    try {
      vcar::io::write_scene(argv[3], vcar::io::read_scene(argv[2]));
    } catch (const std::exception& e) {
      std::cerr << "vcar_web_native: " << e.what() << "\n";
      return 1;
    }
    return 0;
  }
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto next = [&]() -> std::string {
      if (k + 1 >= argc) { std::cerr << a << " needs a value\n"; std::exit(2); }
      return argv[++k];
    };
    if (a == "--scene") scene = next();
    else if (a == "--cameras") cameras = next();
    else if (a == "--view") view = next();
    else if (a == "--click") click = next();
    else if (a == "--box") box = next();
    else if (a == "--objects") objects = next();
    else if (a == "--segmenter") segmenter = next();
    else if (a == "--out") out = next();
    else if (a == "--quality") quality = next();
    else if (a == "--max-side") max_side = std::stoi(next());
    else if (a == "--orbit-views") opt.orbit_views = std::stoi(next());
    else if (a == "--grabcut-context") grabcut_context = std::stof(next());
    else if (a == "--grabcut-iterations") grabcut_iterations = std::stoi(next());
    else if (a == "--click-box") opt.click_box = next() != "off";
    else { std::cerr << "unknown argument " << a << "\n"; return 2; }
  }
  if (scene.empty() || (click.empty() && box.empty() && objects.empty()) || (segmenter != "region" && segmenter != "grabcut")) {
    std::cerr << "usage: vcar_web_native --scene FILE [--cameras FILE] [--view NAME] (--click U,V | --box X0,Y0,X1,Y1"
                 " | --objects U,V;U,V)"
                 " [--segmenter region|grabcut] [--out FILE]\n";
    return 2;
  }
  try {
    const vcar::web::Quality q = vcar::web::quality_of(quality);  // what --max-side and --grabcut-* leave
    opt.max_side = max_side.value_or(q.max_side);
    const float context = grabcut_context.value_or(q.grabcut_context);
    const int iterations = grabcut_iterations.value_or(q.grabcut_iterations);
    vcar::web::Session s;
    s.load_scene(slurp(scene), scene);
    if (!cameras.empty()) s.load_cameras(slurp(cameras), cameras);
    const vcar::Camera ref = vcar::web::reference_view(s, view);
    float u = NAN, v = NAN;
    if (!click.empty() && std::sscanf(click.c_str(), "%f,%f", &u, &v) != 2) throw vcar::Error("expected U,V", "--click " + click);
    if (!box.empty()) {
      Eigen::Vector4f b;
      if (std::sscanf(box.c_str(), "%f,%f,%f,%f", &b[0], &b[1], &b[2], &b[3]) != 4) throw vcar::Error("expected X0,Y0,X1,Y1", "--box " + box);
      opt.box = b;
    }
    vcar::web::FrameMaskFn custom;
    if (segmenter == "grabcut") {
#ifdef VCAR_WEB_NATIVE_HAS_OPENCV
      custom = [context, iterations](std::size_t k, const vcar::Camera& cam, const vcar::ImageRGB8& rgb, const vcar::Prompt& p, bool,
                                 const vcar::web::FrameBox& b) -> std::optional<vcar::Mask> {
        if (!b) return std::nullopt;
        vcar::opencv::GrabCutParams params;
        params.context = context;
        params.iterations = iterations;
        std::vector<vcar::opencv::GrabCutSeed> seeds;
        if (k == 0)
          for (const Eigen::Vector2f& q : p.points) seeds.push_back({q, true});
        const float radius = params.seed_radius * std::hypot(static_cast<float>(cam.width), static_cast<float>(cam.height));
        return vcar::opencv::grabcut(rgb, *b, params, seeds, radius, "GrabCut, frame " + std::to_string(k));
      };
#else
      throw vcar::Error("this build has no OpenCV (Debian libopencv-dev)", "--segmenter grabcut");
#endif
    }
    auto indices_json = [](std::ostringstream& j, const std::vector<vcar::Index>& ix) {
      j << "\"selected\": " << ix.size() << ", \"indices\": [";
      for (std::size_t i = 0; i < ix.size(); ++i) j << (i ? "," : "") << ix[i];
      j << "]";
    };
    std::ostringstream j;
    const auto t0 = std::chrono::steady_clock::now();
    auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    if (!objects.empty()) {
      std::vector<vcar::web::ObjectClick> prompts;
      std::istringstream list(objects);
      for (std::string c; std::getline(list, c, ';');) {
        vcar::web::ObjectClick o;
        if (std::sscanf(c.c_str(), "%f,%f", &o.u, &o.v) != 2) throw vcar::Error("expected U,V;U,V;...", "--objects " + objects);
        prompts.push_back(o);
      }
      vcar::web::ObjectFrameMaskFn per_object;
      if (custom)
        per_object = [&custom](std::size_t, std::size_t k, const vcar::Camera& c, const vcar::ImageRGB8& im,
                               const vcar::Prompt& p, bool subset, const vcar::web::FrameBox& b) {
          return custom(k, c, im, p, subset, b);
        };
      const vcar::MultiSegmentation& m = s.segment_objects(ref, prompts, opt, {}, per_object);
      const double secs = seconds();
      j << "{\"objects\": [";
      for (std::size_t o = 0; o < m.objects.size(); ++o) {
        j << (o ? ", {" : "{");
        indices_json(j, m.objects[o].indices);
        j << "}";
      }
      j << "], \"seconds\": " << secs << "}";
    } else {
      const vcar::SegmentationResult& r = s.segment(ref, u, v, opt, {}, custom);
      const double secs = seconds();
      const vcar::web::TimingSplit sp = vcar::web::timing_split(r.diagnostics);
      j << "{";
      indices_json(j, r.indices);
      j << ", \"seconds\": " << secs << ", \"split\": {\"renders\": " << sp.renders << ", \"segmenter\": " << sp.segmenter
        << ", \"vcar\": " << sp.vcar << ", \"total\": " << sp.total << "}}";
    }
    std::cout << j.str() << "\n";
    if (!out.empty()) std::ofstream(out) << j.str() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "vcar_web_native: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
