// vcar_cuda_example: renders a synthetic scene with the CUDA backend and the CPU backend, prints
// the largest differences and the timings (medians, same run), compares the per-Gaussian
// contributions, then runs vcar::segment with the CUDA renderer and with the CPU renderer.
//
//   vcar_cuda_example [n_gaussians=200000] [width=1280] [height=960] [repeats=11]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <vector>

#include "cuda_renderer.cuh"
#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double median_ms(int repeats, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

double max_abs_diff(const vcar::ImageF& a, const vcar::ImageF& b) {
  double m = 0;
  for (std::size_t k = 0; k < a.data.size(); ++k) m = std::max(m, double(std::fabs(a.data[k] - b.data[k])));
  return m;
}
double mean_abs_diff(const vcar::ImageF& a, const vcar::ImageF& b) {
  double s = 0;
  for (std::size_t k = 0; k < a.data.size(); ++k) s += std::fabs(a.data[k] - b.data[k]);
  return a.data.empty() ? 0.0 : s / double(a.data.size());
}

}  // namespace

int main(int argc, char** argv) try {
  const std::size_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 200000;
  const int width = argc > 2 ? std::atoi(argv[2]) : 1280, height = argc > 3 ? std::atoi(argv[3]) : 960;
  const int repeats = argc > 4 ? std::atoi(argv[4]) : 11;
  const std::string device = vcar::cuda::Renderer::device_name();
  if (device.empty()) {
    std::fprintf(stderr, "no CUDA device\n");
    return 77;
  }

  vcar::synth::WorldParams wp;
  wp.seed = 1;
  wp.n_gaussians = n;
  const vcar::synth::World world = vcar::synth::generate_world(wp);
  vcar::synth::RigParams rp;
  rp.intrinsics = vcar::synth::make_intrinsics(width, height);
  const vcar::synth::Rig rig = vcar::synth::make_rig("forward", world, rp);
  const vcar::Camera& view = rig.eval.front();

  vcar::cuda::Renderer gpu;
  vcar::cpu::TiledRenderer cpu;
  vcar::RenderRequest q;
  q.scene = &world.scene;
  q.camera = &view;
  q.want_depth = true;
  q.background = Eigen::Vector3f(0.2f, 0.3f, 0.4f);  // exercises the background term

  std::printf("device: %s; CPU: %d threads\n", device.c_str(), vcar::max_threads());
  std::printf("scene: %zu Gaussians, view %dx%d\n", world.scene.size(), width, height);
  gpu.render(q);  // warm-up (context creation, first allocations)
  vcar::RenderOutput a, b;
  const double t_gpu = median_ms(repeats, [&] { a = gpu.render(q); });
  const double t_cpu = median_ms(repeats, [&] { b = cpu.render(q); });
  const auto& ft = gpu.last_timings();
  std::printf("render, median of %d: CUDA %.2f ms (upload %.2f, project+scan %.2f, sort %.2f, composite %.2f, "
              "download %.2f; %zu tile entries), CPU %.2f ms, CPU / CUDA = %.1fx\n",
              repeats, t_gpu, ft.upload_ms, ft.project_ms, ft.sort_ms, ft.composite_ms, ft.download_ms, ft.entries,
              t_cpu, t_cpu / t_gpu);
  std::printf("max |CUDA - CPU|: rgb %.2e, alpha %.2e, depth %.2e (mean rgb %.2e)\n", max_abs_diff(a.rgb, b.rgb),
              max_abs_diff(a.alpha, b.alpha), max_abs_diff(a.depth, b.depth), mean_abs_diff(a.rgb, b.rgb));

  // A subset with refined-looking scales: the path ABR's output takes.
  std::vector<vcar::Index> target = world.gaussians_of(world.target_id);
  vcar::LogScales ls;
  for (int d = 0; d < 3; ++d)
    for (vcar::Index i : target) ls[d].push_back(world.scene.log_scale[d][i] - 0.2f);
  q.subset = &target;
  q.log_scale = &ls;
  std::printf("subset of %zu with scale override: max |CUDA - CPU| rgb %.2e, alpha %.2e\n", target.size(),
              max_abs_diff(gpu.render(q).rgb, cpu.render(q).rgb), max_abs_diff(gpu.render(q).alpha, cpu.render(q).alpha));
  q.subset = nullptr;
  q.log_scale = nullptr;

  // Contributions with the target's visible mask (what the peers' methods accumulate).
  const vcar::Mask mask = vcar::synth::visible_mask(world, view, world.target_id);
  vcar::Contributions ca, cc;
  gpu.accumulate_contributions(q, mask, ca);
  cpu.accumulate_contributions(q, mask, cc);
  double dw = 0, dwfg = 0, sw = 0;
  for (std::size_t i = 0; i < ca.weight.size(); ++i) {
    dw = std::max(dw, std::fabs(ca.weight[i] - cc.weight[i]));
    dwfg = std::max(dwfg, std::fabs(ca.weight_fg[i] - cc.weight_fg[i]));
    sw += cc.weight[i];
  }
  std::printf("contributions: max |CUDA - CPU| weight %.2e, weight_fg %.2e (sum of weights %.1f px)\n", dw, dwfg, sw);

  // vcar::segment with either renderer. The oracle never looks at pixels, so occlusion-aware
  // voting (a depth render per view) is switched on to put the renderer on the path.
  vcar::synth::OracleSegmenter oracle(world, {});
  vcar::Prompt prompt;
  prompt.reference_view = rig.reference;
  vcar::VcarParams params = vcar::VcarParams::nvos();
  params.occlusion_aware = true;
  auto t0 = Clock::now();
  const vcar::SegmentationResult rg = vcar::segment(world.scene, rig.train, prompt, gpu, oracle, params);
  const double s_gpu = std::chrono::duration<double>(Clock::now() - t0).count();
  t0 = Clock::now();
  const vcar::SegmentationResult rc = vcar::segment(world.scene, rig.train, prompt, cpu, oracle, params);
  const double s_cpu = std::chrono::duration<double>(Clock::now() - t0).count();
  std::vector<vcar::Index> both;
  std::set_intersection(rg.indices.begin(), rg.indices.end(), rc.indices.begin(), rc.indices.end(),
                        std::back_inserter(both));
  std::printf("segment: CUDA renderer %zu selected (%.2f s), CPU renderer %zu selected (%.2f s), common %zu\n",
              rg.indices.size(), s_gpu, rc.indices.size(), s_cpu, both.size());
  return rg.indices.empty() ? 1 : 0;
} catch (const vcar::Error& e) {
  std::fprintf(stderr, "error: %s\n", e.what());  // what() already names e.where()
  return 1;
}
