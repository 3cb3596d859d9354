// ABR throughput: Gaussian-views per second (projection, overflow test, boundary tracing, factor)
// for Gaussians near the silhouette of a sphere seen from 20 forward-facing views at 1280 x 720, against a
// plain scalar single-thread version of the same rules in the same run; BoundaryRefinement over
// every view, and refine_deferred as vcar::segment runs it (expect_views, deferred tracing).
//   bench_abr [n_gaussians=100000] [views=20] [repeats=5]
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <limits>
#include <random>
#include <vector>

#include "vcar/core/simd.hpp"  // first: it keeps GCC 12 quiet about its own AVX-512 headers (bug 105593)
#include <Eigen/Eigenvalues>

#include "vcar/algo/boundary_refinement.hpp"

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Silhouette of the unit sphere at the origin: pixel centres whose ray hits it.
vcar::Mask sphere_mask(const vcar::Camera& cam) {
  vcar::Mask m(cam.width, cam.height, 1, 0);
  const Eigen::Vector3f c = cam.position();
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const Eigen::Vector3f d = (cam.R_w.transpose() *
                                 Eigen::Vector3f((x + 0.5f - cam.cx) / cam.fx, (y + 0.5f - cam.cy) / cam.fy, 1.f))
                                    .normalized();
      m(x, y) = c.cross(d).squaredNorm() < 1.f ? 255 : 0;
    }
  return m;
}

// The same rules written plainly: one Gaussian at a time, Eigen's solver, all 129 samples
// traced, array-of-structs state.
struct PlainState {
  int n_vis = 0, n_ovf = 0;
  std::array<float, 3> f{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                         std::numeric_limits<float>::infinity()};
};

void plain_view(const vcar::GaussianScene& scene, const vcar::Camera& cam, const vcar::Mask& mask,
                const vcar::AbrParams& p, std::vector<PlainState>& st) {
  std::vector<bool> fg(static_cast<std::size_t>(p.boundary_samples));
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const Eigen::Vector3f s = scene.scale(i);
    const auto g = vcar::project_gaussian(cam, scene.mu(i), scene.R(i), s, 1.f, p.projection);
    if (!g.valid || !vcar::mask_at(mask, g.mean.x(), g.mean.y())) continue;
    ++st[i].n_vis;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> es(g.Sigma2D);
    bool overflow = false;
    for (int k = 0; k < 4; ++k) {
      const int col = k < 2 ? 1 : 0;  // eigenvalues ascending: column 1 is the major axis
      const float lambda = std::max(es.eigenvalues()(col), 0.f);
      const Eigen::Vector2f u = (k % 2 ? -1.f : 1.f) * es.eigenvectors().col(col);
      const float L = p.sigma_c * std::sqrt(lambda);
      const Eigen::Vector2f e = g.mean + L * u;
      if (vcar::mask_at(mask, e.x(), e.y())) continue;
      overflow = true;
      std::array<float, 3> w{};
      for (int d = 0; d < 3; ++d) w[d] = s[d] * s[d] * std::pow(u.dot(g.q[d]), 2.f);
      const int d_star = static_cast<int>(std::max_element(w.begin(), w.end()) - w.begin());
      const float step = L / static_cast<float>(p.boundary_samples - 1);
      for (int j = 0; j < p.boundary_samples; ++j) {
        const float t = static_cast<float>(j) * step;
        fg[static_cast<std::size_t>(j)] = vcar::mask_at(mask, g.mean.x() + t * u.x(), g.mean.y() + t * u.y());
      }
      float l = L;
      for (int j = 1; j < p.boundary_samples; ++j)
        if (!fg[static_cast<std::size_t>(j)]) {
          l = 0.5f * (static_cast<float>(j - 1) * step + static_cast<float>(j) * step);
          break;
        }
      const float num = (l / p.sigma_c) * (l / p.sigma_c) - lambda + w[d_star];
      float f = std::numeric_limits<float>::infinity();
      if (w[d_star] > 0.f) f = num > 0.f ? std::sqrt(num / w[d_star]) : p.f_min;
      st[i].f[d_star] = std::min(st[i].f[d_star], f);
    }
    if (overflow) ++st[i].n_ovf;
  }
}

// Scenario "limb": a forward-facing capture (NVOS-like), 20 views within +-20 degrees azimuth and
// +-10 elevation of +z around the unit sphere; Gaussians in a thin shell on the band within
// +-12 degrees of the central view's limb, so most sit on the mask boundary in most views (the
// heavy case: most eligible observations overflow and are traced).
// Scenario "orbit": views all around the sphere, Gaussians over the whole shell (the usual case:
// a Gaussian is near the silhouette in a few views only).
void run_scenario(bool limb_band, int n, int views, int repeats) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> U(-1.f, 1.f), R(0.97f, 1.03f), LS(std::log(0.005f), std::log(0.04f));
  const float limb = std::acos(1.f / 4.f);  // polar angle of the limb seen from distance 4
  vcar::GaussianScene scene;
  scene.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3f d;
    if (limb_band) {
      const float polar = limb + 0.21f * U(rng), az = 3.1415927f * U(rng);
      d = {std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az), std::cos(polar)};
    } else {
      do { d = {U(rng), U(rng), U(rng)}; } while (d.squaredNorm() < 1e-4f || d.squaredNorm() > 1.f);
      d.normalize();
    }
    scene.set(static_cast<std::size_t>(i), d * R(rng), {LS(rng), LS(rng), LS(rng)},
              {U(rng), U(rng), U(rng), U(rng) + 0.01f}, 2.f);
  }
  std::vector<vcar::Index> cand(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) cand[static_cast<std::size_t>(i)] = static_cast<vcar::Index>(i);

  const vcar::Intrinsics k{1280, 720, 1000.f, 1000.f, 640.f, 360.f};
  std::vector<vcar::Camera> cams;
  std::vector<vcar::Mask> masks;
  for (int v = 0; v < views; ++v) {
    const float ph = 6.2831853f * static_cast<float>(v) / static_cast<float>(views);
    const float az = limb_band ? 0.35f * std::cos(ph) : ph, el = limb_band ? 0.17f * std::sin(2.f * ph) : 0.5f * std::sin(3.f * ph);
    const Eigen::Vector3f eye(4.f * std::cos(el) * std::sin(az), 4.f * std::sin(el), 4.f * std::cos(el) * std::cos(az));
    cams.push_back(vcar::Camera::look_at(eye, {0, 0, 0}, {0, 1, 0}, k, "v" + std::to_string(v)));
    masks.push_back(sphere_mask(cams.back()));
  }
  std::printf("\n== scenario %s\n", limb_band ? "limb (Gaussians on the silhouette band, forward-facing views)"
                                              : "orbit (Gaussians over the sphere, views all around)");

  const vcar::AbrParams p;
  // Process CPU seconds beside wall seconds: the machine is shared, CPU time shows the work done.
  std::vector<double> cpu1;
  auto run_lib = [&](int threads, vcar::AbrResult& out, std::size_t& n_vis, std::size_t& n_ovf) {
    vcar::set_num_threads(threads);
    std::vector<double> t;
    for (int r = 0; r < repeats; ++r) {
      const std::clock_t c0 = std::clock();
      const auto t0 = std::chrono::steady_clock::now();
      vcar::BoundaryRefinement abr(scene, cand, p);
      for (int v = 0; v < views; ++v) abr.add_view(cams[static_cast<std::size_t>(v)], masks[static_cast<std::size_t>(v)]);
      out = abr.finish();
      t.push_back(seconds_since(t0));
      if (threads == 1) cpu1.push_back(static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
      n_vis = n_ovf = 0;
      for (std::size_t c = 0; c < abr.size(); ++c) { n_vis += abr.n_vis(c); n_ovf += abr.n_ovf(c); }
    }
    return median(t);
  };

  // As vcar::segment runs it: expect_views and deferred tracing, the flagged candidates left
  // untraced refined once more (vcar::refine_deferred; the same result).
  auto run_deferred = [&](int threads, vcar::AbrResult& out) {
    vcar::set_num_threads(threads);
    std::vector<double> t;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      out = vcar::refine_deferred(scene, cand, p, static_cast<std::size_t>(views), [&](auto&& add) {
        for (int v = 0; v < views; ++v) add(cams[static_cast<std::size_t>(v)], masks[static_cast<std::size_t>(v)]);
      });
      t.push_back(seconds_since(t0));
    }
    return median(t);
  };

  const int hw = vcar::max_threads();
  vcar::AbrResult r1, r2, d1, d2;
  std::size_t vis = 0, ovf = 0;
  const double t1 = run_lib(1, r1, vis, ovf);
  const double t2 = run_lib(std::max(2, hw), r2, vis, ovf);
  const double td1 = run_deferred(1, d1);
  const double td2 = run_deferred(std::max(2, hw), d2);
  vcar::set_num_threads(hw);

  // Plain scalar version, single thread, same rules.
  std::vector<double> tp, cpup;
  std::vector<PlainState> st;
  for (int r = 0; r < std::max(1, repeats / 2); ++r) {
    const std::clock_t c0 = std::clock();
    const auto t0 = std::chrono::steady_clock::now();
    st.assign(static_cast<std::size_t>(n), PlainState{});
    for (int v = 0; v < views; ++v) plain_view(scene, cams[static_cast<std::size_t>(v)], masks[static_cast<std::size_t>(v)], p, st);
    tp.push_back(seconds_since(t0));
    cpup.push_back(static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  const double t_plain = median(tp);
  // Agreement: the plain version's gated, clamped factors against the library's.
  std::size_t plain_compressed = 0, disagree = 0;
  double max_diff = 0;
  for (int i = 0; i < n; ++i) {
    const auto& s = st[static_cast<std::size_t>(i)];
    const bool flagged = s.n_vis > 0 && static_cast<float>(s.n_ovf) / static_cast<float>(s.n_vis) > p.rho;
    bool any = false;
    for (int d = 0; d < 3; ++d) {
      float ls = scene.log_scale[d][static_cast<std::size_t>(i)];
      const float f = std::min(1.f, std::max(p.f_min, s.f[d]));
      if (flagged && f < 1.f) { ls += std::log(f); any = true; }
      const double diff = std::abs(static_cast<double>(ls) - r1.log_scale[d][static_cast<std::size_t>(i)]);
      max_diff = std::max(max_diff, diff);
      if (diff > 1e-3) ++disagree;
    }
    plain_compressed += any;
  }

  const double gv = static_cast<double>(n) * views;
  std::printf("ABR: %d candidates x %d views at %dx%d, %d repeats (median), %d threads available\n", n, views,
              k.width, k.height, repeats, hw);
  std::printf("eligible observations %zu (%.1f%% of Gaussian-views), overflowing %zu; flagged %zu, compressed %zu\n",
              vis, 100.0 * static_cast<double>(vis) / gv, ovf, r1.flagged, r1.compressed);
  std::printf("library 1 thread : %8.3f s  %10.3e Gaussian-views/s  (CPU %.3f s, %.0f ns per Gaussian-view)\n", t1,
              gv / t1, median(cpu1), 1e9 * median(cpu1) / gv);
  std::printf("library %d threads: %8.3f s  %10.3e Gaussian-views/s  (x%.2f vs 1 thread)\n", std::max(2, hw), t2,
              gv / t2, t1 / t2);
  std::printf("refine_deferred (as vcar::segment), 1 thread: %8.3f s  %10.3e Gaussian-views/s  (x%.2f vs add_view of every view), "
              "%d threads: %8.3f s  %10.3e Gaussian-views/s  (x%.2f); %zu retraced; same result: %s\n",
              td1, gv / td1, t1 / td1, std::max(2, hw), td2, gv / td2, t2 / td2, d1.retraced,
              d1.log_scale == r1.log_scale && d2.log_scale == r1.log_scale && d1.axis_compressed == r1.axis_compressed && d2.axis_compressed == r1.axis_compressed ? "yes" : "NO");
  std::printf("plain scalar 1 thread: %8.3f s  %10.3e Gaussian-views/s  (CPU %.3f s, %.0f ns per Gaussian-view)\n",
              t_plain, gv / t_plain, median(cpup), 1e9 * median(cpup) / gv);
  std::printf("ratios: library 1 thread / plain = x%.2f, library %d threads / plain = x%.2f\n", t_plain / t1,
              std::max(2, hw), t_plain / t2);
  std::printf("threads agree bit for bit: %s\n", r1.log_scale == r2.log_scale ? "yes" : "NO");
  std::printf("plain vs library: compressed %zu vs %zu, axes differing by > 1e-3 in log s: %zu, max |d log s| %.2e\n",
              plain_compressed, r1.compressed, disagree, max_diff);
  std::printf("state per candidate: %zu bytes (index, mean, rotation, scales, log-scales, 2 x uint16 counts, 3 minima and the views that set them, the deferred-tracing mark)\n",
              vcar::BoundaryRefinement::bytes_per_candidate());
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 100000;
  const int views = argc > 2 ? std::atoi(argv[2]) : 20;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 5;
  run_scenario(true, n, views, repeats);
  run_scenario(false, n, views, repeats);
  return 0;
}
