// `vcar render`: one view of a scene, or of a selection with its refined scales, to PNG.
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "scene_inputs.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/state_ply.hpp"

namespace vcar::cli {

int run_render(const RenderOptions& o, const GlobalOptions& g) {
  ProgressLine progress(g.quiet);
  RenderRequest q;
  q.background = parse_rgb(o.background, "--background");
  progress.message("reading cameras");
  const std::vector<Camera> cams = load_cameras(o.cameras);
  const Camera& cam = cams[find_view(cams, o.view, "--view")];
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
  q.camera = &cam;
  progress.message("rendering " + cam.name);
  cpu::TiledRenderer renderer;
  const RenderOutput r = renderer.render(q);
  progress.done();
  try {
    io::write_png(o.out, r.rgb);
    if (!o.alpha.empty()) io::write_png(o.alpha, r.alpha);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
  std::size_t covered = 0;
  for (float a : r.alpha.data) covered += a > 0.5f;
  std::printf("rendered view '%s' (%dx%d, %zu Gaussians, %.1f%% of pixels alpha > 0.5) to %s\n",
              cam.name.c_str(), cam.width, cam.height, q.subset ? q.subset->size() : scene.size(),
              100.0 * static_cast<double>(covered) / static_cast<double>(r.alpha.pixels()), o.out.c_str());
  return exit_ok;
}

}  // namespace vcar::cli
