#pragma once
// The k-nearest-neighbour graph of Gaussian means that GaussianCut and LUDVIG smooth over,
// built with nanoflann (kd-tree over the chosen Gaussians' means), and the edge similarity
//   w_ij = exp(-|mu_i - mu_j|^2 / (2 sigma_d^2)) * exp(-|c_i - c_j|^2 / (2 sigma_c^2)),
// sigma_d = mean neighbour distance of the graph (scene-scale free), c = degree-0 colour.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <nanoflann.hpp>

#include "vcar/baselines/inputs.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar::baselines {

// nanoflann dataset adaptor over the means of `nodes` (indices into the scene).
struct MeanCloud {
  const GaussianScene* scene;
  const std::vector<Index>* nodes;
  std::size_t kdtree_get_point_count() const { return nodes->size(); }
  float kdtree_get_pt(std::size_t k, std::size_t dim) const { return scene->mean[dim][(*nodes)[k]]; }
  template <class BBox> bool kdtree_get_bbox(BBox&) const { return false; }
};

// Graph over nodes 0..N-1 (positions in `nodes`): node a's neighbours are
// neighbour[a * k + m] for m < count[a], nearest first (ties by node order), self excluded.
struct KnnGraph {
  int k = 0;
  std::vector<std::uint32_t> neighbour;
  std::vector<float> dist2;
  std::vector<std::uint8_t> count;
  float sigma_d = 0;  // mean neighbour distance
};

// k is clamped to [0, 255].
inline KnnGraph build_knn_graph(const GaussianScene& scene, const std::vector<Index>& nodes, int k) {
  k = std::min(std::max(k, 0), 255);
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, MeanCloud>, MeanCloud, 3,
                                                   std::uint32_t>;
  KnnGraph g;
  g.k = k;
  const std::size_t N = nodes.size();
  g.neighbour.assign(N * k, 0);
  g.dist2.assign(N * k, 0.f);
  g.count.assign(N, 0);
  if (N < 2 || k <= 0) return g;
  const MeanCloud cloud{&scene, &nodes};
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  // Scratch per fixed chunk of queries, not per Gaussian.
  parallel_chunks(static_cast<std::int64_t>(N), 1024, [&](std::int64_t, std::int64_t begin, std::int64_t end) {
    std::vector<std::uint32_t> idx(static_cast<std::size_t>(k) + 1);
    std::vector<float> d2(static_cast<std::size_t>(k) + 1);
    std::vector<std::size_t> ord(static_cast<std::size_t>(k) + 1);
    for (std::int64_t a = begin; a < end; ++a) {
      const float q[3] = {scene.mean[0][nodes[a]], scene.mean[1][nodes[a]], scene.mean[2][nodes[a]]};
      const std::size_t found = tree.knnSearch(q, static_cast<std::size_t>(k) + 1, idx.data(), d2.data());
      // Deterministic order whatever the tree's tie handling: by distance, then node.
      for (std::size_t m = 0; m < found; ++m) ord[m] = m;
      std::sort(ord.begin(), ord.begin() + static_cast<std::ptrdiff_t>(found), [&](std::size_t x, std::size_t y) {
        return d2[x] != d2[y] ? d2[x] < d2[y] : idx[x] < idx[y];
      });
      int c = 0;
      for (std::size_t m = 0; m < found && c < k; ++m) {
        if (idx[ord[m]] == static_cast<std::uint32_t>(a)) continue;
        g.neighbour[a * k + c] = idx[ord[m]];
        g.dist2[a * k + c] = d2[ord[m]];
        ++c;
      }
      g.count[a] = static_cast<std::uint8_t>(c);
    }
  });
  double sum = 0; std::size_t edges = 0;
  for (std::size_t a = 0; a < N; ++a)
    for (int m = 0; m < g.count[a]; ++m) { sum += std::sqrt(double(g.dist2[a * k + m])); ++edges; }
  g.sigma_d = edges ? static_cast<float>(sum / double(edges)) : 0.f;
  return g;
}

// w_ij of the header comment for edge (a, m); sigma_c <= 0 drops the colour term.
inline float edge_similarity(const KnnGraph& g, std::size_t a, int m, const std::vector<Eigen::Vector3f>& colour,
                             float sigma_c) {
  const std::uint32_t b = g.neighbour[a * g.k + m];
  const float sd2 = g.sigma_d > 0.f ? g.sigma_d * g.sigma_d : 1.f;
  float w = std::exp(-g.dist2[a * g.k + m] / (2.f * sd2));
  if (sigma_c > 0.f) w *= std::exp(-(colour[a] - colour[b]).squaredNorm() / (2.f * sigma_c * sigma_c));
  return w;
}

}  // namespace vcar::baselines
