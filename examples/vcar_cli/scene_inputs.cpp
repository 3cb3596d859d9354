#include "scene_inputs.hpp"

#include "cli_common.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/synth/dataset.hpp"

namespace vcar::cli {

GaussianScene load_scene(const std::filesystem::path& ply) {
  if (!std::filesystem::exists(ply)) throw CliError(exit_bad_input, "no such file", ply.string() + " (--scene)");
  GaussianScene s = io::read_scene(ply);  // PLY, compressed PLY, SPZ or .splat, by content
  if (s.empty()) throw CliError(exit_bad_input, "the scene has no Gaussians", ply.string());
  return s;
}

std::vector<Camera> load_cameras(const std::filesystem::path& path) {
  std::vector<Camera> cams = io::read_cameras(path);
  if (cams.empty()) throw CliError(exit_bad_input, "no cameras in the file", path.string());
  for (const Camera& c : cams) {
    try {
      c.validate();
    } catch (const Error& e) {
      throw CliError(exit_bad_input, e.what(), path.string());
    }
  }
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

}  // namespace vcar::cli
