#pragma once
// Checks of inputs that would otherwise give a silently wrong result: a mask folder that matches
// no view, cameras that look away from the scene (OpenGL axes, other units), an oracle dataset of
// another scene. Each throws CliError (exit 2) saying what to do, or warns on stderr.
#include <filesystem>
#include <string>
#include <vector>

#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace vcar::cli {

// "vcar: warning: <text>" on stderr (clears a progress line first).
void warn(const std::string& text);

// Cameras written with OpenGL axes (x right, y up, z backward) read as OpenCV ones (x right,
// y down, z forward): flips each camera's y and z axes (R_w <- diag(1,-1,-1) R_w, t_w likewise).
void opengl_to_opencv(std::vector<Camera>& cams);

// How many of the views' masks a folder holds (matched like io::MaskFolderSegmenter: the view's
// name without extension, .png/.jpg/.jpeg). Throws (exit 2) when it holds none, naming the file
// names expected; `missing` lists the views without a file.
struct MaskCoverage {
  std::vector<std::string> missing;  // view names
  std::vector<std::filesystem::path> expected_missing;  // DIR/<stem>.png of each
};
MaskCoverage check_mask_folder(const std::filesystem::path& dir, const std::vector<Camera>& cams,
                               std::size_t reference_view);

// Fraction of the scene's Gaussian means that project into a view (z > 0, inside the image),
// averaged over the views; the Gaussians are sampled (at most `sample` of them).
double mean_visible_fraction(const GaussianScene& scene, const std::vector<Camera>& cams, std::size_t sample = 20000);

// Throws (exit 2) when almost no Gaussian lies in front of the cameras, warns when few do or
// when OpenGL axes would see many more; the message names the expected convention, the scene's
// extent and the cameras' distances in scene units, and --opengl-cameras where it would help.
// `opengl` says the cameras were already converted by that flag.
void check_cameras_face_scene(const GaussianScene& scene, const std::vector<Camera>& cams,
                              const std::string& cameras_path, bool opengl);

// Refuses (exit 2) an --oracle dataset whose scene.ply holds other Gaussians than `scene`
// (compared by the order-independent scene fingerprint, io/selection_identity.hpp).
void check_oracle_scene(const GaussianScene& scene, const GaussianScene& dataset_scene,
                        const std::filesystem::path& dataset_dir);

// The external segmenter's program (the first word of --segmenter-cmd) exists and can be run:
// a path to an executable file, or a name found in PATH. Checked before any frame is rendered;
// exit 3 naming the program otherwise.
void check_program(const std::string& program);

}  // namespace vcar::cli
