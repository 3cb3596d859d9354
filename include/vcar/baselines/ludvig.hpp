#pragma once
// LUDVIG (Marrie et al. 2025), mask lifting plus graph diffusion (conventions §8).
//   f0_i = sum alpha T m / (sum alpha T + 1e-8) over every masked view (uplifting);
//   diffusion over a kNN graph (nanoflann, k = 16) of the contributing Gaussians' means with
//   row-normalised similarities P (knn_graph.hpp: distance and colour kernels), anchored to the
//   lifted values:  f <- (1 - beta) f0 + beta P f, `iterations` = 20 times, beta = 0.5;
//   foreground when f_i > threshold (0.5). Gaussians with no contribution stay 0 (they are
//   outside the graph). The anchored form keeps a constant field constant and converges
//   (beta < 1), so the threshold keeps its meaning of "a foreground majority".
// score_i = f_i after diffusion.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vcar/baselines/inputs.hpp"
#include "vcar/baselines/knn_graph.hpp"
#include "vcar/baselines/view_contributions.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::baselines {

struct LudvigParams {
  int k = 16;
  int iterations = 20;
  float beta = 0.5f;       // weight of the neighbours against the lifted value
  float threshold = 0.5f;  // foreground when f > threshold
  float sigma_c = 0.1f;    // colour kernel width; <= 0 drops colour
};

inline Result ludvig_from(const GaussianScene& scene, const Contributions& c, const LudvigParams& p = {}) {
  const std::size_t n = scene.size();
  std::vector<Index> nodes;
  for (std::size_t i = 0; i < n; ++i)
    if (c.weight[i] > 0.0) nodes.push_back(static_cast<Index>(i));
  const std::size_t N = nodes.size();
  std::vector<float> f0(N), f(N), next(N);
  for (std::size_t a = 0; a < N; ++a)
    f0[a] = f[a] = static_cast<float>(c.weight_fg[nodes[a]] / (c.weight[nodes[a]] + 1e-8));
  if (N >= 2 && p.iterations > 0) {
    const KnnGraph knn = build_knn_graph(scene, nodes, p.k);
    std::vector<Eigen::Vector3f> colour(N);
    for (std::size_t a = 0; a < N; ++a) colour[a] = dc_colour(scene, nodes[a]);
    std::vector<float> w(N * static_cast<std::size_t>(knn.k), 0.f);
    for (std::size_t a = 0; a < N; ++a)
      for (int m = 0; m < knn.count[a]; ++m) w[a * knn.k + m] = edge_similarity(knn, a, m, colour, p.sigma_c);
    for (int it = 0; it < p.iterations; ++it) {
      parallel_for(static_cast<std::int64_t>(N), [&](std::int64_t a) {
        double num = 0, den = 0;
        for (int m = 0; m < knn.count[a]; ++m) {
          num += double(w[a * knn.k + m]) * f[knn.neighbour[a * knn.k + m]];
          den += w[a * knn.k + m];
        }
        const float Pf = den > 0 ? static_cast<float>(num / den) : f0[a];
        next[a] = (1.f - p.beta) * f0[a] + p.beta * Pf;
      });
      f.swap(next);
    }
  }
  Result r;
  r.score.assign(n, 0.f);
  for (std::size_t a = 0; a < N; ++a) r.score[nodes[a]] = f[a];
  r.selected = select_where(n, [&](std::size_t i) { return r.score[i] > p.threshold; });
  return r;
}

template <ContributionRenderer R>
Result ludvig(R& renderer, const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
              const LudvigParams& p = {}) {
  return ludvig_from(scene, view_contributions(renderer, scene, cameras, masks), p);
}

}  // namespace vcar::baselines
