#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

#include "two_blobs.hpp"
#include "vcar/baselines/contribution_walk.hpp"
#include "vcar/core/projection.hpp"

TEST_CASE("tiled walk matches a brute-force compositor over all Gaussians") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  vcar::GaussianScene s;
  s.resize(40);
  for (int i = 0; i < 40; ++i)
    s.set(i, {U(rng), U(rng), U(rng)}, {std::log(0.05f + 0.1f * (U(rng) + 1)), std::log(0.05f + 0.1f * (U(rng) + 1)), std::log(0.1f)},
          {1, U(rng), U(rng), U(rng)}, 2.f * U(rng));
  const auto cam = vcar::Camera::look_at({0.3f, 0.2f, -4.f}, {0, 0, 0}, {0, -1, 0}, {70, 50, 60.f, 60.f, 35.f, 25.f});
  std::vector<double> tiled(40, 0.0), brute(40, 0.0);
  vcar::baselines::for_each_contribution(s, cam, nullptr, [&](std::size_t, vcar::Index i, float a, float T) {
    tiled[i] += a * T;
  }, false);
  // Brute force: every projected Gaussian at every pixel, depth order, same compositing rules.
  std::vector<vcar::ProjectedGaussian> g(40);
  std::vector<int> order;
  for (int i = 0; i < 40; ++i) {
    g[i] = vcar::project_gaussian(cam, s.mu(i), s.R(i), s.scale(i), s.opacity(i));
    if (g[i].valid && g[i].on_screen) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return g[a].depth < g[b].depth; });
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      float T = 1.f;
      for (int i : order) {
        const Eigen::Vector2f d = g[i].mean - Eigen::Vector2f(x + 0.5f, y + 0.5f);
        const float sigma = 0.5f * (g[i].conic.x() * d.x() * d.x() + g[i].conic.z() * d.y() * d.y()) +
                            g[i].conic.y() * d.x() * d.y();
        if (sigma < 0.f) continue;
        const float a = std::min(0.999f, s.opacity(i) * std::exp(-sigma));
        if (a < 1.f / 255.f) continue;
        if (T * (1.f - a) <= 1e-4f) break;
        brute[i] += a * T;
        T *= 1.f - a;
      }
    }
  double total = 0;
  for (int i = 0; i < 40; ++i) {
    CHECK(tiled[i] == Approx(brute[i]).margin(1e-6));
    total += brute[i];
  }
  CHECK(total > 1.0);  // the scene is actually on screen
}

TEST_CASE("maximum contributor: an opaque front Gaussian wins, a faint one loses") {
  const auto cam = vcar::Camera::look_at({0, 0, -5.f}, {0, 0, 0}, {0, -1, 0}, {32, 32, 40.f, 40.f, 16.f, 16.f});
  vcar::GaussianScene s;
  s.resize(2);
  s.set(0, {0, 0, -1.f}, Eigen::Vector3f::Constant(std::log(0.3f)), {1, 0, 0, 0}, 4.f);  // front, opacity 0.98
  s.set(1, {0, 0, 1.f}, Eigen::Vector3f::Constant(std::log(0.3f)), {1, 0, 0, 0}, 4.f);   // back
  CHECK(vcar::baselines::max_contributor(s, cam)(16, 16) == 0);
  // Front opacity 0.2: back gets ~0.98 * 0.8 > 0.2 at the centre.
  s.opacity_logit[0] = std::log(0.2f / 0.8f);
  const auto who = vcar::baselines::max_contributor(s, cam);
  CHECK(who(16, 16) == 1);
  CHECK(who(0, 0) == vcar::baselines::no_contributor);  // far corner: nothing composited
  // Only the subset is drawn.
  const std::vector<vcar::Index> front{0};
  CHECK(vcar::baselines::max_contributor(s, cam, &front)(16, 16) == 0);
}

#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/baselines/flashsplat.hpp"
#include "vcar/baselines/lbg.hpp"
#include "vcar/baselines/naive_voting.hpp"
#include "vcar/core/parallel.hpp"

TEST_CASE("the reference walk agrees with the CPU backend's contributions") {
  const auto t = test_blobs::make_two_blobs();
  vcar::cpu::TiledRenderer cpu;
  auto walk = test_blobs::walk_renderer();
  for (std::size_t j = 0; j < t.cameras.size(); ++j) {
    vcar::RenderRequest q;
    q.scene = &t.scene;
    q.camera = &t.cameras[j];
    vcar::Contributions a, b;
    a.reset(t.scene.size());
    b.reset(t.scene.size());
    cpu.accumulate_contributions(q, *t.masks[j], a);
    walk.accumulate_contributions(q, *t.masks[j], b);
    for (std::size_t i = 0; i < t.scene.size(); ++i) {
      CHECK(a.weight[i] == Approx(b.weight[i]).epsilon(1e-4).margin(1e-4));
      CHECK(a.weight_fg[i] == Approx(b.weight_fg[i]).epsilon(1e-4).margin(1e-4));
    }
  }
  // A peer method runs on the backend unchanged.
  const auto r = vcar::baselines::flashsplat(cpu, t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  CHECK(r.selected == t.A);
}

TEST_CASE("walk results do not depend on the thread count") {
  const auto t = test_blobs::make_two_blobs();
  const int saved = vcar::max_threads();
  vcar::set_num_threads(1);
  const auto one = vcar::baselines::max_contributor(t.scene, t.cameras[1]);
  const auto lbg1 = vcar::baselines::lbg(t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  vcar::set_num_threads(3);
  const auto many = vcar::baselines::max_contributor(t.scene, t.cameras[1]);
  const auto lbg3 = vcar::baselines::lbg(t.scene, t.cameras, vcar::baselines::masks_from(t.masks));
  vcar::set_num_threads(saved);
  CHECK(one.data == many.data);
  CHECK(lbg1.score == lbg3.score);
}
