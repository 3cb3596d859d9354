// example_embed_cpu: what a 3DGS viewer does when the user asks to "select this object's
// Gaussians", with the bundled CPU splatter as the renderer.
//
//   example_embed_cpu                                  synthetic scene, oracle masks
//   example_embed_cpu object.ply                       the PLY's Gaussians (e.g. tests/data/donut.ply)
//                                                      placed in a synthetic scene, oracle masks
//   example_embed_cpu scene.ply cameras masks/ [view] your scene: cameras (COLMAP folder,
//                                                      cameras.json or transforms.json) and one
//                                                      mask per view in masks/ (named after the view);
//                                                      [view]: the prompt's view, by name or number (0)
// Options: -o FILE (default selection.ply), -t THREADS.
// Writes the selected Gaussians, with the refined scales of ABR, as an Inria PLY.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

// One progress line per stage, a counter per segmented view; returning false would cancel.
bool print_progress(const vcar::Progress& p) {
  if (p.views == 0)
    std::printf("\n  [%6.2f s] %.*s", p.elapsed_s, static_cast<int>(p.stage.size()), p.stage.data());
  else if (p.view % 10 == 0 || p.view == p.views)  // a viewer would move a progress bar here
    std::printf("\r  [%6.2f s] %.*s: view %zu / %zu", p.elapsed_s, static_cast<int>(p.stage.size()),
                p.stage.data(), p.view, p.views);
  std::fflush(stdout);
  return true;
}

// Places a trained object's Gaussians in a synthetic world beside the world's own target and
// makes them the target: centred on their median, scaled to the target's size.
void adopt_as_target(vcar::synth::World& world, const vcar::GaussianScene& object) {
  std::vector<float> c[3];
  for (int d = 0; d < 3; ++d) {
    c[d] = object.mean[d];
    std::nth_element(c[d].begin(), c[d].begin() + c[d].size() / 2, c[d].end());
  }
  const Eigen::Vector3f median(c[0][c[0].size() / 2], c[1][c[1].size() / 2], c[2][c[2].size() / 2]);
  std::vector<float> dist(object.size());
  for (std::size_t i = 0; i < object.size(); ++i) dist[i] = (object.mu(i) - median).norm();
  std::nth_element(dist.begin(), dist.begin() + dist.size() * 9 / 10, dist.end());
  const float r_object = std::max(dist[dist.size() * 9 / 10], 1e-6f);  // robust to floaters
  const auto [centre, r_target] = world.bounds(world.target_id);
  // Beside the primitive target (towards -x), resting at the same height.
  const float s = r_target / r_object;
  const Eigen::Vector3f at = centre - Eigen::Vector3f(2.2f * r_target, 0.f, 0.f);
  const int id = 100;
  vcar::synth::insert_gaussians(world, object, Eigen::Matrix3f::Identity(), at - s * median, s, id);
  world.target_id = id;
}

template <class Segmenter>
vcar::SegmentationResult run(const vcar::GaussianScene& scene, const std::vector<vcar::Camera>& cameras,
                             std::size_t reference, vcar::cpu::TiledRenderer& renderer, Segmenter& segmenter,
                             const std::string& out) {
  // The prompt: here only the reference view; a SAM-backed segmenter would also read points.
  vcar::Prompt prompt;
  prompt.reference_view = reference;
  const vcar::VcarParams params = vcar::VcarParams::nvos();
  std::printf("segmenting: %zu Gaussians, %zu views, prompt on '%s', %d threads",
              scene.size(), cameras.size(), cameras[reference].name.c_str(), vcar::max_threads());
  const vcar::SegmentationResult r = vcar::segment(scene, cameras, prompt, renderer, segmenter, params, print_progress);
  std::printf("\n");

  const vcar::Diagnostics& d = r.diagnostics;
  std::printf("coarse %zu -> fine %zu -> selected %zu Gaussians; max view gap %.0f deg, spiral %s; "
              "ABR compressed %zu\n", d.n_coarse, d.n_fine, d.n_final, d.max_gap_deg,
              d.sss_triggered ? "sampled" : "skipped", d.abr_compressed);
  if (!d.note.empty()) std::printf("note: %s\n", d.note.c_str());
  for (const auto& [stage, s] : d.timings_s) std::printf("  %-16s %7.3f s\n", stage.c_str(), s);
  if (r.indices.empty()) return r;
  // The subset, with the refined scales aligned with r.indices, every other property kept.
  vcar::io::write_ply(out, scene, r.indices, &r.log_scale);
  std::printf("wrote %s\n", out.c_str());
  return r;
}

}  // namespace

int main(int argc, char** argv) try {
  std::vector<std::string> args;
  std::string out = "selection.ply";
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if ((a == "-o" || a == "-t") && k + 1 < argc) {
      if (a == "-o") out = argv[++k];
      else vcar::set_num_threads(std::atoi(argv[++k]));  // the library's one thread knob
    } else if (a == "-h" || a == "--help") {
      std::printf("usage: %s [-o out.ply] [-t threads] [scene.ply [cameras masks_dir [reference_view]]]\n", argv[0]);
      return 0;
    } else {
      args.push_back(a);
    }
  }
  vcar::cpu::TiledRenderer renderer;  // keeps scratch buffers between renders: reuse it

  if (args.size() >= 3) {  // a real scene: PLY + cameras + a folder of masks
    const vcar::GaussianScene scene = vcar::io::read_ply(args[0]);
    const std::vector<vcar::Camera> cameras = vcar::io::read_cameras(args[1]);
    // Precomputed masks are masks of the captures: the fine round's renders of G_coarse (and the
    // spiral's sampled views) get "no mask", and the result is G_coarse after ABR. A live
    // segmenter (SAM 2 on the rendered frames) runs the fine round.
    vcar::io::MaskFolderSegmenter masks(args[2]);
    // The reference view: its name (as in the camera file), or its position among the cameras.
    std::size_t ref = 0;
    if (args.size() > 3) {
      const auto named = std::find_if(cameras.begin(), cameras.end(), [&](const vcar::Camera& c) { return c.name == args[3]; });
      if (named != cameras.end()) ref = static_cast<std::size_t>(named - cameras.begin());
      else if (!args[3].empty() && args[3].find_first_not_of("0123456789") == std::string::npos) ref = std::stoul(args[3]);
      else throw vcar::Error("no view named '" + args[3] + "' (give a view name or a number)", "reference view");
    }
    return run(scene, cameras, ref, renderer, masks, out).indices.empty() ? 2 : 0;
  }
  if (args.size() == 2) throw vcar::Error("give cameras and a mask folder, or only the PLY", "arguments");

  // A synthetic scene: a table, a target touching a neighbour, distractors, floaters.
  vcar::synth::WorldParams wp;
  wp.seed = 1;
  wp.n_gaussians = 30000;  // seconds on two cores
  vcar::synth::World world = vcar::synth::generate_world(wp);
  if (args.size() == 1) adopt_as_target(world, vcar::io::read_ply(args[0]));
  // Forward-facing capture (NVOS-like): the back of the target is never seen, so the spiral runs.
  const vcar::synth::Rig rig = vcar::synth::make_rig("forward", world);
  // The oracle answers from the exact ground truth; it needs the renderer for PLY objects.
  vcar::synth::OracleSegmenter oracle(world, {}, renderer);
  const vcar::SegmentationResult r = run(world.scene, rig.train, rig.reference, renderer, oracle, out);
  // The synthetic world knows every Gaussian's object: how close is the selection?
  const std::vector<vcar::Index> truth = world.gaussians_of(world.target_id);
  std::vector<vcar::Index> hit;
  std::set_intersection(r.indices.begin(), r.indices.end(), truth.begin(), truth.end(), std::back_inserter(hit));
  std::printf("against the ground truth (%zu Gaussians): precision %.3f, recall %.3f\n", truth.size(),
              r.indices.empty() ? 0.0 : double(hit.size()) / double(r.indices.size()),
              truth.empty() ? 0.0 : double(hit.size()) / double(truth.size()));
  return r.indices.empty() ? 2 : 0;
} catch (const vcar::Error& e) {
  // what() is the whole message; where() alone names the file, view or parameter (for a UI).
  std::fprintf(stderr, "\nerror: %s\n", e.what());
  return 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "\nerror: %s\n", e.what());
  return 1;
}
