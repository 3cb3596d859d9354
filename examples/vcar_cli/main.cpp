// `vcar`: the command line of the library (docs/cli.md).
//   vcar demo | synth | segment | eval | render
// Exit codes: 0 ok, 1 usage, 2 bad input, 3 segmenter failure, 4 interrupted, 5 cannot write
// an output, 70 internal error. Every error message names the file, view or parameter.
#include <cstdio>
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

int main(int argc, char** argv) {
  CLI::App app{"vcar: training-free segmentation of 3D Gaussian Splatting scenes (VCAR)", "vcar"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("vcar 0.1.0"));
  GlobalOptions g;
  app.add_flag("-q,--quiet", g.quiet, "No progress line, even on a terminal");
  app.add_option("-j,--threads", g.threads, "Worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);

  // ---- demo ------------------------------------------------------------------------------
  DemoOptions demo;
  auto* c_demo = app.add_subcommand("demo", "Segment the target of the built-in synthetic scene and evaluate it");
  c_demo->add_option("--out", demo.out, "Output directory")->capture_default_str();

  // ---- synth -----------------------------------------------------------------------------
  SynthOptions synth;
  auto* c_synth = app.add_subcommand("synth", "Write a synthetic dataset (scene, cameras, images, GT masks, prompt)");
  c_synth->add_option("--rig", synth.rig, "Camera rig")
      ->check(CLI::IsMember({"forward", "360", "sparse", "hemisphere"}))->capture_default_str();
  c_synth->add_option("--seed", synth.seed, "World seed")->capture_default_str();
  c_synth->add_option("--gaussians", synth.gaussians, "Number of Gaussians")->capture_default_str()
      ->check(CLI::Range(std::size_t{100}, std::size_t{100000000}));
  c_synth->add_option("--views", synth.views, "Training views (0 = the rig's default)")->check(CLI::NonNegativeNumber);
  c_synth->add_option("--width", synth.width, "Image width (0 = default)")->check(CLI::NonNegativeNumber);
  c_synth->add_option("--height", synth.height, "Image height (0 = default)")->check(CLI::NonNegativeNumber);
  c_synth->add_option("--out", synth.out, "Output directory")->required();

  // ---- segment ---------------------------------------------------------------------------
  SegmentOptions seg;
  auto* c_seg = app.add_subcommand("segment", "Segment a 3DGS scene from 2D masks (the VCAR pipeline)");
  c_seg->add_option("--scene", seg.scene, "3DGS scene: PLY, compressed PLY, SPZ or .splat")->required();
  c_seg->add_option("--cameras", seg.cameras, "COLMAP sparse dir, cameras.json or transforms.json")->required();
  c_seg->add_option("--images", seg.images, "Training images (default: rendered with the CPU backend)");
  c_seg->add_option("--prompt-view", seg.prompt_view, "Name of the reference view the prompt is given on")->required();
  auto* o_masks = c_seg->add_option("--masks", seg.masks, "Folder of masks named like the views");
  auto* o_cmd = c_seg->add_option("--segmenter-cmd", seg.segmenter_cmd, "External segmenter command (protocol: docs/cli.md)");
  auto* o_oracle = c_seg->add_option("--oracle", seg.oracle, "Synthetic dataset dir: ground-truth masks rendered per frame");
  o_masks->excludes(o_cmd)->excludes(o_oracle);
  o_cmd->excludes(o_oracle);
  c_seg->add_option("--preset", seg.preset, "Parameter preset")
      ->check(CLI::IsMember({"robust", "nvos", "lerf", "reference_code"}))->capture_default_str();
  c_seg->add_option("--set", seg.sets, "Override a parameter: key=value (repeatable)")->take_all()
      ->allow_extra_args(false);
  c_seg->add_option("--points", seg.points, "Prompt points \"u,v;u,v\" (u,v,0 = negative)");
  c_seg->add_option("--box", seg.box, "Prompt box \"x0,y0,x1,y1\"");
  c_seg->add_option("--text", seg.text, "Prompt text");
  c_seg->add_option("--segmenter-timeout", seg.segmenter_timeout, "Seconds per segmentation round")
      ->capture_default_str()->check(CLI::PositiveNumber);
  c_seg->add_flag("--keep-requests", seg.keep_requests, "Keep the segmenter's request directories under OUT/requests");
  c_seg->add_flag("--segmenter-output", seg.segmenter_output, "Show the segmenter's output instead of logging it");
  c_seg->add_option("--out", seg.out, "Output directory")->required();
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
  auto* c_render = app.add_subcommand("render", "Render a view of a scene (or of a selection) to PNG");
  c_render->add_option("--scene", rd.scene, "3DGS scene: PLY, compressed PLY, SPZ, .splat or state PLY")->required();
  c_render->add_option("--cameras", rd.cameras, "COLMAP sparse dir, cameras.json or transforms.json")->required();
  c_render->add_option("--view", rd.view, "View name")->required();
  c_render->add_option("--out", rd.out, "Output PNG (RGB)")->required();
  c_render->add_option("--alpha", rd.alpha, "Also write the alpha channel to this PNG");
  c_render->add_option("--selection", rd.selection, "Render only this selection (selection.json with its refined scales, or a state PLY)");
  c_render->add_option("--background", rd.background, "Background colour r,g,b in [0,1]")->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help / version / the usage error
    return rc == 0 ? exit_ok : exit_usage;
  }

  install_signal_handlers();
  if (g.threads > 0) vcar::set_num_threads(g.threads);
  try {
    if (*c_demo) return run_demo(demo, g);
    if (*c_synth) return run_synth(synth, g);
    if (*c_seg) {
      if (seg.masks.empty() && seg.segmenter_cmd.empty() && seg.oracle.empty())
        throw CliError(exit_usage, "one of --masks, --segmenter-cmd or --oracle is required", "segment");
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
