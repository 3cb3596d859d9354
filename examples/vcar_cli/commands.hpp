#pragma once
// The subcommands of `vcar`; each returns its exit code or throws CliError / vcar::Error.
#include <cstdint>
#include <string>
#include <vector>

namespace vcar::cli {

struct GlobalOptions {
  bool quiet = false;   // no progress line even on a terminal
  int threads = 0;      // 0: OpenMP's default
};

struct SegmentOptions {
  std::string scene, cameras, images, prompt_view, out;
  std::string masks, segmenter_cmd, oracle;  // exactly one of these or `segmenter`
  std::string segmenter;                     // a built-in segmenter: "grabcut" (builds with OpenCV)
  std::string preset = "robust";
  std::vector<std::string> sets;
  std::string points, box, text;
  double segmenter_timeout = 3600;
  bool keep_requests = false;
  bool segmenter_output = false;  // show the segmenter's stdout/stderr instead of logging it
  std::string state_ply;          // also write the whole scene with SuperSplat's state flags
  bool opengl_cameras = false;    // the camera file's axes are OpenGL's (x right, y up, z back)
  std::string prompts;            // several objects: a JSON list of prompts (cmd_segment_objects.cpp)
  std::string oracle_mode = "by_name";       // --oracle: visible, silhouette, by_name or rendered
  std::vector<std::string> oracle_failures;  // --oracle: failure models, key=value (scene_inputs.cpp)
};
int run_segment(const SegmentOptions& o, const GlobalOptions& g);
int run_segment_objects(const SegmentOptions& o, const GlobalOptions& g);

struct RenderOptions {
  std::string scene, cameras, view, out, alpha, selection, background = "0,0,0";
  std::string views;        // "a,b,c": these views into the folder --out
  bool all_views = false;   // every view into the folder --out
  bool opengl_cameras = false;
};
int run_render(const RenderOptions& o, const GlobalOptions& g);

struct EvalOptions {
  std::string dataset, selection;
  float alpha = 0.5f;
  bool json = false;
};
int run_eval(const EvalOptions& o, const GlobalOptions& g);

struct SynthOptions {
  std::string rig, out;  // rig "": forward, or the stage file's
  std::string stage;     // a stage file (synth/stage_json.hpp): real objects instead of primitives
  std::string target;    // with --stage: the target object's name (default: the stage file's)
  std::uint64_t seed = 1;
  std::size_t gaussians = 20000;
  int views = 0;         // 0: the rig's default
  int width = 0, height = 0;  // 0: the rig's default
};
int run_synth(const SynthOptions& o, const GlobalOptions& g);

struct DemoOptions {
  std::string out = "vcar-demo";
};
int run_demo(const DemoOptions& o, const GlobalOptions& g);

}  // namespace vcar::cli
