#pragma once
// GaussianCut (Jain et al. 2024), training-free part (conventions §8).
//
// Coarse: w_i = sum alpha T m / sum alpha T over every masked view; coarse foreground when
// w_i >= tau_w (0.9; 0.3 for 360-degree scenes). Gaussians with no contribution at all get w = 0
// and stay background (they are outside the graph).
// Graph cut over the contributing Gaussians on a k = 10 nearest-neighbour graph of the means
// (nanoflann), solved with Boost's boykov_kolmogorov_max_flow (source = foreground):
//   unary (cost of each label), normalised so a Gaussian at w = 0 or 1 costs lambda_u:
//     cost_fg(i) = lambda_u max(0, tau_w - w_i) / tau_w,
//     cost_bg(i) = lambda_u max(0, w_i - tau_w) / (1 - tau_w);
//   pairwise for each kNN edge: lambda_p * exp(-d^2 / 2 sigma_d^2) * exp(-|dc|^2 / 2 sigma_c^2)
//     (knn_graph.hpp: sigma_d = mean neighbour distance, c = degree-0 colour, sigma_c = 0.1).
// Constants: k = 10, lambda_u = 1, lambda_p = 0.1 (an isolated Gaussian among 10 identical
// neighbours flips when its unary margin is below ~1, i.e. it follows its neighbours unless its
// own evidence is strong). A vertex the cut leaves free keeps its coarse label.
// score_i = w_i.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

// GCC reports a false -Wmaybe-uninitialized inside Boost's edge iterators once BK is inlined.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include "vcar/baselines/inputs.hpp"
#include "vcar/baselines/knn_graph.hpp"
#include "vcar/baselines/view_contributions.hpp"

namespace vcar::baselines {

struct GaussianCutParams {
  float tau_w = 0.9f;     // coarse foreground threshold (0.3 for 360-degree scenes)
  int k = 10;             // neighbours per Gaussian
  float lambda_u = 1.f;   // unary weight
  float lambda_p = 0.1f;  // pairwise weight
  float sigma_c = 0.1f;   // colour kernel width (rgb in [0, 1]); <= 0 drops colour
  bool graph_cut = true;  // false: the coarse threshold only
};

inline Result gaussian_cut_from(const GaussianScene& scene, const Contributions& c, const GaussianCutParams& p = {}) {
  const std::size_t n = scene.size();
  Result r;
  r.score.assign(n, 0.f);
  std::vector<Index> nodes;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(c.weight[i] > 0.0)) continue;
    r.score[i] = static_cast<float>(c.weight_fg[i] / c.weight[i]);
    nodes.push_back(static_cast<Index>(i));
  }
  std::vector<std::uint8_t> fg(n, 0);
  for (Index i : nodes) fg[i] = r.score[i] >= p.tau_w;
  if (p.graph_cut && nodes.size() >= 2) {
    using namespace boost;
    using Traits = adjacency_list_traits<vecS, vecS, directedS>;
    using Graph = adjacency_list<vecS, vecS, directedS,
        property<vertex_color_t, default_color_type,
            property<vertex_distance_t, long, property<vertex_predecessor_t, Traits::edge_descriptor>>>,
        property<edge_capacity_t, double,
            property<edge_residual_capacity_t, double, property<edge_reverse_t, Traits::edge_descriptor>>>>;
    const std::size_t N = nodes.size();
    Graph g(N + 2);
    const auto src = vertex(N, g), snk = vertex(N + 1, g);
    auto cap = get(edge_capacity, g);
    auto rev = get(edge_reverse, g);
    auto link = [&](std::size_t a, std::size_t b, double ab, double ba) {
      const auto e = add_edge(vertex(a, g), vertex(b, g), g).first;
      const auto f = add_edge(vertex(b, g), vertex(a, g), g).first;
      cap[e] = ab; cap[f] = ba; rev[e] = f; rev[f] = e;
    };
    const double tau = p.tau_w;
    for (std::size_t a = 0; a < N; ++a) {
      const double w = r.score[nodes[a]];
      const double cost_fg = p.lambda_u * std::max(0.0, tau - w) / tau;
      const double cost_bg = p.lambda_u * std::max(0.0, w - tau) / std::max(1e-6, 1.0 - tau);
      if (cost_bg > 0) link(N, a, cost_bg, 0.0);  // cut (paid) when a ends on the sink side
      if (cost_fg > 0) link(a, N + 1, cost_fg, 0.0);
    }
    const KnnGraph knn = build_knn_graph(scene, nodes, p.k);
    std::vector<Eigen::Vector3f> colour(N);
    for (std::size_t a = 0; a < N; ++a) colour[a] = dc_colour(scene, nodes[a]);
    for (std::size_t a = 0; a < N; ++a)
      for (int m = 0; m < knn.count[a]; ++m) {
        const double w = p.lambda_p * edge_similarity(knn, a, m, colour, p.sigma_c);
        link(a, knn.neighbour[a * knn.k + m], w, w);
      }
    boykov_kolmogorov_max_flow(g, cap, get(edge_residual_capacity, g), rev, get(vertex_predecessor, g),
                               get(vertex_color, g), get(vertex_distance, g), get(vertex_index, g), src, snk);
    auto colour_map = get(vertex_color, g);
    for (std::size_t a = 0; a < N; ++a) {
      const auto col = get(colour_map, vertex(a, g));
      if (col == color_traits<default_color_type>::black()) fg[nodes[a]] = 1;       // source tree
      else if (col == color_traits<default_color_type>::white()) fg[nodes[a]] = 0;  // sink tree
    }
  }
  r.selected = select_where(n, [&](std::size_t i) { return fg[i] != 0; });
  return r;
}

template <ContributionRenderer R>
Result gaussian_cut(R& renderer, const GaussianScene& scene, std::span<const Camera> cameras, const MaskProvider& masks,
                    const GaussianCutParams& p = {}) {
  return gaussian_cut_from(scene, view_contributions(renderer, scene, cameras, masks), p);
}

}  // namespace vcar::baselines
