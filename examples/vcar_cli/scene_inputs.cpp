#include "scene_inputs.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <set>
#include <unordered_map>
#include <utility>

#include "cli_common.hpp"
#include "commands.hpp"
#include "input_checks.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/synth/dataset.hpp"

namespace vcar::cli {

GaussianScene load_scene(const std::filesystem::path& ply) {
  if (!std::filesystem::exists(ply)) throw CliError(exit_bad_input, "no such file", ply.string() + " (--scene)");
  InfiniteOpacities infinite;
  GaussianScene s = io::read_scene(ply, nullptr, &infinite);  // PLY, compressed PLY, SPZ or .splat, by content
  if (infinite.total()) warn(ply.string() + ": " + infinite.message());
  if (s.empty()) throw CliError(exit_bad_input, "the scene has no Gaussians", ply.string());
  return s;
}

std::vector<Camera> load_cameras(const std::filesystem::path& path, bool opengl) {
  std::vector<Camera> cams = io::read_cameras(path);
  if (cams.empty()) throw CliError(exit_bad_input, "no cameras in the file", path.string());
  std::unordered_map<std::string, std::size_t> first;  // views are named by img_name: masks, images, --view
  for (std::size_t k = 0; k < cams.size(); ++k) {
    const Camera& c = cams[k];
    try {
      c.validate();
    } catch (const Error& e) {
      throw CliError(exit_bad_input, e.what(), path.string());
    }
    const std::string stem = std::filesystem::path(c.name).stem().string();
    const auto [it, fresh] = first.emplace(stem, k);
    if (!fresh)
      throw CliError(exit_bad_input, "views " + std::to_string(it->second) + " and " + std::to_string(k) +
                                         " have the same name '" + c.name + "'" +
                                         (cams[it->second].name == c.name ? "" : " (as '" + cams[it->second].name + "')") +
                                         " (names must differ without their extension: masks and images are matched by them)",
                     path.string());
  }
  if (opengl) opengl_to_opencv(cams);
  return cams;
}

io::MaskFolderSegmenter make_mask_folder(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) throw CliError(exit_bad_input, "mask folder does not exist", dir.string() + " (--masks)");
  return io::MaskFolderSegmenter(dir);
}

OracleDataset load_oracle_dataset(const std::filesystem::path& dir) {
  if (!std::filesystem::is_regular_file(dir / "gt" / "scene.json"))
    throw CliError(exit_bad_input, "not a vcar synth dataset (no gt/scene.json)", dir.string());
  return {synth::load_world(dir)};
}

synth::OracleParams oracle_params(const SegmentOptions& o) {
  using synth::OracleMode;
  synth::OracleParams p;
  if (o.oracle_mode == "rendered") p.mode = OracleMode::rendered;
  else if (o.oracle_mode == "visible") p.mode = OracleMode::visible;
  else if (o.oracle_mode == "silhouette") p.mode = OracleMode::silhouette;
  else if (o.oracle_mode != "by_name")
    throw CliError(exit_usage, "unknown mode '" + o.oracle_mode + "'; valid: by_name, visible, silhouette, rendered", "--oracle-mode");
  // key -> (field setter); integers and probabilities are checked by OracleParams::validate.
  const std::vector<std::pair<std::string, std::function<void(double)>>> keys = {
      {"p_wrong", [&](double v) { p.sam.p_wrong = v; }},   {"p_part", [&](double v) { p.sam.p_part = v; }},
      {"p_leak", [&](double v) { p.sam.p_leak = v; }},     {"leak_px", [&](double v) { p.sam.leak_px = static_cast<int>(v); }},
      {"drift_px", [&](double v) { p.sam.drift_px = static_cast<float>(v); }},
      {"p_drop", [&](double v) { p.p_drop = v; }},         {"p_swap", [&](double v) { p.p_swap = v; }},
      {"dilate_px", [&](double v) { p.dilate_px = static_cast<int>(v); }},
      {"jitter_px", [&](double v) { p.jitter_px = static_cast<int>(v); }},
      {"n_blobs", [&](double v) { p.n_blobs = static_cast<int>(v); }},
      {"blob_radius_px", [&](double v) { p.blob_radius_px = static_cast<float>(v); }},
      {"seed", [&](double v) { p.seed = static_cast<std::uint64_t>(v); }}};
  const std::set<std::string> whole = {"leak_px", "dilate_px", "jitter_px", "n_blobs", "seed"};
  for (const std::string& kv : o.oracle_failures) {
    const auto eq = kv.find('=');
    const std::string key = kv.substr(0, eq), value = eq == std::string::npos ? "" : kv.substr(eq + 1);
    auto it = std::find_if(keys.begin(), keys.end(), [&](const auto& k) { return k.first == key; });
    if (it == keys.end()) {
      std::string valid;
      for (const auto& k : keys) valid += (valid.empty() ? "" : ", ") + k.first;
      throw CliError(exit_usage, "unknown key '" + key + "' in '" + kv + "'; valid: " + valid, "--oracle-failure");
    }
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(value.c_str(), &end);
    const bool integral = whole.count(key) > 0;
    if (value.empty() || *end != '\0' || errno != 0 || !std::isfinite(v) || (integral && (v != std::floor(v) || std::abs(v) > 1e9)) ||
        (key == "seed" && v < 0))
      throw CliError(exit_usage, "expected key=" + std::string(integral ? "INTEGER" : "NUMBER") + ", got '" + kv + "'",
                     "--oracle-failure");
    it->second(v);
  }
  try {
    p.validate();
  } catch (const Error& e) {  // "OracleParams.p_leak: must be in [0, 1]" -> "--oracle-failure: p_leak: must be ..."
    const std::string what = e.what(), prefix = "OracleParams.";
    throw CliError(exit_usage, what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what, "--oracle-failure");
  }
  return p;
}

void open_segment_sources(const SegmentOptions& o, const std::vector<Camera>& cams, ProgressLine& progress,
                          std::optional<io::ExternalSegmenter>& external, GaussianScene& scene,
                          std::optional<OracleDataset>& oracle) {
  if (!o.segmenter_cmd.empty()) {
    io::ExternalSegmenterOptions so;
    so.timeout_s = o.segmenter_timeout;
    so.keep_requests = o.keep_requests;
    so.work_dir = std::filesystem::path(o.out) / "requests";
    so.inherit_output = o.segmenter_output;
    so.cancelled = [] { return interrupted().load(); };
    so.progress = [&progress](const io::ExternalProgress& p) { progress.external(p); };
    try {
      external.emplace(o.segmenter_cmd, so);
    } catch (const Error& e) {
      throw CliError(exit_usage, e.what());
    }
    check_program(external->argv().front());
  }
  progress.message("reading scene");
  scene = load_scene(o.scene);
  progress.done();
  check_cameras_face_scene(scene, cams, o.cameras, o.opengl_cameras);
  if (!o.oracle.empty()) {
    progress.message("reading the oracle dataset");
    oracle.emplace(load_oracle_dataset(o.oracle));
    check_oracle_scene(scene, oracle->world.scene, o.oracle);
  }
}

}  // namespace vcar::cli
