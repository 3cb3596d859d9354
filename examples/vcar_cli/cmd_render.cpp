// `vcar render`: views of a scene, or of a selection with its refined scales, to PNG or JPEG.
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "input_checks.hpp"
#include "scene_inputs.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/state_ply.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

namespace {
// The file --out (or --alpha) names for one view: its extension decides the format.
void check_image_name(const fs::path& file, const std::string& option) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
    throw CliError(exit_usage, "unknown image format '" + ext + "': name the file .png, .jpg or .jpeg", file.string() + " (" + option + ")");
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw CliError(exit_output, "the directory " + dir.string() + " does not exist (create it first)", file.string() + " (" + option + ")");
}
}  // namespace

int run_render(const RenderOptions& o, const GlobalOptions& g) {
  ProgressLine progress(g.quiet);
  const bool many = o.all_views || !o.views.empty();
  if (static_cast<int>(!o.view.empty()) + static_cast<int>(o.all_views) + static_cast<int>(!o.views.empty()) != 1)
    throw CliError(exit_usage, "give exactly one of --view NAME, --views a,b,c or --all-views", "render");
  if (!many) {
    check_image_name(o.out, "--out");
    if (!o.alpha.empty()) check_image_name(o.alpha, "--alpha");
  } else if (!o.alpha.empty() && o.alpha == o.out) {
    throw CliError(exit_usage, "--alpha must be another folder than --out", o.alpha + " (--alpha)");
  }
  RenderRequest q;
  q.background = parse_rgb(o.background, "--background");
  progress.message("reading cameras");
  const std::vector<Camera> cams = load_cameras(o.cameras, o.opengl_cameras);
  std::vector<std::size_t> chosen;
  if (o.all_views) {
    for (std::size_t k = 0; k < cams.size(); ++k) chosen.push_back(k);
  } else if (many) {
    std::istringstream in(o.views);
    std::string name;
    while (std::getline(in, name, ','))
      if (!name.empty()) chosen.push_back(find_view(cams, name, "--views"));
    if (chosen.empty()) throw CliError(exit_usage, "no view named", "--views");
  } else {
    chosen.push_back(find_view(cams, o.view, "--view"));
  }
  progress.message("reading scene");
  const GaussianScene scene = load_scene(o.scene);
  Selection sel;
  if (!o.selection.empty()) {
    sel = read_selection(o.selection, &scene);
    q.subset = &sel.indices;
    if (sel.has_log_scales()) q.log_scale = &sel.log_scale;
  } else if (const auto state = io::state_of(scene, o.scene); !state.empty()) {
    // A state PLY as the scene: what SuperSplat shows, every Gaussian not flagged deleted.
    for (std::size_t i = 0; i < state.size(); ++i)
      if (!(state[i] & io::splat_state::deleted)) sel.indices.push_back(static_cast<Index>(i));
    q.subset = &sel.indices;
  }
  q.scene = &scene;
  std::optional<OutputDir> out_dir, alpha_dir;
  if (many) {
    out_dir.emplace(o.out);
    if (!o.alpha.empty()) alpha_dir.emplace(o.alpha);
  }
  cpu::TiledRenderer renderer;
  std::size_t covered_total = 0, pixels_total = 0;
  for (std::size_t n = 0; n < chosen.size(); ++n) {
    const Camera& cam = cams[chosen[n]];
    q.camera = &cam;
    progress({"rendering", n, chosen.size(), 0});
    const RenderOutput r = renderer.render(q);
    const std::string stem = fs::path(cam.name).stem().string();
    const fs::path rgb_file = many ? fs::path(o.out) / (stem + ".png") : fs::path(o.out);
    const fs::path alpha_file = many ? (o.alpha.empty() ? fs::path() : fs::path(o.alpha) / (stem + ".png")) : fs::path(o.alpha);
    try {
      io::write_image(rgb_file, to_8bit(r.rgb));
      if (!alpha_file.empty()) io::write_image(alpha_file, to_8bit(r.alpha));
    } catch (const Error& e) {
      throw CliError(exit_output, e.what());
    }
    for (float a : r.alpha.data) covered_total += a > 0.5f;
    pixels_total += r.alpha.pixels();
    if (interrupted().load()) throw Cancelled("rendering");
  }
  progress.done();
  if (out_dir) out_dir->commit();
  if (alpha_dir) alpha_dir->commit();
  const double covered = 100.0 * static_cast<double>(covered_total) / static_cast<double>(std::max<std::size_t>(1, pixels_total));
  const std::size_t gaussians = q.subset ? q.subset->size() : scene.size();
  if (many)
    std::printf("rendered %zu views (%zu Gaussians, %.1f%% of pixels alpha > 0.5) to %s/<view>.png\n", chosen.size(),
                gaussians, covered, o.out.c_str());
  else
    std::printf("rendered view '%s' (%dx%d, %zu Gaussians, %.1f%% of pixels alpha > 0.5) to %s\n",
                cams[chosen[0]].name.c_str(), cams[chosen[0]].width, cams[chosen[0]].height, gaussians, covered, o.out.c_str());
  return exit_ok;
}

}  // namespace vcar::cli
