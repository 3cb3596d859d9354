// Interactive re-selection with masks in hand (issue 15): a synthetic 360-degree scene of N
// Gaussians and M training views at W x H (default 1M x 100 at 1008 x 756), the target's visible
// masks held in memory. Timed in the same run:
//   - one CPU render of the scene at that size (the budget a re-selection should stay under);
//   - vcar::segment with the masks as its segmenter, SSS off (the paper's vote, nvos preset);
//   - a render and vcar::segment in turn, as a viewer runs them: the median ratio of 9 pairs;
//   - vcar::Reselection: setting every mask (the full vote) + select, then one mask changed +
//     select, with ABR from scratch and incremental (its coarse_voting line is the vote's share);
// at 1 thread and at every available thread. Checks that Reselection's selection and log-scales
// equal vcar::segment's, and prints the peak resident memory.
//   bench_reselect [N=1000000] [M=100] [W=1008] [H=756] [PRESET=nvos]
// PRESET robust (the default preset of vcar::segment and Reselection) makes the session render
// every view once (its construct line) and vote every view again on each select.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/algo/reselection.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double median_seconds(int reps, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto a = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

double peak_rss_mib() {  // VmHWM of this process
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t N = argc > 1 ? std::stoul(argv[1]) : 1000000;
  const int M = argc > 2 ? std::stoi(argv[2]) : 100;
  const int W = argc > 3 ? std::stoi(argv[3]) : 1008, H = argc > 4 ? std::stoi(argv[4]) : 756;
  const std::string preset = argc > 5 ? argv[5] : "nvos";
  const int threads = vcar::max_threads();

  vcar::synth::WorldParams wp;
  wp.seed = 7;
  wp.n_gaussians = N;
  const vcar::synth::World world = vcar::synth::generate_world(wp);
  vcar::synth::RigParams rp;
  rp.n_train = M;
  rp.intrinsics = vcar::synth::make_intrinsics(W, H);
  const vcar::synth::Rig rig = vcar::synth::orbit_rig(world, rp);
  std::vector<vcar::Mask> masks;
  for (const auto& cam : rig.train) masks.push_back(vcar::synth::visible_mask(world, cam, world.target_id));
  const vcar::Mask changed = vcar::synth::dilate_erode(masks[M / 2], -3);  // the "click": view M/2 eroded by 3 px
  std::printf("re-selection: %zu Gaussians x %d views at %dx%d (orbit rig), %d threads available\n",
              world.scene.size(), M, W, H, threads);
  std::printf("peak memory after the scene and %d masks: %.0f MiB\n", M, peak_rss_mib());

  vcar::cpu::TiledRenderer renderer;
  vcar::VcarParams params = vcar::VcarParams::preset(preset);
  params.enable_sss = false;
  std::printf("preset %s, SSS off\n", preset.c_str());
  // The masks are in hand: the segmenter hands out pointers to them (no copy).
  auto segmenter = vcar::make_streaming_segmenter(
      [&](const vcar::FrameSequence& f, const vcar::Prompt&, const vcar::MaskSink& sink) {
        for (std::size_t k = 0; k < f.size(); ++k) sink(k, &masks[k]);  // frame k -> training view (reference first)
      });

  std::printf("%-46s %8s %10s\n", "", "threads", "median s");
  vcar::SegmentationResult ref;
  for (int t : {1, threads}) {
    vcar::set_num_threads(t);
    const double render = median_seconds(3, [&] {
      vcar::RenderRequest q;
      q.scene = &world.scene;
      q.camera = &rig.train[0];
      (void)renderer.render(q);
    });
    std::printf("%-46s %8d %10.4f\n", "one CPU render (the budget)", t, render);
    const double seg = median_seconds(3, [&] {
      ref = vcar::segment(world.scene, rig.train, vcar::Prompt{}, renderer, segmenter, params);
    });
    std::printf("%-46s %8d %10.4f\n", "vcar::segment, masks in hand, SSS off", t, seg);
    // Every stage of the last run, and the time outside them (total minus their sum).
    double staged = 0, total = 0;
    for (const auto& [stage, s] : ref.diagnostics.timings_s) {
      std::printf("  %-44s %8d %10.4f\n", stage.c_str(), t, s);
      (stage == "total" ? total : staged) += s;
    }
    std::printf("  %-44s %8d %10.4f\n", "(outside the stages)", t, total - staged);
    // As a viewer runs them: a frame, then a re-selection, in turn, so that each finds the
    // caches as the other left them. The median of the pairs' ratios: both see the same noise.
    {
      std::vector<double> ratio, tr, ts;
      for (int r = 0; r < 9; ++r) {
        tr.push_back(median_seconds(1, [&] {
          vcar::RenderRequest q;
          q.scene = &world.scene;
          q.camera = &rig.train[0];
          (void)renderer.render(q);
        }));
        ts.push_back(median_seconds(1, [&] {
          (void)vcar::segment(world.scene, rig.train, vcar::Prompt{}, renderer, segmenter, params);
        }));
        ratio.push_back(ts.back() / tr.back());
      }
      for (auto* v : {&ratio, &tr, &ts}) std::sort(v->begin(), v->end());
      std::printf("%-46s %8d %10.4f   (render %.4f, vcar::segment %.4f: medians of 9 pairs)\n",
                  "render, then vcar::segment, in turn: ratio", t, ratio[4], tr[4], ts[4]);
    }

    std::optional<vcar::Reselection> session;
    const double build = median_seconds(1, [&] { session.emplace(world.scene, rig.train, renderer, params); });
    std::printf("%-46s %8d %10.4f\n", "Reselection: construct (Morton order or renders)", t, build);
    vcar::SegmentationResult first;
    const double full = median_seconds(1, [&] {
      for (int j = 0; j < M; ++j) session->set_mask(static_cast<std::size_t>(j), &masks[j]);
      first = session->select();
    });
    std::printf("%-46s %8d %10.4f\n", "Reselection: every mask set + select", t, full);
    bool flip = true;
    auto one_changed = [&] {
      session->set_mask(static_cast<std::size_t>(M / 2), flip ? &changed : &masks[M / 2]);
      flip = !flip;
      first = session->select();
    };
    session->set_incremental_abr(false);
    const double scratch = median_seconds(5, one_changed);
    std::printf("%-46s %8d %10.4f   (%.2f of one render)\n", "Reselection: one mask changed, ABR anew", t,
                scratch, scratch / render);
    for (const auto& [stage, s] : first.diagnostics.timings_s)
      std::printf("  %-44s %8d %10.4f\n", stage.c_str(), t, s);
    session->set_incremental_abr(true);
    const double incremental = median_seconds(5, one_changed);
    const vcar::ReselectionStats st = session->last_stats();
    std::printf("%-46s %8d %10.4f   (%.2f of one render, %.1fx faster than ABR anew)\n",
                "Reselection: one mask changed + select", t, incremental, incremental / render, scratch / incremental);
    for (const auto& [stage, s] : first.diagnostics.timings_s)
      std::printf("  %-44s %8d %10.4f\n", stage.c_str(), t, s);
    std::printf("  ABR %s: %zu view(s) changed, %zu Gaussians carried (%zu minima recomputed), %zu new\n",
                st.abr_incremental ? "incremental" : "anew", st.views_changed, st.carried, st.stale, st.fresh);
    // Back to the original masks: the result must be vcar::segment's.
    session->set_mask(static_cast<std::size_t>(M / 2), &masks[M / 2]);
    const vcar::SegmentationResult again = session->select();
    const bool same = again.indices == ref.indices && again.log_scale == ref.log_scale;
    std::printf("Reselection equals vcar::segment: %s (%zu selected, %zu ABR-compressed)\n", same ? "yes" : "NO",
                again.indices.size(), again.diagnostics.abr_compressed);
    if (!same) return 1;
  }
  std::printf("peak memory (VmHWM): %.0f MiB\n", peak_rss_mib());
  return 0;
}
