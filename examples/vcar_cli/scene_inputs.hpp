#pragma once
// Reading the inputs of the commands: scenes, cameras, mask folders and synthetic datasets.
// Failures are vcar::Error naming the file (exit code 2).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/external_segmenter.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::cli {

// A scene in any format io::read_scene knows (docs/formats.md).
GaussianScene load_scene(const std::filesystem::path& ply);
// Cameras in any format io::read_cameras knows; names must be unique (without extension).
// `opengl`: the file's camera axes are OpenGL's (--opengl-cameras), converted to OpenCV's.
std::vector<Camera> load_cameras(const std::filesystem::path& path, bool opengl = false);
io::MaskFolderSegmenter make_mask_folder(const std::filesystem::path& dir);

// A `vcar synth` dataset's world (primitives, Gaussians, true ids) for the oracle and eval.
struct OracleDataset {
  synth::World world;
};
OracleDataset load_oracle_dataset(const std::filesystem::path& dir);

struct SegmentOptions;
// The oracle's parameters from --oracle-mode and --oracle-failure key=value (keys: the fields of
// synth::OracleParams and synth::SamFailures, docs/cli.md); a bad key or value is a usage error.
synth::OracleParams oracle_params(const SegmentOptions& o);

class ProgressLine;
// What both segment commands open before segmenting, in the order that fails fastest: the
// external segmenter (--segmenter-cmd; its program checked before any frame is rendered), the
// scene (checked against the cameras) and the oracle dataset (--oracle; checked against the scene).
void open_segment_sources(const SegmentOptions& o, const std::vector<Camera>& cams, ProgressLine& progress,
                          std::optional<io::ExternalSegmenter>& external, GaussianScene& scene,
                          std::optional<OracleDataset>& oracle);

}  // namespace vcar::cli
