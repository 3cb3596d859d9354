// example_reselect: the loop of an interactive selection tool. A viewer holds one mask per
// training view (from a promptable segmenter); the user fixes the masks a view at a time, and
// after each fix the selection is recomputed with vcar::Reselection, which takes back only what
// changed (the vote counters and ABR's per-Gaussian state), so a fix costs a fraction of a
// full selection.
//
//   example_reselect [gaussians=200000] [views=60] [preset=robust]
//
// The default preset (robust) reads each view's render: the session renders every training view
// once (CPU renderer) and votes all views again on each select(); a paper preset (nvos) needs no
// renders and takes back only the changed view's votes.
//
// The scene is synthetic (a 360-degree capture around a table with objects), so the true
// Gaussians of the target are known and each step prints 3D precision and recall. The
// segmenter's first answer is wrong in three views (the neighbour object is taken too, a
// mask is missing, one is eroded); the "user" repairs them one by one.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "vcar/algo/reselection.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/eval/selection_metrics.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// Union of two masks: what a segmenter that also took the neighbour returns.
vcar::Mask united(vcar::Mask a, const vcar::Mask& b) {
  for (std::size_t p = 0; p < a.data.size(); ++p) a.data[p] = a.data[p] | b.data[p];
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 200000;
  const int views = argc > 2 ? std::atoi(argv[2]) : 60;
  if (n < 1000 || views < 4) {
    std::fprintf(stderr, "usage: example_reselect [gaussians >= 1000] [views >= 4] [preset: robust|nvos|lerf]\n");
    return 2;
  }
  vcar::VcarParams params;
  try {
    params = vcar::VcarParams::preset(argc > 3 ? argv[3] : "robust");
  } catch (const vcar::Error& e) {
    std::fprintf(stderr, "example_reselect: %s\n", e.what());
    return 2;
  }
  vcar::synth::WorldParams wp;
  wp.seed = 3;
  wp.n_gaussians = n;
  const vcar::synth::World world = vcar::synth::generate_world(wp);
  vcar::synth::RigParams rp;
  rp.n_train = views;
  rp.intrinsics = vcar::synth::make_intrinsics(640, 480);
  const vcar::synth::Rig rig = vcar::synth::orbit_rig(world, rp);
  const std::vector<vcar::Index> truth = world.gaussians_of(world.target_id);
  std::printf("scene: %zu Gaussians, %d views at 640x480; the target has %zu Gaussians\n", world.scene.size(), views,
              truth.size());

  // The vote and ABR; SSS needs a segmenter for its sampled views (vcar::segment).
  params.enable_sss = false;
  vcar::cpu::TiledRenderer renderer;
  const auto t_build = Clock::now();
  vcar::Reselection session(world.scene, rig.train, renderer, params);
  std::printf("session built in %.1f ms (renders of the %d views when the preset reads them)\n",
              1e3 * std::chrono::duration<double>(Clock::now() - t_build).count(), views);

  std::vector<vcar::Mask> right;  // the masks the user will end up with
  for (const vcar::Camera& cam : rig.train) right.push_back(vcar::synth::visible_mask(world, cam, world.target_id));

  auto step = [&](const std::string& what) {
    const auto t0 = Clock::now();
    const vcar::SegmentationResult r = session.select();
    const double ms = 1e3 * std::chrono::duration<double>(Clock::now() - t0).count();
    const auto s = vcar::eval::selection_scores(r.indices, truth, world.scene.size());
    const vcar::ReselectionStats& st = session.last_stats();
    std::printf("%-44s %7zu selected  P %.3f R %.3f  %7.1f ms  (ABR %s: %zu view(s) changed, %zu carried, %zu new)\n",
                what.c_str(), r.indices.size(), s.precision, s.recall, ms, st.abr_incremental ? "incremental" : "anew",
                st.views_changed, st.carried, st.fresh);
  };

  // The segmenter's first answer: right everywhere but in three views.
  const std::size_t a = 1, b = views / 3, c = 2 * views / 3;
  const vcar::Mask wrong_a = united(right[a], vcar::synth::visible_mask(world, rig.train[a], world.neighbour_id));
  const vcar::Mask wrong_c = vcar::synth::dilate_erode(right[c], -6);
  for (std::size_t j = 0; j < rig.train.size(); ++j) {
    if (j == b) continue;  // no mask
    session.set_mask(j, j == a ? &wrong_a : j == c ? &wrong_c : &right[j]);
  }
  step("first answer (3 views wrong)");
  session.set_mask(a, &right[a]);
  step("view " + std::to_string(a) + ": the neighbour removed");
  session.set_mask(b, &right[b]);
  step("view " + std::to_string(b) + ": its mask added");
  session.set_mask(c, &right[c]);
  step("view " + std::to_string(c) + ": the eroded mask replaced");
  session.set_mask(c, nullptr);
  step("view " + std::to_string(c) + ": cleared (undo)");
  session.set_mask(c, &right[c]);
  step("view " + std::to_string(c) + ": set again (redo)");
  return 0;
}
