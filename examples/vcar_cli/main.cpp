// `vcar`: the command line of the library (docs/cli.md).
//   vcar demo | synth | segment | eval | render
// Exit codes: 0 ok, 1 usage, 2 bad input, 3 segmenter failure, 4 interrupted, 5 cannot write
// an output, 70 internal error. Every error message names the file, view or parameter.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <new>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/core/parallel.hpp"

using namespace vcar::cli;

namespace {

// Validators whose messages name the value and the bound in a few words (CLI11's ranges print
// the limits of double in full).
CLI::Validator whole_number_at_least(long long min) {
  return CLI::Validator(
      [min](std::string& v) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long long x = std::strtoll(v.c_str(), &end, 10);
        if (v.empty() || *end != '\0' || errno != 0) return "expected a whole number, got '" + v + "'";
        if (x < min) return "must be at least " + std::to_string(min) + ", got " + v;
        return {};
      },
      "INT>=" + std::to_string(min));
}
CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        errno = 0;
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        if (v.empty() || *end != '\0' || errno != 0 || !std::isfinite(x)) return "expected a number, got '" + v + "'";
        if (!(x > 0)) return "must be greater than 0, got " + v;
        return {};
      },
      "NUMBER>0");
}

const char* const commands = "demo, synth, segment, eval, render";

// The message of a usage error, in vcar's words: every missing option of the command at once,
// unknown commands and options named as such.
std::string usage_message(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  const CLI::App* sub = nullptr;
  for (const CLI::App* s : app.get_subcommands()) sub = s;  // the command given, if any
  const std::string what = e.what();
  if (dynamic_cast<const CLI::RequiredError*>(&e)) {
    if (!sub) {
      // No command: the first word that is not a global option is an unknown command.
      for (int k = 1; k < argc; ++k) {
        const std::string a = argv[k];
        if (a == "-j" || a == "--threads") { ++k; continue; }
        if (!a.empty() && a[0] == '-') continue;
        return "unknown command '" + a + "'; commands: " + commands;
      }
      return std::string("no command given; commands: ") + commands;
    }
    std::string missing;
    std::size_t n = 0;
    for (const CLI::Option* opt : sub->get_options()) {
      // segment: --prompt-view is required unless --prompts gives every object's prompt.
      const bool required = opt->get_required() ||
                            (sub->get_name() == "segment" && opt->get_name() == "--prompt-view" && sub->count("--prompts") == 0);
      if (required && opt->count() == 0) { missing += (n++ ? ", " : "") + opt->get_name(); }
    }
    if (sub->get_name() == "segment" &&
        sub->count("--masks") + sub->count("--segmenter-cmd") + sub->count("--segmenter") + sub->count("--oracle") == 0)
      missing += (n++ ? ", " : "") + std::string("one of --masks, --segmenter-cmd, --segmenter or --oracle");
    if (n > 0) return sub->get_name() + ": missing " + missing;
  }
  if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
    const std::string::size_type colon = what.find(": ");
    const std::string args = colon == std::string::npos ? what : what.substr(colon + 2);
    const bool option = !args.empty() && args[0] == '-';
    if (!sub && !option) return "unknown command '" + args.substr(0, args.find(' ')) + "'; commands: " + commands;
    return std::string(option ? "unknown option" : "unexpected argument") + (args.find(' ') == std::string::npos ? " " : "s ") +
           args + (sub ? " for '" + sub->get_name() + "'" : std::string());
  }
  return what;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vcar: training-free segmentation of 3D Gaussian Splatting scenes (VCAR)", "vcar"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("vcar 0.1.0"));
  GlobalOptions g;
  app.add_flag("-q,--quiet", g.quiet, "No progress line, even on a terminal");
  app.add_option("-j,--threads", g.threads, "Worker threads (0 = all cores)")->check(whole_number_at_least(0));

  // ---- demo ------------------------------------------------------------------------------
  DemoOptions demo;
  auto* c_demo = app.add_subcommand("demo", "Segment the target of the built-in synthetic scene and evaluate it");
  c_demo->add_option("--out", demo.out, "Output directory")->capture_default_str();

  // ---- synth -----------------------------------------------------------------------------
  SynthOptions synth;
  auto* c_synth = app.add_subcommand("synth", "Write a synthetic dataset (scene, cameras, images, GT masks, prompt)");
  c_synth->add_option("--rig", synth.rig, "Camera rig (default: forward, or the stage file's; orbit = 360)")
      ->check(CLI::IsMember({"forward", "360", "orbit", "sparse", "hemisphere"}));
  c_synth->add_option("--seed", synth.seed, "World seed")->capture_default_str();
  auto* o_gaussians = c_synth->add_option("--gaussians", synth.gaussians, "Number of Gaussians")->capture_default_str()
      ->check(CLI::Range(std::size_t{100}, std::size_t{100000000}));
  auto* o_stage = c_synth->add_option("--stage", synth.stage, "Stage file (JSON): trained objects on a floor, exact labels");
  o_stage->excludes(o_gaussians);
  c_synth->add_option("--target", synth.target, "With --stage: the target object's name")->needs(o_stage);
  c_synth->add_option("--views", synth.views, "Training views (0 = the rig's default)")->check(whole_number_at_least(0));
  c_synth->add_option("--width", synth.width, "Image width (0 = default)")->check(whole_number_at_least(0));
  c_synth->add_option("--height", synth.height, "Image height (0 = default)")->check(whole_number_at_least(0));
  c_synth->add_option("--out", synth.out, "Output directory")->required();

  // ---- segment ---------------------------------------------------------------------------
  SegmentOptions seg;
  auto* c_seg = app.add_subcommand("segment", "Segment a 3DGS scene from 2D masks (the VCAR pipeline)");
  c_seg->add_option("--scene", seg.scene, "3DGS scene: PLY, compressed PLY, SPZ or .splat")->required();
  c_seg->add_option("--cameras", seg.cameras, "COLMAP sparse dir, cameras.json or transforms.json")->required();
  c_seg->add_option("--images", seg.images, "Training images (default: rendered with the CPU backend)");
  auto* o_prompt_view = c_seg->add_option("--prompt-view", seg.prompt_view, "Name of the reference view the prompt is given on");
  auto* o_prompts = c_seg->add_option("--prompts", seg.prompts,
                                      "Several objects: JSON list of {name, reference_view, points/box/text or object_id}");
  o_prompts->excludes(o_prompt_view);
  auto* o_masks = c_seg->add_option("--masks", seg.masks, "Folder of masks named like the views");
  auto* o_cmd = c_seg->add_option("--segmenter-cmd", seg.segmenter_cmd, "External segmenter command (protocol: docs/cli.md)");
  auto* o_oracle = c_seg->add_option("--oracle", seg.oracle, "Synthetic dataset dir: ground-truth masks rendered per frame");
  auto* o_builtin = c_seg->add_option("--segmenter", seg.segmenter,
                                      "Built-in segmenter: grabcut (OpenCV's GrabCut on each frame, its box lifted from "
                                      "--box or --points; builds with OpenCV only)")
                        ->check(CLI::IsMember({"grabcut"}));
  c_seg->add_option("--oracle-mode", seg.oracle_mode,
                    "With --oracle: rendered (what each frame's render draws), by_name, visible or silhouette")
      ->check(CLI::IsMember({"by_name", "visible", "silhouette", "rendered"}))->capture_default_str()->needs(o_oracle);
  c_seg->add_option("--oracle-failure", seg.oracle_failures,
                    "With --oracle: a failure model, key=value (repeatable): p_wrong, p_part, p_leak, leak_px, "
                    "drift_px, p_drop, p_swap, dilate_px, jitter_px, n_blobs, blob_radius_px, seed")
      ->take_all()->allow_extra_args(false)->needs(o_oracle);
  o_masks->excludes(o_cmd)->excludes(o_oracle)->excludes(o_builtin);
  o_cmd->excludes(o_oracle)->excludes(o_builtin);
  o_oracle->excludes(o_builtin);
  c_seg->add_option("--preset", seg.preset, "Parameter preset")
      ->check(CLI::IsMember({"robust", "nvos", "lerf", "reference_code"}))->capture_default_str();
  c_seg->add_option("--set", seg.sets, "Override a parameter: key=value (repeatable)")->take_all()
      ->allow_extra_args(false);
  c_seg->add_option("--points", seg.points, "Prompt points \"u,v;u,v\" (u,v,0 = negative)");
  c_seg->add_option("--box", seg.box, "Prompt box \"x0,y0,x1,y1\"");
  c_seg->add_option("--text", seg.text, "Prompt text");
  c_seg->add_option("--segmenter-timeout", seg.segmenter_timeout, "Seconds per segmentation round")
      ->capture_default_str()->check(positive_number());
  c_seg->add_flag("--keep-requests", seg.keep_requests, "Keep the segmenter's request directories under OUT/requests");
  c_seg->add_flag("--segmenter-output", seg.segmenter_output, "Show the segmenter's output instead of logging it");
  c_seg->add_option("--out", seg.out, "Output directory")->required();
  c_seg->add_flag("--opengl-cameras", seg.opengl_cameras,
                  "The camera file uses OpenGL axes (x right, y up, z backward): convert them");
  c_seg->add_option("--state-ply", seg.state_ply,
                    "Also write the whole scene as PLY with SuperSplat's `uchar state` (bit 0: selected)");

  // ---- eval ------------------------------------------------------------------------------
  EvalOptions ev;
  auto* c_eval = app.add_subcommand("eval", "Score a selection against a synthetic dataset's ground truth");
  c_eval->add_option("--dataset", ev.dataset, "Dataset directory (vcar synth)")->required();
  c_eval->add_option("--selection", ev.selection, "selection.json or state PLY written by vcar segment")->required();
  c_eval->add_option("--alpha", ev.alpha, "Rendered alpha threshold of the predicted mask")
      ->capture_default_str()->check(CLI::Range(0.0f, 1.0f));
  c_eval->add_flag("--json", ev.json, "Print one JSON object");

  // ---- render ----------------------------------------------------------------------------
  RenderOptions rd;
  auto* c_render = app.add_subcommand("render", "Render views of a scene (or of a selection) to PNG or JPEG");
  c_render->add_option("--scene", rd.scene, "3DGS scene: PLY, compressed PLY, SPZ, .splat or state PLY")->required();
  c_render->add_option("--cameras", rd.cameras, "COLMAP sparse dir, cameras.json or transforms.json")->required();
  auto* o_view = c_render->add_option("--view", rd.view, "View name");
  auto* o_views = c_render->add_option("--views", rd.views, "Views a,b,c: each to OUT/<view>.png (--out is a folder)");
  auto* o_all = c_render->add_flag("--all-views", rd.all_views, "Every view to OUT/<view>.png (--out is a folder)");
  o_view->excludes(o_views)->excludes(o_all);
  o_views->excludes(o_all);
  c_render->add_option("--out", rd.out, "Output image (.png, .jpg), or folder with --views / --all-views")->required();
  c_render->add_option("--alpha", rd.alpha, "Also write the alpha channel to this image (a folder with --views / --all-views)");
  c_render->add_option("--selection", rd.selection, "Render only this selection (selection.json with its refined scales, or a state PLY)");
  c_render->add_option("--background", rd.background, "Background colour r,g,b in [0,1]")->capture_default_str();
  c_render->add_flag("--opengl-cameras", rd.opengl_cameras,
                     "The camera file uses OpenGL axes (x right, y up, z backward): convert them");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e) == 0 ? exit_ok : exit_usage;  // --help, --version
    std::fprintf(stderr, "vcar: error: %s\nRun with --help for more information.\n", usage_message(app, e, argc, argv).c_str());
    return exit_usage;
  }

  install_signal_handlers();
  if (g.threads > 0) vcar::set_num_threads(g.threads);
  try {
    if (*c_demo) return run_demo(demo, g);
    if (*c_synth) return run_synth(synth, g);
    if (*c_seg) {
      std::string missing;
      if (seg.prompt_view.empty() && seg.prompts.empty()) missing = "--prompt-view (or --prompts)";
      if (seg.masks.empty() && seg.segmenter_cmd.empty() && seg.segmenter.empty() && seg.oracle.empty())
        missing += (missing.empty() ? "" : ", ") + std::string("one of --masks, --segmenter-cmd, --segmenter or --oracle");
      if (!missing.empty()) throw CliError(exit_usage, "missing " + missing, "segment");
      return run_segment(seg, g);
    }
    if (*c_eval) return run_eval(ev, g);
    if (*c_render) return run_render(rd, g);
  } catch (const CliError& e) {
    std::fprintf(stderr, "vcar: error: %s\n", e.what());
    if (e.code == exit_usage) std::fprintf(stderr, "Run with --help for more information.\n");
    return e.code;
  } catch (const vcar::Cancelled& e) {
    std::fprintf(stderr, "vcar: interrupted (%s)\n", e.where().c_str());
    return exit_cancelled;
  } catch (const vcar::Error& e) {
    std::fprintf(stderr, "vcar: error: %s\n", e.what());
    return exit_bad_input;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "vcar: error: out of memory\n");
    return exit_internal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vcar: internal error: %s\n", e.what());
    return exit_internal;
  }
  return exit_usage;
}
