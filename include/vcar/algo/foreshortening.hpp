#pragma once
// Beyond the paper: the weight of a view in the vote by how face-on it sees a Gaussian
// (docs/robust.md, Eq. R5).
//
// A surface Gaussian is a flat disc. Seen face-on its centre pixel is deep inside the object's
// mask; seen edge-on it sits on the silhouette rim, where a mask that undershoots or overshoots
// by a pixel flips its label. The projected area of the disc shrinks with |cos| of the angle
// between its normal and the viewing ray, so a view's evidence is weighted by it:
//   n_i   = r_a, the axis of the smallest scale, a = argmin_d s_d
//   phi_i = 1 - s_a / s_b, s_b the smaller of the other two scales   (flatness: disc 1, ball or
//                                                                     needle 0)
//   d_ij  = (mu_i - c_j) / |mu_i - c_j|                               (viewing ray of view j)
//   omega_ij = (1 - phi_i) + phi_i |n_i . d_ij|                                      (Eq. R5)
// A ball (or a needle, whose footprint does not shrink with one angle) weighs 1 in every view.
// Per candidate: phi_i n_i and 1 - phi_i (16 bytes), so a view costs one dot product and a sqrt.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/gaussian_scene.hpp"

namespace vcar {

// phi_i n_i (three columns) and 1 - phi_i of every candidate, for Eq. R5.
struct Foreshortening {
  std::array<std::vector<float>, 3> phi_n;
  std::vector<float> one_minus_phi;

  // Flatness and normal of Gaussian i (Eq. R5: n_i, phi_i).
  static std::pair<Eigen::Vector3f, float> normal_and_flatness(const GaussianScene& scene, Index i) {
    int a = 0;
    for (int d = 1; d < 3; ++d)
      if (scene.log_scale[d][i] < scene.log_scale[a][i]) a = d;
    const float s_b = std::min(scene.log_scale[(a + 1) % 3][i], scene.log_scale[(a + 2) % 3][i]);
    const float phi = std::clamp(1.f - std::exp(scene.log_scale[a][i] - s_b), 0.f, 1.f);
    return {scene.R(i).col(a), std::isfinite(phi) ? phi : 0.f};
  }

  // candidates: scene indices (empty = every Gaussian of the scene, in order).
  static Foreshortening of(const GaussianScene& scene, const std::vector<Index>& candidates) {
    Foreshortening f;
    const std::size_t n = candidates.empty() ? scene.size() : candidates.size();
    for (auto& c : f.phi_n) c.resize(n);
    f.one_minus_phi.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const auto [nrm, phi] = normal_and_flatness(scene, candidates.empty() ? static_cast<Index>(k) : candidates[k]);
      for (int d = 0; d < 3; ++d) f.phi_n[d][k] = phi * nrm[d];
      f.one_minus_phi[k] = 1.f - phi;
    }
    return f;
  }

  // Eq. R5 for candidate k at mean (x, y, z) seen from camera centre c.
  float weight(std::size_t k, float x, float y, float z, const Eigen::Vector3f& c) const {
    const float dx = x - c.x(), dy = y - c.y(), dz = z - c.z();
    const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float dot = phi_n[0][k] * dx + phi_n[1][k] * dy + phi_n[2][k] * dz;
    return len > 0.f ? one_minus_phi[k] + std::abs(dot) / len : 1.f;
  }
};

}  // namespace vcar
