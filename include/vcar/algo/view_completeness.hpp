#pragma once
// View completeness assessment (Eq. 6, supplementary A.1-A.3): which training cameras see the
// coarse object (rho^(j) >= rho_min), their headings from the object centre, and the largest
// angular gap Delta_max between K Fibonacci probe directions and the nearest heading.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/simd.hpp"

namespace vcar {

// Unit directions as structure-of-arrays.
struct Directions {
  std::vector<float> x, y, z;
  std::size_t size() const noexcept { return x.size(); }
  Eigen::Vector3f operator[](std::size_t i) const { return {x[i], y[i], z[i]}; }
  void push_back(const Eigen::Vector3f& d) { x.push_back(d.x()); y.push_back(d.y()); z.push_back(d.z()); }
};

// A.3: phi_i = acos(1 - 2 (i + 0.5) / K), theta_i = pi (1 + sqrt 5) i,
// t_i = (sin phi cos theta, sin phi sin theta, cos phi), i = 0..K-1 (computed in double).
inline Directions fibonacci_lattice(int K) {
  if (K < 1) throw Error("K must be >= 1, got " + std::to_string(K), "K");
  Directions t;
  t.x.resize(K); t.y.resize(K); t.z.resize(K);
  const double golden = std::numbers::pi * (1.0 + std::sqrt(5.0));
  for (int i = 0; i < K; ++i) {
    const double phi = std::acos(1.0 - 2.0 * (i + 0.5) / K);
    const double theta = golden * i;
    t.x[i] = static_cast<float>(std::sin(phi) * std::cos(theta));
    t.y[i] = static_cast<float>(std::sin(phi) * std::sin(theta));
    t.z[i] = static_cast<float>(std::cos(phi));
  }
  return t;
}

// The coarse object's means gathered once (SoA) for the per-camera visibility tests of A.1.
struct ObjectPoints {
  std::vector<float> x, y, z;
  ObjectPoints(const GaussianScene& scene, std::span<const Index> indices) {
    x.resize(indices.size()); y.resize(indices.size()); z.resize(indices.size());
    for (std::size_t k = 0; k < indices.size(); ++k) {
      x[k] = scene.mean[0][indices[k]]; y[k] = scene.mean[1][indices[k]]; z[k] = scene.mean[2][indices[k]];
    }
  }
  std::size_t size() const noexcept { return x.size(); }
};

// A.1: rho^(j) = (1 / N_c) sum_i 1[visible_i^(j)] with the Eq. 1 test; 0 for an empty set.
inline float visible_fraction(const ObjectPoints& P, const Camera& camera) {
  const std::size_t n = P.size();
  if (n == 0) return 0.f;
  const auto w = detail::MeanProjection::from(camera);
  constexpr std::size_t L = detail::mean_batch;
  alignas(64) std::int32_t pix[L], vis[L];
  alignas(64) float depth[L];
  std::size_t count = 0;
  for (std::size_t i0 = 0; i0 < n; i0 += L) {
    const std::size_t m = std::min(L, n - i0);
    if (m == L) detail::project_batch(w, &P.x[i0], &P.y[i0], &P.z[i0], pix, vis, depth);
    else detail::project_tail(w, &P.x[i0], &P.y[i0], &P.z[i0], m, pix, vis, depth);
    for (std::size_t l = 0; l < L; ++l) count += static_cast<std::size_t>(vis[l]);
  }
  return static_cast<float>(static_cast<double>(count) / static_cast<double>(n));
}

inline float visible_fraction(const GaussianScene& scene, std::span<const Index> indices, const Camera& camera) {
  return visible_fraction(ObjectPoints(scene, indices), camera);
}

// A.1: positions (in `cameras`) of the valid cameras, rho^(j) >= rho_min, ascending.
inline std::vector<std::size_t> valid_cameras(const GaussianScene& scene, std::span<const Index> indices,
                                              std::span<const Camera> cameras, float rho_min) {
  const ObjectPoints P(scene, indices);
  std::vector<float> rho(cameras.size());
  parallel_for(static_cast<std::int64_t>(cameras.size()), [&](std::int64_t j) { rho[j] = visible_fraction(P, cameras[j]); });
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < cameras.size(); ++j)
    if (rho[j] >= rho_min) out.push_back(j);
  return out;
}

// A.2: h_j = (v_pos - c) / |v_pos - c| for the chosen cameras; a camera at the centre (zero or
// non-finite distance) has no heading and is skipped.
inline Directions headings(std::span<const Camera> cameras, std::span<const std::size_t> chosen,
                           const Eigen::Vector3f& c) {
  Directions h;
  for (std::size_t j : chosen) {
    const Eigen::Vector3f d = cameras[j].position() - c;
    const float len = d.norm();
    if (len > 0.f && std::isfinite(len)) h.push_back(d / len);
  }
  return h;
}

// A.2 from positions: h_j = (p_j - c) / |p_j - c|, skipping positions at the centre.
inline Directions headings(const Eigen::Vector3f& c, std::span<const Eigen::Vector3f> positions) {
  Directions h;
  for (const Eigen::Vector3f& p : positions) {
    const Eigen::Vector3f d = p - c;
    const float len = d.norm();
    if (len > 0.f && std::isfinite(len)) h.push_back(d / len);
  }
  return h;
}

struct AngularGap {
  float Delta_max_rad = 0.f;  // Eq. 6
  float Delta_max_deg = 0.f;
  Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();  // probe t_i of the largest gap (from c outward)
  std::size_t probe = 0;          // its lattice index
  std::size_t valid_cameras = 0;  // number of headings used
};

// Eq. 6 / A.3: Delta_max = max_i acos(max_j t_i . h_j). Since acos is decreasing this is
// acos(min_i max_j t_i . h_j): the inner loop is dot products and max only, one acos at the
// end. Ties go to the lowest probe index. No heading: Delta_max = 180 degrees (nothing is
// covered), direction = t_0.
inline AngularGap max_angular_gap(const Directions& t, const Directions& h) {
  AngularGap g;
  g.valid_cameras = h.size();
  if (h.size() == 0 || t.size() == 0) {
    g.Delta_max_rad = static_cast<float>(std::numbers::pi);
    g.Delta_max_deg = 180.f;
    if (t.size() > 0) g.direction = t[0];
    return g;
  }
  using B = simd::batch<float>;
  constexpr std::size_t L = B::size;
  const std::size_t K = t.size(), J = h.size();
  float worst = 2.f;  // min over probes of the best cosine
  std::size_t worst_i = 0;
  alignas(64) float px[L], py[L], pz[L], best[L];
  for (std::size_t i0 = 0; i0 < K; i0 += L) {
    const std::size_t m = std::min(L, K - i0);
    for (std::size_t l = 0; l < L; ++l) {  // pad the tail by repeating the last probe
      const std::size_t i = i0 + std::min(l, m - 1);
      px[l] = t.x[i]; py[l] = t.y[i]; pz[l] = t.z[i];
    }
    const B X = B::load_aligned(px), Y = B::load_aligned(py), Z = B::load_aligned(pz);
    B b(-2.f);
    for (std::size_t j = 0; j < J; ++j)
      b = simd::max(b, simd::fma(X, B(h.x[j]), simd::fma(Y, B(h.y[j]), Z * B(h.z[j]))));  // C_ij = t_i . h_j
    b.store_aligned(best);
    for (std::size_t l = 0; l < m; ++l)
      if (best[l] < worst) { worst = best[l]; worst_i = i0 + l; }
  }
  const double delta = std::acos(std::clamp(static_cast<double>(worst), -1.0, 1.0));
  g.Delta_max_rad = static_cast<float>(delta);
  g.Delta_max_deg = static_cast<float>(delta * 180.0 / std::numbers::pi);
  g.probe = worst_i;
  g.direction = t[worst_i];
  return g;
}

// Sec. 3.3.2 in one call: valid cameras (A.1), headings (A.2), Delta_max (Eq. 6) with K probes.
inline AngularGap assess_view_completeness(const GaussianScene& scene, std::span<const Index> indices,
                                           std::span<const Camera> cameras, const Eigen::Vector3f& c,
                                           float rho_min, int K) {
  const auto valid = valid_cameras(scene, indices, cameras, rho_min);
  return max_angular_gap(fibonacci_lattice(K), headings(cameras, valid, c));
}

}  // namespace vcar
