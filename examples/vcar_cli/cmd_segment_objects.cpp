// `vcar segment --prompts FILE`: several objects in one run (vcar::segment_objects,
// algo/segment_objects.hpp).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "input_checks.hpp"
#include "photo_renderer.hpp"
#include "scene_inputs.hpp"
#include "vcar/algo/segment_objects.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/diagnostics_json.hpp"
#include "vcar/io/external_segmenter.hpp"
#include "vcar/io/label_ply.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/state_ply.hpp"
#include "vcar/synth/oracle_segmenter.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

namespace {

// The prompts file: a JSON array (or {"objects": [...]}) of {"name", "reference_view", and
// "points" [[u, v], ...] with optional "point_labels", "box" [x0, y0, x1, y1], "text", or
// "object_id" (the oracle's object in a synthetic dataset)}.
std::vector<ObjectPrompt> read_prompts(const fs::path& file, const std::vector<Camera>& cams) {
  const std::string where = file.string() + " (--prompts)";
  nlohmann::json j = read_json(file);
  if (j.is_object() && j.contains("objects")) j = j["objects"];
  if (!j.is_array() || j.empty()) throw CliError(exit_bad_input, "expected a non-empty JSON array of objects", where);
  std::vector<ObjectPrompt> out;
  std::set<std::string> names;
  for (std::size_t k = 0; k < j.size(); ++k) {
    const auto& e = j[k];
    const std::string w = where + ", entry " + std::to_string(k);
    ObjectPrompt o;
    try {
      if (!e.is_object() || !e.contains("name") || !e.contains("reference_view"))
        throw CliError(exit_bad_input, "each object needs \"name\" and \"reference_view\"", w);
      o.name = e["name"].get<std::string>();
      if (o.name.empty() || o.name == "." || o.name == ".." ||
          o.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.-") != std::string::npos)
        throw CliError(exit_bad_input, "name '" + o.name + "' must be a folder name ([A-Za-z0-9_.-])", w);
      if (!names.insert(o.name).second) throw CliError(exit_bad_input, "two objects are named '" + o.name + "'", w);
      o.prompt.reference_view = find_view(cams, e["reference_view"].get<std::string>(), w + " reference_view");
      if (e.contains("points")) {
        for (const auto& p : e["points"]) o.prompt.points.emplace_back(p.at(0).get<float>(), p.at(1).get<float>());
        if (e.contains("point_labels")) o.prompt.point_labels = e["point_labels"].get<std::vector<int>>();
        else o.prompt.point_labels.assign(o.prompt.points.size(), 1);
        if (o.prompt.point_labels.size() != o.prompt.points.size())
          throw CliError(exit_bad_input, "\"point_labels\" and \"points\" differ in length", w);
      }
      if (e.contains("box") && !e["box"].is_null()) {
        const auto b = e["box"].get<std::vector<float>>();
        if (b.size() != 4 || !(b[2] > b[0] && b[3] > b[1])) throw CliError(exit_bad_input, "\"box\" must be [x0, y0, x1, y1], x1 > x0, y1 > y0", w);
        o.prompt.box = Eigen::Vector4f(b[0], b[1], b[2], b[3]);
      }
      if (e.contains("text")) o.prompt.text = e["text"].get<std::string>();
      if (e.contains("object_id")) o.object_id = e["object_id"].get<int>();
    } catch (const nlohmann::json::exception& x) {
      throw CliError(exit_bad_input, std::string("malformed object: ") + x.what(), w);
    }
    const Camera& ref = cams[o.prompt.reference_view];
    for (std::size_t p = 0; p < o.prompt.points.size(); ++p)
      if (!inside_image(o.prompt.points[p].x(), o.prompt.points[p].y(), ref.width, ref.height))
        throw CliError(exit_bad_input, "point " + std::to_string(p) + " lies outside view '" + ref.name + "'", w);
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace

int run_segment_objects(const SegmentOptions& o, const GlobalOptions& g) {
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine progress(g.quiet);
  if (!o.prompt_view.empty() || !o.points.empty() || !o.box.empty() || !o.text.empty())
    throw CliError(exit_usage, "--prompts gives every object's prompt: leave out --prompt-view, --points, --box and --text", "--prompts");
  if (!o.state_ply.empty())
    throw CliError(exit_usage, "--state-ply holds one selection; with --prompts use OUT/labels.ply", "--state-ply");
  const VcarParams params = make_params(o.preset, o.sets);
  const synth::OracleParams oracle_p = oracle_params(o);  // --oracle-mode, --oracle-failure

  progress.message("reading cameras");
  const std::vector<Camera> cams = load_cameras(o.cameras, o.opengl_cameras);
  const std::vector<ObjectPrompt> objects = read_prompts(o.prompts, cams);
  const std::size_t K = objects.size();
  if (!o.masks.empty()) {
    if (!fs::is_directory(o.masks)) throw CliError(exit_bad_input, "mask folder does not exist", o.masks + " (--masks)");
    progress.done();
    for (const ObjectPrompt& ob : objects) {
      const fs::path dir = fs::path(o.masks) / ob.name;
      if (!fs::is_directory(dir))
        throw CliError(exit_bad_input, "no mask folder for object '" + ob.name + "': expected " + dir.string() +
                                           "/<view>.png (one folder per object)", o.masks + " (--masks)");
      check_mask_folder(dir, cams, ob.prompt.reference_view);
    }
  }
  if (!o.segmenter_cmd.empty())
    for (const ObjectPrompt& ob : objects)
      if (ob.prompt.points.empty() && !ob.prompt.box && ob.prompt.text.empty())
        throw CliError(exit_usage, "object '" + ob.name + "' has no prompt (points, box or text) for the segmenter", o.prompts + " (--prompts)");
  if (!o.oracle.empty())
    for (const ObjectPrompt& ob : objects)
      if (ob.object_id < 0)
        throw CliError(exit_bad_input, "object '" + ob.name + "' has no \"object_id\": the oracle needs the world's object", o.prompts + " (--prompts)");
  std::optional<io::ExternalSegmenter> external;
  GaussianScene scene;
  std::optional<OracleDataset> oracle_ds;
  open_segment_sources(o, cams, progress, external, scene, oracle_ds);

  cpu::TiledRenderer cpu_renderer;
  std::optional<PhotoRenderer> photos;
  if (!o.images.empty()) photos.emplace(cpu_renderer, o.images, cams);

  // The source of masks, for any subset of the objects.
  std::vector<io::MaskFolderSegmenter> folders;
  std::vector<synth::OracleSegmenter> oracles;
  MultiSegmentFn source;
  if (!o.masks.empty()) {
    for (const ObjectPrompt& ob : objects) folders.emplace_back(fs::path(o.masks) / ob.name);
    source = [each = EachObject<io::MaskFolderSegmenter>(folders)](const FrameSequence& f, const std::vector<ObjectRequest>& req,
                                                                   const ObjectMaskSink& sink) mutable {
      each.segment_objects(f, req, sink);
    };
  } else if (external) {
    source = [&](const FrameSequence& f, const std::vector<ObjectRequest>& req, const ObjectMaskSink& sink) {
      external->segment_objects(f, req, sink);
    };
  } else {
    // The rendered mode's label copies of the scene: prepared once, shared by the objects.
    const auto labels = oracle_p.mode == synth::OracleMode::rendered
                            ? std::make_shared<const synth::RenderedLabels>(oracle_ds->world) : nullptr;
    for (const ObjectPrompt& ob : objects) {
      synth::OracleParams op = oracle_p;
      op.target_id = ob.object_id;
      oracles.emplace_back(oracle_ds->world, op, cpu_renderer, labels);
    }
    // Each object's frames numbered from its own first (the oracle's failure draws depend on the
    // frame number): the same answers as in a single run. One ray cast (or one set of label
    // renders) per frame for the objects that see it whole (the coarse round). In the fine
    // round each frame draws its own object's G_coarse (FrameSequence::drawn).
    source = [&](const FrameSequence& f, const std::vector<ObjectRequest>& req, const ObjectMaskSink& sink) {
      for (std::size_t k = 0; k < f.size(); ++k) {
        synth::OracleSegmenter::FrameCasts casts;
        const std::vector<Index>* drawn = f.drawn ? f.drawn(k) : nullptr;
        const bool subset = f.drawn ? drawn != nullptr : f.subset;
        for (std::size_t q = 0; q < req.size(); ++q) {
          if (!req[q].covers(k)) continue;
          const std::optional<Mask> m =
              oracles[req[q].object].mask(f.cameras[k], k - req[q].first_frame, subset, casts, drawn);
          sink(k, q, m ? &*m : nullptr);
        }
      }
    };
  }

  OutputDir out(o.out);
  MultiSegmentation result;
  try {
    auto multi = make_multi_segmenter(source);
    if (photos) result = segment_objects(scene, cams, objects, *photos, multi, params, progress.callback());
    else result = segment_objects(scene, cams, objects, cpu_renderer, multi, params, progress.callback());
  } catch (const Cancelled&) {
    if (external && !external->last_request_dir().empty() && external->failure() == io::ExternalSegmenter::Failure::cancelled) {
      std::error_code ec;
      fs::remove_all(external->last_request_dir(), ec);
    }
    throw;
  } catch (const CliError&) {
    throw;
  } catch (const Error& e) {
    if (external && external->failure() == io::ExternalSegmenter::Failure::cancelled) {
      std::error_code ec;
      fs::remove_all(external->last_request_dir(), ec);
      throw CliError(exit_cancelled, e.what());
    }
    if (external && external->failure() != io::ExternalSegmenter::Failure::none) throw CliError(exit_segmenter, e.what());
    if (interrupted().load()) throw CliError(exit_cancelled, e.what());
    throw;
  }
  if (external && !o.keep_requests) {
    std::error_code ec;
    fs::remove(out.path() / "requests", ec);
  }
  progress.done();

  // ---- outputs: objects/<name>.ply, object.ply (every object), removed.ply, labels.ply,
  // selection.json ("objects"), report.json.
  progress.message("writing results");
  const std::vector<std::uint64_t> ids = io::gaussian_identities(scene);
  std::vector<std::int32_t> label(scene.size(), -1);
  nlohmann::json sel_objects = nlohmann::json::array(), rep_objects = nlohmann::json::array();
  make_output_dir(out.path() / "objects");
  std::vector<std::pair<Index, std::pair<std::size_t, std::size_t>>> all;
  for (std::size_t k = 0; k < K; ++k) {
    const SegmentationResult& r = result.objects[k];
    for (std::size_t e = 0; e < r.indices.size(); ++e) {
      label[r.indices[e]] = static_cast<std::int32_t>(k);
      all.push_back({r.indices[e], {k, e}});
    }
    try {
      io::write_ply(out.path() / "objects" / (objects[k].name + ".ply"), scene, r.indices, r.log_scale[0].empty() ? nullptr : &r.log_scale);
    } catch (const Error& e) {
      throw CliError(exit_output, e.what());
    }
    Selection sel;
    sel.indices = r.indices;
    sel.scores = r.scores;
    sel.log_scale = r.log_scale;
    sel.scene_gaussians = scene.size();
    sel.identity = io::selection_identity(ids, r.indices);
    nlohmann::json sj = selection_json(sel);
    sj["name"] = objects[k].name;
    if (objects[k].object_id >= 0) sj["object_id"] = objects[k].object_id;
    sel_objects.push_back(std::move(sj));
    nlohmann::json rep = io::diagnostics_json(r.diagnostics);  // io/diagnostics_json.hpp, as report.json
    rep["name"] = objects[k].name;
    rep["reference_view"] = cams[objects[k].prompt.reference_view].name;
    rep["counts"]["lost_to_others"] = result.lost[k];
    rep["output"] = "objects/" + objects[k].name + ".ply";
    rep_objects.push_back(std::move(rep));
  }
  std::sort(all.begin(), all.end());
  std::vector<Index> union_idx, rest;
  LogScales union_ls;
  for (const auto& [i, at] : all) {
    const SegmentationResult& r = result.objects[at.first];
    union_idx.push_back(i);
    for (int d = 0; d < 3; ++d)
      union_ls[d].push_back(r.log_scale[0].empty() ? scene.log_scale[d][i] : r.log_scale[d][at.second]);
  }
  for (std::size_t i = 0, k = 0; i < scene.size(); ++i) {
    if (k < union_idx.size() && union_idx[k] == i) { ++k; continue; }
    rest.push_back(static_cast<Index>(i));
  }
  try {
    io::write_ply(out.path() / "object.ply", scene, union_idx, &union_ls);
    io::write_ply(out.path() / "removed.ply", scene, rest);
    io::write_label_ply(out.path() / "labels.ply", scene, label);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
  const io::SceneFingerprint fp = io::scene_fingerprint(ids);
  write_json(out.path() / "selection.json",
             {{"objects", sel_objects}, {"scene_gaussians", scene.size()}, {"conflicts", result.conflicts},
              {"scene", {{"gaussians", fp.gaussians}, {"ordered", io::identity_hex(fp.ordered)},
                         {"unordered", io::identity_hex(fp.unordered)}}}});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json shared = nlohmann::json::object();
  for (const auto& [stage, s] : result.timings_s) shared[stage] = s;
  nlohmann::json inputs = {{"scene", o.scene}, {"cameras", o.cameras}, {"images", o.images}, {"prompts", o.prompts},
                           {"preset", o.preset}, {"set", o.sets}, {"views", cams.size()}, {"opengl_cameras", o.opengl_cameras},
                           {"masks", o.masks}, {"segmenter_cmd", o.segmenter_cmd}, {"oracle", o.oracle}};
  if (!o.oracle.empty()) {
    inputs["oracle_mode"] = o.oracle_mode;
    inputs["oracle_failures"] = o.oracle_failures;
  }
  write_json(out.path() / "report.json",
             {{"inputs", inputs}, {"parameters", params_json(params)}, {"objects", rep_objects},
              {"conflicts", result.conflicts}, {"segmenter_calls", result.segmenter_calls}, {"counts", {{"scene", scene.size()}, {"selected", union_idx.size()}, {"removed", rest.size()}}},
              {"timings_s", shared}, {"seconds", seconds}, {"threads", max_threads()}, {"peak_rss_mib", peak_rss_mib()},
              {"outputs", {{"objects", "objects/<name>.ply"}, {"object", "object.ply"}, {"removed", "removed.ply"},
                           {"labels", "labels.ply"}, {"selection", "selection.json"}}}});
  progress.done();
  out.commit();

  std::printf("%zu objects in one run (one coarse round for all; the segmenter asked %zu time%s)\n", K,
              result.segmenter_calls, result.segmenter_calls == 1 ? "" : "s");
  for (std::size_t k = 0; k < K; ++k) {
    const Diagnostics& d = result.objects[k].diagnostics;
    std::printf("%-12s %6zu selected (coarse %zu -> fine %zu); gap %.1f deg, SSS %s; ABR %zu compressed; %zu masks missing%s%s\n",
                objects[k].name.c_str(), d.n_final, d.n_coarse, d.n_fine, d.max_gap_deg,
                !params.enable_sss ? "off" : d.sss_triggered ? "ran" : "not needed", d.abr_compressed, d.masks_missing,
                result.lost[k] ? (", " + std::to_string(result.lost[k]) + " lost to another object").c_str() : "",
                d.note.empty() ? "" : ("; note: " + d.note).c_str());
  }
  std::printf("conflicts %zu Gaussians selected by two objects went to the higher score\n", result.conflicts);
  if (!o.masks.empty())
    for (const SegmentationResult& r : result.objects)
      if (r.diagnostics.sss_triggered) {
        std::fputs(mask_folder_advice, stdout);
        break;
      }
  std::printf("time      %.1f s on %d threads, peak memory %.0f MiB\n", seconds, max_threads(), peak_rss_mib());
  std::printf("wrote     %s/{objects/<name>.ply, object.ply, removed.ply, labels.ply, selection.json, report.json}\n",
              out.path().string().c_str());
  return exit_ok;
}

}  // namespace vcar::cli
