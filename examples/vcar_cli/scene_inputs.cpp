#include "scene_inputs.hpp"

#include <unordered_map>

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
