#pragma once
// SAGD (Hu et al. 2024) as specified in conventions §8.
//
// Selection: in every view the centre gets the label of Eq. 2 (-1 invisible or no mask, 0
// background, 1 foreground); the mode over ALL views (-1 included) must be 1 and its share of the
// views must exceed 0.7 (strict). score_i = share of views labelling i foreground. Ties in the
// mode can never select (a tied mode has share <= 0.5).
//
// Boundary decomposition of each selected Gaussian, per view with a mask:
//   endpoints e+- = mu +- 1.5 s_max r_max (the 3D major axis); when exactly one endpoint is
//   foreground (an invisible endpoint counts as not foreground), the segment e- .. e+ is sampled
//   at `samples` evenly spaced 3D points, each projected and looked up (floor pixel, off-image =
//   outside), r_j = inside fraction. Over the views that trigger:
//     r = mean of r_j;  scales *= 0.8 r on all axes;
//     mean += dir * 0.5 (1 - r) * 3 s_max * r_max, dir = sign of sum_j +-(1 - r_j), + when e+ is
//     the inside endpoint of view j (0: views disagree exactly, the mean stays).
//   A Gaussian no view triggers is unchanged.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vcar/baselines/inputs.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::baselines {

struct SagdParams {
  float share_min = 0.7f;     // the mode's share must exceed this
  float endpoint_sigma = 1.5f;  // endpoints at +- this many sigma of the major axis
  float scale_factor = 0.8f;  // scales *= scale_factor * r
  float shift_factor = 0.5f;  // mean moves by shift_factor (1 - r) * 3 sigma
  int samples = 33;           // points on the segment for the inside fraction
  bool decompose = true;
};

struct SagdResult : Result {
  // New means and log-scales of the selected Gaussians, aligned with `selected`.
  std::array<std::vector<float>, 3> mean;
  LogScales log_scale;
  std::vector<std::uint8_t> decomposed;  // 1 where some view triggered (aligned with selected)

  // The selection as a scene with the decomposed geometry (for rendering and evaluation).
  GaussianScene scene_of(const GaussianScene& scene) const {
    GaussianScene out = scene.subset(selected);
    for (int d = 0; d < 3; ++d) { out.mean[d] = mean[d]; out.log_scale[d] = log_scale[d]; }
    return out;
  }
};

inline SagdResult sagd(const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
                       const SagdParams& p = {}) {
  const std::size_t n = scene.size(), M = cameras.size();
  std::vector<std::uint32_t> c_fg(n, 0), c_bg(n, 0), c_inv(n, 0);
  for (std::size_t j = 0; j < M; ++j) {
    const Mask* m = checked_mask(masks, cameras, j);
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
      const int l = point_label(cameras[j], m, scene.mu(i));  // Eq. 2
      (l == 1 ? c_fg : l == 0 ? c_bg : c_inv)[i] += 1;
    });
  }
  SagdResult r;
  r.score.resize(n);
  for (std::size_t i = 0; i < n; ++i) r.score[i] = M ? float(c_fg[i]) / float(M) : 0.f;
  r.selected = select_where(n, [&](std::size_t i) {
    return c_fg[i] > c_bg[i] && c_fg[i] > c_inv[i] && double(c_fg[i]) > p.share_min * double(M);
  });
  const std::size_t S = r.selected.size();
  for (int d = 0; d < 3; ++d) {
    r.mean[d].resize(S); r.log_scale[d].resize(S);
    for (std::size_t k = 0; k < S; ++k) {
      r.mean[d][k] = scene.mean[d][r.selected[k]];
      r.log_scale[d][k] = scene.log_scale[d][r.selected[k]];
    }
  }
  r.decomposed.assign(S, 0);
  if (!p.decompose || S == 0) return r;
  std::vector<float> r_sum(S, 0.f), dir_sum(S, 0.f);
  std::vector<std::uint32_t> hits(S, 0);
  for (std::size_t j = 0; j < M; ++j) {
    const Mask* m = checked_mask(masks, cameras, j);
    if (!m) continue;
    parallel_for(static_cast<std::int64_t>(S), [&](std::int64_t k) {
      const std::size_t i = r.selected[k];
      const Eigen::Vector3f s = scene.scale(i);
      int dmax = 0;
      for (int d = 1; d < 3; ++d) if (s[d] > s[dmax]) dmax = d;
      const Eigen::Vector3f axis = scene.R(i).col(dmax) * (p.endpoint_sigma * s[dmax]);
      const Eigen::Vector3f mu = scene.mu(i);
      const bool in_plus = point_label(cameras[j], m, mu + axis) == 1;
      const bool in_minus = point_label(cameras[j], m, mu - axis) == 1;
      if (in_plus == in_minus) return;
      int inside = 0;
      for (int t = 0; t < p.samples; ++t) {
        const float f = p.samples > 1 ? -1.f + 2.f * float(t) / float(p.samples - 1) : 0.f;
        inside += point_label(cameras[j], m, mu + f * axis) == 1;
      }
      const float rj = float(inside) / float(p.samples);
      r_sum[k] += rj;
      dir_sum[k] += (in_plus ? 1.f : -1.f) * (1.f - rj);
      ++hits[k];
    });
  }
  for (std::size_t k = 0; k < S; ++k) {
    if (hits[k] == 0) continue;
    const std::size_t i = r.selected[k];
    const float rr = r_sum[k] / float(hits[k]);
    const Eigen::Vector3f s = scene.scale(i);
    int dmax = 0;
    for (int d = 1; d < 3; ++d) if (s[d] > s[dmax]) dmax = d;
    const float dir = dir_sum[k] > 0.f ? 1.f : (dir_sum[k] < 0.f ? -1.f : 0.f);
    const Eigen::Vector3f shift = scene.R(i).col(dmax) * (dir * p.shift_factor * (1.f - rr) * 3.f * s[dmax]);
    const float dlog = std::log(std::max(p.scale_factor * rr, 1e-6f));  // rr > 0: one endpoint is inside
    for (int d = 0; d < 3; ++d) {
      r.mean[d][k] += shift[d];
      r.log_scale[d][k] += dlog;
    }
    r.decomposed[k] = 1;
  }
  return r;
}

}  // namespace vcar::baselines
