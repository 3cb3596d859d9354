// `vcar segment`: the full pipeline on a scene file, its cameras and a source of masks.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "input_checks.hpp"
#include "mask_tally.hpp"
#include "photo_renderer.hpp"
#include "scene_inputs.hpp"
#include "segmenter_grabcut.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/algo/prompt_lift.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/external_segmenter.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/state_ply.hpp"
#include "vcar/synth/oracle_segmenter.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

namespace {

// The pipeline with any renderer and segmenter; maps failures of the segmenter to exit codes.
template <class R, class S>
SegmentationResult run_pipeline(const GaussianScene& scene, const std::vector<Camera>& cams,
                                const Prompt& prompt, R& renderer, S& segmenter,
                                const VcarParams& params, ProgressLine& progress,
                                const io::ExternalSegmenter* external) {
  try {
    return segment(scene, cams, prompt, renderer, segmenter, params, progress.callback());
  } catch (const Cancelled&) {
    throw;
  } catch (const CliError&) {
    throw;
  } catch (const Error& e) {
    if (external && external->failure() == io::ExternalSegmenter::Failure::cancelled)
      throw CliError(exit_cancelled, e.what());
    if (external && external->failure() != io::ExternalSegmenter::Failure::none)
      throw CliError(exit_segmenter, e.what());
    if (interrupted().load()) throw CliError(exit_cancelled, e.what());
    throw;
  }
}

}  // namespace

int run_segment(const SegmentOptions& o, const GlobalOptions& g) {
  const bool grabcut = o.segmenter == "grabcut";
  if (grabcut && !has_grabcut())
    throw CliError(exit_usage, "this build of vcar has no OpenCV, so no GrabCut (install OpenCV, e.g. Debian's "
                               "libopencv-dev, and configure and build vcar again)", "--segmenter grabcut");
  if (grabcut && !o.prompts.empty())
    throw CliError(exit_usage, "GrabCut segments one object: give --prompt-view with --box or --points, not --prompts",
                   "--segmenter grabcut");
  if (!o.prompts.empty()) return run_segment_objects(o, g);
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine progress(g.quiet);

  // Inputs first (cheap checks before expensive reads), then the scene; the output folder last,
  // so a run that fails on its inputs leaves nothing behind.
  VcarParams params = make_params(o.preset, o.sets);
  const synth::OracleParams oracle_p = oracle_params(o);  // --oracle-mode, --oracle-failure
  Prompt prompt;
  if (!o.points.empty()) parse_points(o.points, prompt);
  if (!o.box.empty()) prompt.box = parse_box(o.box);
  prompt.text = o.text;
  if (!o.segmenter_cmd.empty() && prompt.points.empty() && !prompt.box && prompt.text.empty())
    throw CliError(exit_usage, "an external segmenter needs a prompt: --points, --box or --text", "--segmenter-cmd");
  // A prompt lifted to 3D gives a box on every frame (algo/prompt_lift.hpp): GrabCut's, and the
  // external segmenter's prompt.json "boxes". It needs a box or a positive point.
  bool liftable = prompt.box.has_value();
  for (std::size_t k = 0; k < prompt.points.size(); ++k)
    liftable = liftable || k >= prompt.point_labels.size() || prompt.point_labels[k] != 0;  // a positive point
  if (grabcut && !liftable)
    throw CliError(exit_usage, "GrabCut needs a box on every frame: give --box or positive --points", "--segmenter grabcut");
  if (!o.state_ply.empty() && fs::is_directory(o.state_ply))
    throw CliError(exit_usage, "is a directory; give a file name", o.state_ply + " (--state-ply)");

  progress.message("reading cameras");
  const std::vector<Camera> cams = load_cameras(o.cameras, o.opengl_cameras);
  prompt.reference_view = find_view(cams, o.prompt_view, "--prompt-view");
  const Camera& ref = cams[prompt.reference_view];
  for (std::size_t k = 0; k < prompt.points.size(); ++k)
    if (!inside_image(prompt.points[k].x(), prompt.points[k].y(), ref.width, ref.height))
      throw CliError(exit_bad_input, "point " + std::to_string(k) + " lies outside view '" + ref.name + "' (" +
                                         std::to_string(ref.width) + "x" + std::to_string(ref.height) + ")",
                     "--points");
  if (!o.masks.empty()) {
    if (!fs::is_directory(o.masks)) throw CliError(exit_bad_input, "mask folder does not exist", o.masks + " (--masks)");
    progress.done();
    check_mask_folder(o.masks, cams, prompt.reference_view);
  }
  std::optional<io::ExternalSegmenter> external;
  GaussianScene scene;
  std::optional<OracleDataset> oracle_ds;
  open_segment_sources(o, cams, progress, external, scene, oracle_ds);

  cpu::TiledRenderer cpu_renderer;
  std::optional<PhotoRenderer> photos;
  if (!o.images.empty()) photos.emplace(cpu_renderer, o.images, cams);

  // GrabCut with points alone: the box around the clicked object, found by GrabCut itself on
  // the prompt view (algo/click_box.hpp), is lifted instead of the points' neighbourhood.
  const std::optional<Eigen::Vector4f> user_box = prompt.box;
  std::optional<Eigen::Vector4f> click_box;
  if (grabcut && !prompt.box) {
    if constexpr (has_grabcut()) {  // grabcut_click_box exists only in builds with OpenCV
      progress.message("finding the clicked object's box");
      const RenderOutput view = photos ? detail::render_view(*photos, scene, ref, nullptr, params.background)
                                       : detail::render_view(cpu_renderer, scene, ref, nullptr, params.background);
      click_box = grabcut_click_box(to_8bit(view.rgb), prompt);
      progress.done();
      if (click_box) prompt.box = click_box;
      else warn("--points: GrabCut found no object at the point: its neighbourhood is lifted");
    }
  }
  // Lifted with the CPU renderer: the depth of a PhotoRenderer is the CPU renderer's anyway, and
  // its alpha (the photograph's: 1 everywhere) is no surface test. GrabCut cannot do without
  // the boxes; an external program got the prompt before "boxes" existed, so there a prompt
  // that cannot be lifted only costs the boxes.
  std::optional<LiftedPrompt> lifted;
  if ((grabcut || external) && liftable) {
    progress.message("lifting the prompt");
    try {
      lifted = lift_prompt(scene, ref, prompt, cpu_renderer);
    } catch (const Error& e) {
      progress.done();
      if (grabcut)
        throw CliError(exit_bad_input, std::string(e.what()) + " (lifting the prompt to a box on every frame)",
                       prompt.box ? "--box" : "--points");
      warn(std::string(prompt.box ? "--box: " : "--points: ") + e.what() + ": the segmenter's prompt.json gets no \"boxes\"");
    }
    progress.done();
    if (external && lifted) external->set_boxes([&l = *lifted](std::size_t, const Camera& c) { return l.box_for(c); });
  }

  nlohmann::json inputs = {{"scene", o.scene}, {"cameras", o.cameras}, {"images", o.images},
                           {"prompt_view", ref.name}, {"preset", o.preset}, {"set", o.sets},
                           {"views", cams.size()}, {"opengl_cameras", o.opengl_cameras},
                           {"scene_format", io::scene_format_name(io::detect_scene_format(o.scene))}};
  nlohmann::json pj = {{"points", nlohmann::json::array()}, {"point_labels", prompt.point_labels},
                       {"text", prompt.text}};
  for (const auto& p : prompt.points) pj["points"].push_back({p.x(), p.y()});
  if (user_box) pj["box"] = {(*user_box)[0], (*user_box)[1], (*user_box)[2], (*user_box)[3]};
  if (click_box) pj["click_box"] = {(*click_box)[0], (*click_box)[1], (*click_box)[2], (*click_box)[3]};
  if (lifted) pj["lifted_gaussians"] = lifted->indices.size();
  inputs["prompt"] = pj;

  OutputDir out(o.out);
  auto with_renderer = [&](auto& segmenter, const io::ExternalSegmenter* ext) {
    if (photos) return run_pipeline(scene, cams, prompt, *photos, segmenter, params, progress, ext);
    return run_pipeline(scene, cams, prompt, cpu_renderer, segmenter, params, progress, ext);
  };
  auto tallied = [&](auto& segmenter, const io::ExternalSegmenter* ext, MaskCounts& counts) {
    TallySegmenter tally(segmenter, cams);
    SegmentationResult r = with_renderer(tally, ext);
    if (const RoundTally* t = tally.used())  // the masks the final vote and ABR used
      counts = {t->training, t->training_missing, t->sampled, t->sampled_missing};
    return r;
  };

  SegmentationResult result;
  MaskCounts counts;
  if (!o.masks.empty()) {
    inputs["masks"] = o.masks;
    io::MaskFolderSegmenter seg = make_mask_folder(o.masks);
    result = tallied(seg, nullptr, counts);
  } else if (external) {
    inputs["segmenter_cmd"] = o.segmenter_cmd;
    try {
      result = tallied(*external, &*external, counts);
    } catch (...) {
      // A failed program's request stays for inspection (the message names it); one cut short
      // by Ctrl-C or by a failure of vcar itself is removed.
      const auto f = external->failure();
      if (f == io::ExternalSegmenter::Failure::cancelled || f == io::ExternalSegmenter::Failure::none ||
          f == io::ExternalSegmenter::Failure::start) {
        std::error_code ec;
        if (!external->last_request_dir().empty()) fs::remove_all(external->last_request_dir(), ec);
      }
      throw;
    }
    if (!o.keep_requests) {
      std::error_code ec;
      fs::remove(out.path() / "requests", ec);  // only when empty: failed requests stay for inspection
    }
  } else if (grabcut) {
    inputs["segmenter"] = o.segmenter;
    if constexpr (has_grabcut()) {  // make_grabcut_segmenter exists only in builds with OpenCV
      auto seg = make_streaming_segmenter(make_grabcut_segmenter(std::move(*lifted)));
      result = tallied(seg, nullptr, counts);
    }
  } else {
    inputs["oracle"] = o.oracle;
    inputs["oracle_mode"] = o.oracle_mode;
    inputs["oracle_failures"] = o.oracle_failures;
    synth::OracleSegmenter seg(oracle_ds->world, oracle_p, cpu_renderer);
    result = tallied(seg, nullptr, counts);
  }
  progress.done();

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json report = write_segmentation(out.path(), scene, result, params, inputs);
  report["masks"] = mask_counts_json(counts);
  report["seconds"] = seconds;
  write_json(out.path() / "report.json", report);
  if (!o.state_ply.empty()) {
    try {  // the input scene unchanged (refined scales stay in object.ply and selection.json)
      io::write_state_ply(o.state_ply, scene, io::selection_state(scene.size(), result.indices));
    } catch (const Error& e) {
      throw CliError(exit_output, e.what());
    }
  }
  out.commit();
  std::fputs(summary_text(result.diagnostics, params, scene.size(), &counts, seconds, !o.masks.empty()).c_str(), stdout);
  std::printf("wrote     %s/{object.ply, removed.ply, selection.json, report.json}\n", out.path().string().c_str());
  if (!o.state_ply.empty()) std::printf("wrote     %s (SuperSplat state: the selection is selected)\n", o.state_ply.c_str());
  return exit_ok;
}

}  // namespace vcar::cli
