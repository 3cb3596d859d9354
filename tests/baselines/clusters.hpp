#pragma once
// Test fixture: two 3x3x3 grid clusters (spacing 0.1, 5 apart) with hand-set per-Gaussian
// contributions, for the graph-based methods.
#include <cmath>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace test_clusters {

struct Clusters {
  vcar::GaussianScene scene;
  vcar::Contributions c;
  static constexpr int per = 27;  // cluster A: 0..26, cluster B: 27..53; 13 is A's centre
};

// fg fraction 1 for A and 0 for B, weight 1 each.
inline Clusters make_clusters() {
  Clusters t;
  t.scene.resize(2 * Clusters::per);
  t.c.reset(2 * Clusters::per);
  int k = 0;
  for (int blob = 0; blob < 2; ++blob)
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x, ++k) {
          t.scene.set(k, {5.f * blob + 0.1f * x, 0.1f * y, 0.1f * z}, Eigen::Vector3f::Constant(std::log(0.05f)),
                      {1, 0, 0, 0}, 2.f);
          t.scene.set_rgb(k, {0.5f, 0.5f, 0.5f});
          t.c.weight[k] = 1.0;
          t.c.weight_fg[k] = blob == 0 ? 1.0 : 0.0;
        }
  return t;
}

}  // namespace test_clusters
