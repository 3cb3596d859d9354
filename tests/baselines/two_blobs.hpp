#pragma once
// Test fixture: two separated blobs of Gaussians (A left, B right), five cameras on an arc in
// front of them (no view puts one blob behind the other), masks of blob A rendered with the
// reference walk (alpha of A alone > 0.01: the whole footprint,
// as a segmenter outlines an object), and a ContributionRenderer built on the same walk.
#include <cmath>
#include <optional>
#include <vector>

#include "vcar/baselines/contribution_walk.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace test_blobs {

struct TwoBlobs {
  vcar::GaussianScene scene;
  std::vector<vcar::Index> A, B;
  std::vector<vcar::Camera> cameras;
  std::vector<std::optional<vcar::Mask>> masks;
};

inline vcar::ImageF walk_alpha(const vcar::GaussianScene& s, const vcar::Camera& cam,
                               const std::vector<vcar::Index>* subset) {
  vcar::ImageF a(cam.width, cam.height, 1, 0.f);
  vcar::baselines::for_each_contribution(s, cam, subset, [&](std::size_t p, vcar::Index, float alpha, float T) {
    a.data[p] += alpha * T;
  });
  return a;
}

// A ContributionRenderer (alpha only; rgb stays black) from the reference walk.
inline auto walk_renderer() {
  auto r = vcar::make_contribution_renderer(
      [](const vcar::RenderRequest& q) {
        vcar::RenderOutput o;
        o.alpha = walk_alpha(*q.scene, *q.camera, q.subset);
        o.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
        return o;
      },
      [](const vcar::RenderRequest& q, const vcar::Mask& m, vcar::Contributions& c) {
        vcar::baselines::for_each_contribution(*q.scene, *q.camera, q.subset,
            [&](std::size_t p, vcar::Index i, float alpha, float T) {
              c.weight[i] += alpha * T;
              if (m.data[p]) c.weight_fg[i] += alpha * T;
            }, /*parallel=*/false);
      });
  static_assert(vcar::ContributionRenderer<decltype(r)>);
  return r;
}

inline TwoBlobs make_two_blobs() {
  TwoBlobs t;
  t.scene.resize(18);
  int k = 0;
  for (int blob = 0; blob < 2; ++blob)
    for (int gy = -1; gy <= 1; ++gy)
      for (int gx = -1; gx <= 1; ++gx, ++k) {
        const float cx = blob == 0 ? -1.2f : 1.2f;
        t.scene.set(k, {cx + 0.2f * gx, 0.2f * gy, 0.f}, Eigen::Vector3f::Constant(std::log(0.15f)),
                    {1, 0, 0, 0}, 3.f);  // opacity ~0.95
        t.scene.set_rgb(k, blob == 0 ? Eigen::Vector3f(0.9f, 0.1f, 0.1f) : Eigen::Vector3f(0.1f, 0.1f, 0.9f));
        (blob == 0 ? t.A : t.B).push_back(static_cast<vcar::Index>(k));
      }
  const vcar::Intrinsics K{96, 64, 120.f, 120.f, 48.f, 32.f};
  for (int j = 0; j < 5; ++j) {
    const float th = (-40.f + 20.f * j) * 3.14159265f / 180.f;
    t.cameras.push_back(vcar::Camera::look_at({6.f * std::sin(th), 0.f, -6.f * std::cos(th)}, {0, 0, 0}, {0, -1, 0},
                                              K, "view" + std::to_string(j)));
  }
  for (const auto& cam : t.cameras) t.masks.emplace_back(vcar::threshold(walk_alpha(t.scene, cam, &t.A), 0.01f));
  return t;
}

}  // namespace test_blobs
