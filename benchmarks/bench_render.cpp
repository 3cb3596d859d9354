// Throughput of vcar::cpu::TiledRenderer against a straightforward per-pixel splatter
// (naive_splatter.hpp), both timed in the same run on the same random scenes; the splatter
// twice: as it is ("naive"), and with the per-pixel Gaussian lists that OpenSplat's CPU forward
// pass builds for its backward pass ("opensplat").
//   bench_render            100k and 1M Gaussians at 640x480 and 1280x720
//   bench_render --quick    20k and 100k Gaussians
//   bench_render --tiled N W H REPS [THREADS]   the tiled renderer alone (profiling, callgrind)
#include <algorithm>
#include <bit>
#include <cstdint>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <random>
#include <vector>

#include "naive_splatter.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// Median wall time, and median CPU time of all threads (the machine may be shared: CPU time
// shows the work done whatever the load).
struct Timing { double wall = 0, cpu = 0; };
template <class F>
Timing median_ms(int reps, F&& f) {
  std::vector<double> w, c;
  for (int r = 0; r < reps; ++r) {
    const auto a = Clock::now();
    const double c0 = process_cpu_ms();
    f();
    c.push_back(process_cpu_ms() - c0);
    w.push_back(std::chrono::duration<double, std::milli>(Clock::now() - a).count());
  }
  std::sort(w.begin(), w.end());
  std::sort(c.begin(), c.end());
  return {w[w.size() / 2], c[c.size() / 2]};
}

vcar::Camera bench_camera(int W, int H) {
  vcar::Camera c;
  c.name = "bench";
  c.set_intrinsics({W, H, 0.8f * W, 0.8f * W, 0.5f * W, 0.5f * H});  // about 64 degrees across
  return c;  // at the origin, looking down +z
}

// Gaussians spread over the whole field of view at depths 2..10, sized so that at 1280x720 their
// standard deviation is 1..12 px (log-uniform, anisotropic), opacities from faint to opaque,
// SH degree 3 with small view-dependent terms.
vcar::GaussianScene bench_scene(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  std::normal_distribution<float> N(0.f, 1.f);
  const float f = 0.8f * 1280.f;
  vcar::GaussianScene sc;
  sc.resize(n, 3);
  for (std::size_t i = 0; i < n; ++i) {
    const float z = 2.f + 8.f * U(rng);
    const float x = (U(rng) - 0.5f) * 1.1f * 1280.f / f * z, y = (U(rng) - 0.5f) * 1.1f * 720.f / f * z;
    const float sigma_px = std::exp(std::log(1.f) + (std::log(12.f) - std::log(1.f)) * U(rng));
    const float s = sigma_px * z / f;
    sc.set(i, {x, y, z}, {std::log(s), std::log(s * (0.3f + 0.7f * U(rng))), std::log(s * (0.3f + 0.7f * U(rng)))},
           {N(rng), N(rng), N(rng), N(rng)}, -2.f + 7.f * U(rng));
    for (int k = 0; k < 16; ++k)
      for (int c = 0; c < 3; ++c) sc.sh[(i * 16 + k) * 3 + c] = k == 0 ? 1.2f * (U(rng) - 0.5f) : 0.1f * N(rng);
  }
  return sc;
}

}  // namespace

// Renders one scene with the tiled renderer only: CPU and wall medians (for profilers).
int tiled_only(std::size_t n, int W, int H, int reps, int threads) {
  const vcar::GaussianScene sc = bench_scene(n, 42);
  const vcar::Camera cam = bench_camera(W, H);
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  vcar::cpu::TiledRenderer r(vcar::cpu::TiledRendererOptions{{}, threads});
  // FNV-1a over the bits of rgb and alpha: equal hashes mean bit-identical images across versions.
  std::uint64_t hash = 1469598103934665603ull;
  const vcar::RenderOutput out = r.render(q);
  for (const auto* v : {&out.rgb.data, &out.alpha.data})
    for (float x : *v) {
      const auto b = std::bit_cast<std::uint32_t>(x);
      for (int k = 0; k < 4; ++k) hash = (hash ^ ((b >> (8 * k)) & 0xffu)) * 1099511628211ull;
    }
  std::vector<double> project, shade, bin, composite;  // stage medians over the same calls
  const Timing t = median_ms(reps, [&] {
    r.render(q);
    project.push_back(r.last_times().project_ms);
    shade.push_back(r.last_times().shade_ms);
    bin.push_back(r.last_times().bin_ms);
    composite.push_back(r.last_times().composite_ms);
  });
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf("tiled %zu %dx%d threads %d: wall %.2f ms, cpu %.2f ms (project %.1f, shade %.1f, bin %.1f, composite %.1f; "
              "image hash %016llx)\n", n, W, H, threads, t.wall, t.cpu, median(project), median(shade), median(bin), median(composite),
              static_cast<unsigned long long>(hash));
  return 0;
}

int main(int argc, char** argv) {
  if (argc >= 6 && std::strcmp(argv[1], "--tiled") == 0)
    return tiled_only(std::strtoull(argv[2], nullptr, 10), std::atoi(argv[3]), std::atoi(argv[4]),
                      std::atoi(argv[5]), argc >= 7 ? std::atoi(argv[6]) : 0);
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const std::vector<std::size_t> sizes = quick ? std::vector<std::size_t>{20000, 100000}
                                               : std::vector<std::size_t>{100000, 1000000};
  const int threads = vcar::max_threads();
  std::printf("bench_render: vcar::cpu::TiledRenderer vs naive per-pixel splatter\n");
  std::printf("threads %d, SIMD lanes %d, medians in ms\n\n", threads, int(vcar::cpu::Lane::size));
  std::printf("wall: tiled (all threads), tiled-1t (one thread), contrib (accumulate_contributions),\n"
              "naive (naive_splatter.hpp, one thread), opensplat (the same with OpenSplat's per-pixel Gaussian\n"
              "lists, one thread); cpu: CPU ms of all threads; max|d|: alpha difference;\n"
              "d>1e-4: share of pixels differing by more (the naive 3-sigma box drops opaque fringes)\n");
  std::printf("%9s %9s | %8s %8s %8s %9s %9s | %8s %8s | %9s %9s %9s %9s | %8s %8s\n", "gaussians", "image", "tiled",
              "tiled-1t", "contrib", "naive", "opensplat", "cpu-til", "cpu-nai", "naive/til", "naive/1t", "cpu ratio",
              "os/1t", "max|d|", "d>1e-4");
  for (std::size_t n : sizes) {
    const vcar::GaussianScene sc = bench_scene(n, 42);
    for (auto [W, H] : {std::pair{640, 480}, std::pair{1280, 720}}) {
      const vcar::Camera cam = bench_camera(W, H);
      vcar::RenderRequest q;
      q.scene = &sc;
      q.camera = &cam;
      vcar::cpu::TiledRenderer r;
      vcar::RenderOutput out;
      const int reps = quick ? 3 : 5;
      r.render(q);  // warm-up: scratch buffers
      const Timing t_tiled = median_ms(reps, [&] { out = r.render(q); });
      vcar::cpu::TiledRenderer r1(vcar::cpu::TiledRendererOptions{{}, 1});
      const Timing t_one = median_ms(reps, [&] { r1.render(q); });
      vcar::Mask mask(W, H, 1);
      for (int y = 0; y < H; ++y)
        for (int x = W / 4; x < 3 * W / 4; ++x) mask(x, y) = 255;
      const Timing t_contrib = median_ms(reps, [&] {
        vcar::Contributions acc;
        r.accumulate_contributions(q, mask, acc);
      });
      const bool big = n >= 1000000 && W >= 1280;
      vcar::RenderOutput ref;
      const int naive_reps = big ? 1 : 3;
      const Timing t_naive = median_ms(naive_reps, [&] { ref = vcar::bench::naive_render(q); });
      // A fresh set of lists per repeat, freed after the timing (OpenSplat keeps them for its
      // backward pass).
      std::vector<std::vector<std::vector<std::int32_t>>> lists(static_cast<std::size_t>(naive_reps));
      std::size_t rep = 0;
      const Timing t_os = median_ms(naive_reps, [&] { (void)vcar::bench::naive_render(q, {}, &lists[rep++]); });
      lists.clear();
      double diff = 0;
      std::size_t off = 0;
      for (std::size_t k = 0; k < out.alpha.data.size(); ++k) {
        const double d = std::abs(out.alpha.data[k] - ref.alpha.data[k]);
        diff = std::max(diff, d);
        off += d > 1e-4;
      }
      char img[32];
      std::snprintf(img, sizeof img, "%dx%d", W, H);
      std::printf("%9zu %9s | %8.1f %8.1f %8.1f %9.1f %9.1f | %8.1f %8.1f | %9.1f %9.1f %9.1f %9.1f | %8.1e %7.2f%%\n", n,
                  img, t_tiled.wall, t_one.wall, t_contrib.wall, t_naive.wall, t_os.wall, t_tiled.cpu, t_naive.cpu,
                  t_naive.wall / t_tiled.wall, t_naive.wall / t_one.wall, t_naive.cpu / t_tiled.cpu, t_os.wall / t_one.wall, diff,
                  100.0 * double(off) / double(out.alpha.data.size()));
      std::fflush(stdout);
    }
  }
  return 0;
}
