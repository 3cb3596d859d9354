// Synthetic world throughput: generation of 1M Gaussians and exact ground truth (visible +
// silhouette masks by ray casting) for 100 views. Medians of repeated runs; the speed-up over
// one thread is measured in the same run.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <vector>

#include "vcar/core/parallel.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {
double median_seconds(int reps, const std::function<void()>& f) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto a = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}
}  // namespace

int main() {
  using namespace vcar::synth;
  const int threads = vcar::max_threads();
  WorldParams wp;
  wp.seed = 7;
  wp.n_gaussians = 1000000;
  World w;
  const double gen = median_seconds(3, [&] { w = generate_world(wp); });
  vcar::set_num_threads(1);
  const double gen1 = median_seconds(1, [&] { w = generate_world(wp); });
  vcar::set_num_threads(threads);

  RigParams rp;
  rp.n_train = 100;
  const Rig rig = orbit_rig(w, rp);
  std::size_t pixels = 0;
  auto gt = [&] {
    pixels = 0;
    for (const auto& cam : rig.train) {
      pixels += count(visible_mask(w, cam, w.target_id));
      pixels += count(silhouette_mask(w, cam, w.target_id));
    }
  };
  const double gt_s = median_seconds(3, gt);
  RigParams big = rp;
  big.intrinsics = make_intrinsics(960, 720);
  const Rig rig_big = orbit_rig(w, big);
  const double gt_big = median_seconds(1, [&] {
    for (const auto& cam : rig_big.train) (void)visible_mask(w, cam, w.target_id);
  });
  std::printf("synth benchmark, %d threads\n", threads);
  std::printf("generate_world 1M Gaussians: median %.3f s (1 thread %.3f s, speed-up %.2fx)\n", gen, gen1, gen1 / gen);
  std::printf("ground truth 100 views 320x240 (visible + silhouette): median %.3f s, %.2f ms/view, %zu fg px\n",
              gt_s, 1e3 * gt_s / 100, pixels);
  std::printf("ground truth 100 views 960x720 (visible): %.3f s, %.2f ms/view (ratio to 320x240 visible+sil: %.2f)\n",
              gt_big, 1e3 * gt_big / 100, gt_big / gt_s);
  return 0;
}
