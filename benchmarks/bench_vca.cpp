// View completeness assessment (Eq. 6, A.1-A.3): Delta_max for K = 2000 probes and 100 cameras
// against a scalar version with one acos per (probe, camera) pair, measured in the same run;
// plus the valid-camera filter (A.1) on a coarse object of 100k Gaussians.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "vcar/algo/view_completeness.hpp"

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

int main() {
  const int K = 2000, M = 100;
  std::mt19937 rng(2);
  std::normal_distribution<float> N01;
  // Cameras on the upper hemisphere, looking at the origin: a forward-facing-like rig.
  std::vector<vcar::Camera> cams;
  for (int j = 0; j < M; ++j) {
    Eigen::Vector3f d(N01(rng), N01(rng), std::abs(N01(rng)));
    cams.push_back(vcar::Camera::look_at(4.f * d.normalized(), Eigen::Vector3f::Zero(), {0, 0, 1},
                                         {1280, 720, 900, 900, 640, 360}, "cam" + std::to_string(j)));
  }
  const auto t = vcar::fibonacci_lattice(K);
  std::vector<std::size_t> all(M);
  for (int j = 0; j < M; ++j) all[j] = j;
  const auto h = vcar::headings(cams, all, Eigen::Vector3f::Zero());

  vcar::AngularGap g;
  const double t_fast = median_seconds(51, [&] { g = vcar::max_angular_gap(t, h); });
  double gap_scalar = 0;
  const double t_scalar = median_seconds(11, [&] {
    gap_scalar = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      double best = 1e9;  // delta_i = min_j acos(t_i . h_j)
      for (std::size_t j = 0; j < h.size(); ++j)
        best = std::min(best, std::acos(std::clamp(static_cast<double>(t[i].dot(h[j])), -1.0, 1.0)));
      gap_scalar = std::max(gap_scalar, best);
    }
  });
  const double t_lattice = median_seconds(51, [&] { volatile auto n = vcar::fibonacci_lattice(K).size(); (void)n; });
  std::printf("VCA: K = %d probes, %zu cameras\n", K, h.size());
  std::printf("  max_angular_gap (max of dots, 1 acos): %9.4f ms  Delta_max = %.3f deg\n", 1e3 * t_fast, g.Delta_max_deg);
  std::printf("  scalar, acos per pair:                 %9.4f ms  Delta_max = %.3f deg  (%.1fx slower)\n",
              1e3 * t_scalar, gap_scalar * 180 / 3.14159265358979, t_scalar / t_fast);
  std::printf("  fibonacci_lattice(K):                  %9.4f ms\n", 1e3 * t_lattice);

  // A.1 on a coarse object of 100k Gaussians: rho^(j) for each of the 100 cameras.
  vcar::GaussianScene scene;
  const std::size_t Nc = 100000;
  scene.resize(Nc);
  for (std::size_t i = 0; i < Nc; ++i)
    for (int d = 0; d < 3; ++d) scene.mean[d][i] = 0.5f * N01(rng);
  std::vector<vcar::Index> idx(Nc);
  for (std::size_t i = 0; i < Nc; ++i) idx[i] = static_cast<vcar::Index>(i);
  std::size_t n_valid = 0;
  const double t_valid = median_seconds(11, [&] { n_valid = vcar::valid_cameras(scene, idx, cams, 0.2f).size(); });
  const double t_all = median_seconds(11, [&] {
    g = vcar::assess_view_completeness(scene, idx, cams, Eigen::Vector3f::Zero(), 0.2f, K);
  });
  std::printf("  valid_cameras (%zu Gaussians x %d cameras, %d threads): %8.3f ms, %zu valid\n", Nc, M,
              vcar::max_threads(), 1e3 * t_valid, n_valid);
  std::printf("  assess_view_completeness (all of the above):            %8.3f ms, Delta_max = %.2f deg\n",
              1e3 * t_all, g.Delta_max_deg);
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    char buf[128] = {};
    if (std::fgets(buf, sizeof buf, f)) std::printf("load average at the end: %s", buf);
    std::fclose(f);
  }
  return 0;
}
