#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>

#include "vcar/algo/robust_voting.hpp"
#include "vcar/algo/undershoot.hpp"
#include "vcar/algo/visibility_voting.hpp"

#include "point_scene.hpp"
#include "square_mask.hpp"

using vcar::Camera;
using vcar::ImageF;
using vcar::Index;
using vcar::Mask;

namespace {
Mask square(int x0, int y0, int x1, int y1) { return square_mask(20, 20, x0, y0, x1, y1); }
}  // namespace

TEST_CASE("Eq. R2 by hand: one unoccluded background view shrinks a plain 0.9 once, to 0.6") {
  // Gaussian 0 at pixel (10, 10), z = 2. Nine views: the mask covers it, but the render's surface
  // lies at depth 1 (D / A = 1): occluded (Eq. R3), plain evidence only. One view: background, no
  // render, so unoccluded. R^0 = 9 / 10; V^o = 1, F^o = 0: R^1 = (0 + 2 * 0.9) / (1 + 2) = 0.6. The
  // sure level holds the same view (no R6 band), so it adds nothing: R = 0.6, not 0.4.
  const auto scene = scene_of({{0.1f, 0.1f, 2.f}});
  const Mask full = square(0, 0, 20, 20), empty = square(0, 0, 0, 0);
  ImageF depth(20, 20, 1), alpha(20, 20, 1);
  for (std::size_t p = 0; p < depth.data.size(); ++p) { alpha.data[p] = 1.f; depth.data[p] = 1.f; }
  for (const float gamma : {0.f, 1.f}) {
    CAPTURE(gamma);
    vcar::RobustVoteOptions o;
    o.gamma = gamma;
    vcar::RobustVoting v(scene, o);
    for (int j = 0; j < 9; ++j) v.add_view(cam20(("fg" + std::to_string(j)).c_str()), &full, &depth, &alpha, 0.05f);
    v.add_view(cam20("bg"), &empty);
    CHECK(v.visible(0) == 10); CHECK(v.foreground(0) == 9);
    CHECK(v.visible(0, 1) == 1); CHECK(v.foreground(0, 1) == 0);
    CHECK(v.visible(0, 2) == 1); CHECK(v.foreground(0, 2) == 0);
    CHECK(v.ratio(0) == Approx(0.6f).margin(1e-6));
    CHECK(v.ratio(0, false) == Approx(0.6f).margin(1e-6));
    CHECK(v.kept(0, 0.5f));
    CHECK_FALSE(v.kept(0, 0.7f));
  }
  // kappa 0: the unoccluded view decides alone.
  vcar::RobustVoteOptions k0;
  k0.kappa = 0.f;
  vcar::RobustVoting v0(scene, k0);
  for (int j = 0; j < 9; ++j) v0.add_view(cam20(("fg" + std::to_string(j)).c_str()), &full, &depth, &alpha, 0.05f);
  v0.add_view(cam20("bg"), &empty);
  CHECK(v0.ratio(0) == 0.f);
}

TEST_CASE("Eq. R3 by hand: a Gaussian behind the rendered surface is occluded, within tolerance it is not") {
  const auto scene = scene_of({
      {0.05f, 0.05f, 1.0f},   // 0: on the surface (depth 1)
      {0.1f, 0.1f, 2.0f},     // 1: pixel (10, 10), z = 2: behind the surface -> occluded
      {0.052f, 0.052f, 1.04f},// 2: z = 1.04 <= 1 * 1.05: within the tolerance
      {0.45f, 0.45f, 1.0f},   // 3: pixel (14, 14): alpha 0.4 < 0.5 there: no surface, visible
  });
  const Camera c = cam20("a");
  const Mask m = square(0, 0, 20, 20);
  ImageF depth(20, 20, 1), alpha(20, 20, 1);
  for (std::size_t p = 0; p < depth.data.size(); ++p) { alpha.data[p] = 0.8f; depth.data[p] = 0.8f; }  // D / A = 1
  alpha.data[14 * 20 + 14] = 0.4f;
  depth.data[14 * 20 + 14] = 0.1f;
  vcar::RobustVoting v(scene);
  v.add_view(c, &m, &depth, &alpha, 0.05f);
  CHECK(v.visible(0, 1) == 1);
  CHECK(v.visible(1, 0) == 1);
  CHECK(v.visible(1, 1) == 0);  // occluded: only the plain level counts it
  CHECK(v.visible(2, 1) == 1);
  CHECK(v.visible(3, 1) == 1);
  // Eq. R2 falls back to the plain level for the occluded one: F / V = 1.
  CHECK(v.ratio(1) == 1.f);
}

TEST_CASE("RobustVoting with every mechanism off equals VisibilityVoting (Eq. 1-3) on random scenes") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  std::vector<Eigen::Vector3f> mus(3000);
  for (auto& m : mus) m = {U(rng), U(rng), U(rng) + 2.5f};
  const auto scene = scene_of(mus);
  std::vector<Index> cand;
  for (Index i = 0; i < 3000; i += 3) cand.push_back(i);
  vcar::RobustVoting r(scene, cand);
  vcar::VisibilityVoting p(scene, cand);
  for (int j = 0; j < 12; ++j) {
    Camera c = Camera::look_at({2.f * std::cos(0.5f * j), 0.3f, 2.5f + 2.f * std::sin(0.5f * j)}, {0, 0, 2.5f},
                               {0, -1, 0}, {37, 23, 30, 31, 18.5f, 11.5f}, "c" + std::to_string(j));
    Mask m(37, 23, 1);
    for (auto& b : m.data) b = static_cast<std::uint8_t>(rng() % 2 ? 255 : 0);
    const Mask* mp = j % 5 == 4 ? nullptr : &m;
    r.add_view(c, mp);
    p.add_view(c, mp);
  }
  for (std::size_t k = 0; k < cand.size(); ++k) {
    REQUIRE(r.visible(k) == p.visible(k));
    REQUIRE(r.foreground(k) == p.foreground(k));
    REQUIRE(r.ratio(k) == p.ratio(k));
  }
  std::vector<Index> idx;
  std::vector<float> sc;
  r.selected(0.5f, idx, sc);
  CHECK(idx == p.selected(0.5f));
}

TEST_CASE("RobustVoting rejects masks and depth images of the wrong size, naming the view") {
  const auto scene = scene_of({{0, 0, 1}});
  vcar::RobustVoting v(scene);
  const Camera c = cam20("left");
  Mask bad(10, 20, 1);
  CHECK_THROWS_WITH(v.add_view(c, &bad), Catch::Contains("view 'left'"));
  Mask m(20, 20, 1);
  ImageF d(20, 10, 1), a(20, 20, 1);
  CHECK_THROWS_WITH(v.add_view(c, &m, &d, &a, 0.05f), Catch::Contains("depth/alpha"));
  CHECK_THROWS_WITH(v.add_view(c, &m, &a, nullptr, 0.05f), Catch::Contains("alpha image"));
}

TEST_CASE("Eq. R6 in the vote: background pixels within gamma e_j of an undershooting mask are no evidence") {
  // Render alpha [5, 15)^2; the mask [8, 12)^2 undershoots it by e = 3 px (test_undershoot).
  const auto scene = scene_of({
      {-0.35f, 0.05f, 1},  // 0: pixel (6, 10): 2 px outside the mask, inside the render
      {-0.75f, 0.05f, 1},  // 1: pixel (2, 10): 6 px outside the mask
      {0.05f, 0.05f, 1},   // 2: pixel (10, 10): inside the mask
  });
  const Camera c = cam20("a");
  const Mask m = square(8, 8, 12, 12);
  ImageF alpha(20, 20, 1);
  for (int y = 5; y < 15; ++y)
    for (int x = 5; x < 15; ++x) alpha.data[static_cast<std::size_t>(y) * 20 + x] = 1.f;
  vcar::RobustVoteOptions o;
  o.gamma = 1.f;
  vcar::RobustVoting with(scene, o), without(scene);
  with.add_view(c, &m, nullptr, &alpha);
  without.add_view(c, &m, nullptr, &alpha);
  CHECK(with.last_undershoot_px() == 3.0);
  CHECK(without.visible(0, 2) == 1);  // sure background without R6
  CHECK(with.visible(0, 2) == 0);     // within gamma e = 3 px: unsure
  CHECK(with.visible(1, 2) == 1);     // 6 px out: still sure background
  CHECK(with.foreground(1, 2) == 0);
  CHECK(with.visible(2, 2) == 1);
  CHECK(with.foreground(2, 2) == 1);
  // Without a render of the candidates (the coarse round) R6 has nothing to measure.
  vcar::RobustVoting no_render(scene, o);
  no_render.add_view(c, &m);
  CHECK(no_render.visible(0, 2) == 1);
  // gamma 0.5: reach 1.5 px: pixel 6 is 2 px out: sure again.
  o.gamma = 0.5f;
  vcar::RobustVoting half(scene, o);
  half.add_view(c, &m, nullptr, &alpha);
  CHECK(half.visible(0, 2) == 1);
}

TEST_CASE("Eq. R6c in the vote: ratio(k, false) is the vote without R6, bit for bit (brute force)") {
  // Random scenes, masks that undershoot the render by 0-4 px: the vote with R6 read without it
  // equals a vote that never had R6, for every candidate and every threshold.
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  std::vector<Eigen::Vector3f> mus(2000);
  for (auto& m : mus) m = {0.6f * U(rng), 0.6f * U(rng), 0.6f * U(rng) + 2.5f};
  auto scene = scene_of(mus);
  for (std::size_t i = 0; i < scene.size(); ++i)  // flat, tilted discs
    scene.set(i, mus[i], {-3.f, -3.f, -6.f}, {1.f, U(rng), U(rng), U(rng)}, 0.f);
  std::vector<Index> cand;
  for (Index i = 0; i < 2000; i += 2) cand.push_back(i);
  {
    {
      vcar::RobustVoteOptions with_r6{2.f, 1.5f, false}, without_r6{2.f, 0.f, false};
      vcar::RobustVoting a(scene, cand, with_r6), b(scene, cand, without_r6);
      for (int j = 0; j < 10; ++j) {
        Camera c = Camera::look_at({2.f * std::cos(0.6f * j), 0.4f, 2.5f + 2.f * std::sin(0.6f * j)}, {0, 0, 2.5f},
                                   {0, -1, 0}, {40, 30, 30, 30, 20.f, 15.f}, "c" + std::to_string(j));
        const int x0 = 8 + static_cast<int>(rng() % 4), y0 = 6 + static_cast<int>(rng() % 4);
        const int e = static_cast<int>(rng() % 5);  // the mask's undershoot
        ImageF alpha(40, 30, 1);
        Mask m(40, 30, 1);
        for (int y = y0; y < y0 + 18; ++y)
          for (int x = x0; x < x0 + 24; ++x) {
            alpha.data[static_cast<std::size_t>(y) * 40 + x] = 1.f;
            if (x >= x0 + e && x < x0 + 24 - e && y >= y0 + e && y < y0 + 18 - e)
              m.data[static_cast<std::size_t>(y) * 40 + x] = 255;
          }
        a.add_view(c, &m, nullptr, &alpha);
        b.add_view(c, &m, nullptr, &alpha);
      }
      std::size_t differs = 0;
      for (std::size_t k = 0; k < cand.size(); ++k) {
        REQUIRE(a.ratio(k, false) == b.ratio(k));
        differs += a.ratio(k) != b.ratio(k);
      }
      CHECK(differs > 0);  // R6 changed the vote, so the comparison above means something
      for (float tau : {0.3f, 0.5f, 0.85f}) {
        std::vector<Index> ia, ib;
        std::vector<float> sa, sb;
        a.selected(tau, ia, sa, false);
        b.selected(tau, ib, sb);
        CHECK(ia == ib);
        CHECK(sa == sb);
      }
    }
  }
}

TEST_CASE("Eq. R6c by hand: ratio(k, false) reads the sure level without R6's widening") {
  // Gaussian 0 at pixel (6, 10). View a: the mask [8, 12)^2 undershoots the render [5, 15)^2 by
  // e = 3 px, so pixel (6, 10), 2 px out, is unsure with R6 (reach 3) and sure background
  // without it. View b: a mask over the whole image (no contour: e = 0), foreground.
  // V = V^o = 2, F = F^o = 1: R^0 = R^1 = 1/2 (the same counts: not shrunk). With R6: V^s = 1, F^s = 1,
  // R^2 = (1 + 2 * 1/2) / (1 + 2) = 2/3. Without: V^s = 2, F^s = 1, R^2 = 1/2.
  const auto scene = scene_of({{-0.35f, 0.05f, 1}});
  const Mask ma = square(8, 8, 12, 12), mb = square(0, 0, 20, 20);
  ImageF alpha(20, 20, 1);
  for (int y = 5; y < 15; ++y)
    for (int x = 5; x < 15; ++x) alpha.data[static_cast<std::size_t>(y) * 20 + x] = 1.f;
  vcar::RobustVoteOptions o;
  o.gamma = 1.f;
  vcar::RobustVoting v(scene, o);
  v.add_view(cam20("a"), &ma, nullptr, &alpha);
  v.add_view(cam20("b"), &mb, nullptr, &alpha);
  CHECK(v.ratio(0) == Approx(2.f / 3.f));
  CHECK(v.ratio(0, false) == Approx(0.5f));
  // At tau 0.6 the Gaussian is kept with R6 and dropped without it.
  CHECK(v.kept(0, 0.6f));
  CHECK_FALSE(v.kept(0, 0.6f, false));
  // gamma 0 (R6 off): both readings are the same vote.
  vcar::RobustVoting off(scene);
  off.add_view(cam20("a"), &ma, nullptr, &alpha);
  off.add_view(cam20("b"), &mb, nullptr, &alpha);
  CHECK(off.ratio(0) == off.ratio(0, false));
  CHECK(off.ratio(0) == Approx(0.5f));
}

TEST_CASE("Eq. R13 by hand: a mask on the wrong object stops voting, one on half the target votes half") {
  // Target: Gaussians 0 and 1 at pixels (5, 5) and (6, 6); background: 2 and 3 at (15, 15) and
  // (16, 16). Views 0-2 mask the target, view 3 the background (wrong object), view 4 only
  // Gaussian 0 (a part). Unweighted (Eq. 3): R = 4/5, 3/5, 1/5, 1/5. Consensus at 0.5: {0, 1}.
  // Eq. R13a: r = 1, 1, 1, 0 (A 0, B 2, C 2), 1/2 (A 1, B 0, C 1). Eq. R13b: V^r = 3.5 for every
  // Gaussian; F^r = 3.5, 3, 0, 0. Eq. R2 with kappa 2 over R^0: R_0 = (3.5 + 1.6) / 5.5,
  // R_1 = (3 + 1.2) / 5.5, R_2 = R_3 = 0.4 / 5.5. The consensus stays {0, 1}: a second pass
  // changes nothing.
  const auto scene = scene_of({{-0.5f, -0.5f, 1.f}, {-0.4f, -0.4f, 1.f}, {0.5f, 0.5f, 1.f}, {0.6f, 0.6f, 1.f}});
  const Mask target = square(0, 0, 10, 10), wrong = square(10, 10, 20, 20), part = square(0, 0, 6, 6);
  for (const bool on : {false, true}) {
    CAPTURE(on);
    vcar::RobustVoteOptions o;
    o.reliability = on;
    vcar::RobustVoting v(scene, o);
    for (int j = 0; j < 3; ++j) v.add_view(cam20(("good" + std::to_string(j)).c_str()), &target);
    v.add_view(cam20("wrong"), &wrong);
    v.add_view(cam20("part"), &part);
    const std::vector<float> r = v.weigh_views(0.5f);
    if (!on) {
      CHECK(r.empty());
      CHECK(v.ratio(0) == Approx(0.8f)); CHECK(v.ratio(1) == Approx(0.6f)); CHECK(v.ratio(2) == Approx(0.2f));
      continue;
    }
    REQUIRE(r.size() == 5);
    CHECK(r[0] == 1.f); CHECK(r[1] == 1.f); CHECK(r[2] == 1.f);
    CHECK(r[3] == 0.f);
    CHECK(r[4] == 0.5f);
    CHECK(v.ratio(0) == Approx(5.1f / 5.5f).margin(1e-6));
    CHECK(v.ratio(1) == Approx(4.2f / 5.5f).margin(1e-6));
    CHECK(v.ratio(2) == Approx(0.4f / 5.5f).margin(1e-6));
    CHECK(v.ratio(3) == Approx(0.4f / 5.5f).margin(1e-6));
  }
}

TEST_CASE("Eq. R13 against brute force: view weights and weighted counts on random scenes") {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-0.9f, 0.9f);
  std::vector<Eigen::Vector3f> mus;
  for (int i = 0; i < 300; ++i) mus.push_back({u(rng), u(rng), 1.f + 0.5f * (u(rng) + 0.9f)});
  const auto scene = scene_of(mus);
  std::vector<Mask> masks;
  std::uniform_int_distribution<int> c(0, 19);
  for (int j = 0; j < 7; ++j) {
    const int x0 = c(rng), y0 = c(rng);
    masks.push_back(square(std::min(x0, 8), std::min(y0, 8), std::max(x0, 12), std::max(y0, 12)));
  }
  vcar::RobustVoteOptions o;
  o.reliability = true;
  o.kappa = 1.f;
  vcar::RobustVoting v(scene, o);
  v.chunk = 64;  // several chunks
  for (std::size_t j = 0; j < masks.size(); ++j) v.add_view(cam20(("v" + std::to_string(j)).c_str()), &masks[j]);
  // Brute force: in-view and in-mask per (i, j) by projecting the means (cam20: pixel 10 x / z + 10).
  auto at = [&](std::size_t i, std::size_t j, bool& seen) {
    const float px = 10.f * mus[i].x() / mus[i].z() + 10.f, py = 10.f * mus[i].y() / mus[i].z() + 10.f;
    seen = px >= 0.f && py >= 0.f && px < 20.f && py < 20.f;
    return seen && masks[j].data[static_cast<std::size_t>(static_cast<int>(py)) * 20 + static_cast<std::size_t>(static_cast<int>(px))] != 0;
  };
  std::vector<float> R0(mus.size());
  for (std::size_t i = 0; i < mus.size(); ++i) {
    int V = 0, F = 0;
    for (std::size_t j = 0; j < masks.size(); ++j) { bool s; F += at(i, j, s); V += s; }
    R0[i] = static_cast<float>(F) / static_cast<float>(std::max(V, 1));
  }
  const std::vector<float> r = v.weigh_views(0.5f, 1);  // one pass: the consensus is Eq. 3's
  for (std::size_t j = 0; j < masks.size(); ++j) {
    int a = 0, b = 0, cc = 0;
    for (std::size_t i = 0; i < mus.size(); ++i) {
      bool s;
      const bool f = at(i, j, s);
      const bool S = R0[i] >= 0.5f;
      if (!s) continue;
      a += S && f; b += !S && f; cc += S && !f;
    }
    CAPTURE(j);
    CHECK(r[j] == Approx(a + b + cc ? static_cast<float>(a) / static_cast<float>(a + b + cc) : 1.f).margin(1e-6));
  }
  for (std::size_t i = 0; i < mus.size(); ++i) {
    double V = 0, F = 0;
    for (std::size_t j = 0; j < masks.size(); ++j) { bool s; const bool f = at(i, j, s); V += s ? r[j] : 0; F += f ? r[j] : 0; }
    CAPTURE(i);
    CHECK(v.ratio(i) == Approx((F + 1.0 * R0[i]) / (V + 1.0)).margin(1e-5));
  }
}

TEST_CASE("RobustVoting decides whole chunks exactly as mean by mean: every counter and R13's weights (brute force)") {
  // A dense floor (z = 3) and a dense box in front of it (z about 2), so that many chunks of 256
  // means fall wholly on one side of the masks, the render's surface and R6's band; a render whose
  // surface is the box where it covers it, the floor elsewhere, nothing in one corner; masks of
  // the box that undershoot the render by 0-3 px. Each counter equals the per-mean rules (Eq. 1,
  // 2, R3, R6b) applied to each mean, projected one at a time.
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  std::vector<Eigen::Vector3f> mus;
  for (int i = 0; i < 12000; ++i) mus.push_back({1.6f * U(rng), 1.2f * U(rng), 3.f + 0.01f * U(rng)});
  for (int i = 0; i < 6000; ++i) mus.push_back({0.4f * U(rng), 0.3f * U(rng), 2.f + 0.2f * U(rng)});
  const auto scene = scene_of(mus);
  constexpr int W = 64, H = 48;
  vcar::RobustVoteOptions o{2.f, 1.5f, true};
  vcar::RobustVoting v(scene, o);
  std::vector<std::vector<std::uint8_t>> seen, fg;  // brute force: per view, per mean
  std::array<std::vector<int>, 6> count;
  for (auto& c : count) c.assign(mus.size(), 0);
  for (int j = 0; j < 8; ++j) {
    const Camera c = Camera::look_at({0.3f * std::cos(0.8f * j), 0.2f * std::sin(0.8f * j), 0.f}, {0, 0, 3.f},
                                     {0, -1, 0}, {W, H, 40, 40, 32.f, 24.f}, "c" + std::to_string(j));
    // The render: project the box's corners for its pixel rectangle.
    int bx0 = W, by0 = H, bx1 = -1, by1 = -1;
    for (float sx : {-0.4f, 0.4f})
      for (float sy : {-0.3f, 0.3f})
        for (float sz : {1.8f, 2.2f}) {
          const Eigen::Vector3f q = c.R_w * Eigen::Vector3f(sx, sy, sz) + c.t_w;
          const int u = static_cast<int>(std::floor(c.fx * q.x() / q.z() + c.cx)), w = static_cast<int>(std::floor(c.fy * q.y() / q.z() + c.cy));
          bx0 = std::min(bx0, u), bx1 = std::max(bx1, u), by0 = std::min(by0, w), by1 = std::max(by1, w);
        }
    ImageF depth(W, H, 1), alpha(W, H, 1);
    Mask m(W, H, 1);
    const int e = j % 4;  // the mask's undershoot
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * W + x;
        const bool box = x >= bx0 && x <= bx1 && y >= by0 && y <= by1;
        alpha.data[p] = x < 6 && y < 6 ? 0.2f : 0.9f;
        depth.data[p] = alpha.data[p] * (box ? 1.9f + 0.01f * static_cast<float>(x % 7) : 3.f);
        m.data[p] = x >= bx0 + e && x <= bx1 - e && y >= by0 + e && y <= by1 - e ? 255 : 0;
      }
    v.add_view(c, &m, &depth, &alpha, 0.05f);
    // Brute force, the rules of the file's top: the sure plane from Eq. R6a-b as the vote builds it.
    std::vector<std::uint8_t> sure(m.data.size(), 255);
    vcar::widen_outer_band(m, o.gamma * vcar::undershoot_px(m, alpha), sure);
    const vcar::detail::MeanProjection P = vcar::detail::MeanProjection::from(c);
    seen.emplace_back(mus.size(), 0);
    fg.emplace_back(mus.size(), 0);
    for (std::size_t i = 0; i < mus.size(); ++i) {
      std::int32_t pix[vcar::detail::mean_batch], vis[vcar::detail::mean_batch];
      float z[vcar::detail::mean_batch];
      vcar::detail::project_tail(P, &mus[i].x(), &mus[i].y(), &mus[i].z(), 1, pix, vis, z);
      if (!vis[0]) continue;
      const std::size_t p = static_cast<std::size_t>(pix[0]);
      const int f = m.data[p] != 0;
      ++count[0][i], count[1][i] += f;
      if (alpha.data[p] >= 0.5f && !(z[0] <= depth.data[p] / alpha.data[p] * 1.05f)) continue;
      ++count[2][i], count[3][i] += f;
      seen.back()[i] = 1, fg.back()[i] = static_cast<std::uint8_t>(f);
      if (!sure[p]) continue;
      ++count[4][i], count[5][i] += f;
    }
  }
  CAPTURE(v.whole_chunks(), v.chunk_views());
  CHECK(v.whole_chunks() > v.chunk_views() / 10);  // the whole-chunk path is what is tested
  CHECK(v.whole_chunks() < v.chunk_views());      // and the per-mean one as well
  std::size_t occluded = 0, unsure = 0;
  for (std::size_t i = 0; i < mus.size(); ++i) {
    CAPTURE(i);
    for (int level = 0; level < 3; ++level) {
      REQUIRE(v.visible(i, level) == count[2 * level][i]);
      REQUIRE(v.foreground(i, level) == count[2 * level + 1][i]);
    }
    occluded += count[2][i] < count[0][i];
    unsure += count[4][i] < count[2][i];
  }
  CHECK(occluded > 1000);  // Eq. R3 and R6b acted
  CHECK(unsure > 100);
  // R13's weights (Eq. R13a) from the brute-force bits and the vote's own consensus at 0.5.
  std::vector<std::uint8_t> S(mus.size());
  for (std::size_t i = 0; i < mus.size(); ++i) S[i] = v.ratio(i) >= 0.5f;
  const std::vector<float> r = v.weigh_views(0.5f, 1);
  for (std::size_t j = 0; j < seen.size(); ++j) {
    int a = 0, b = 0, cc = 0;
    for (std::size_t i = 0; i < mus.size(); ++i) {
      if (!seen[j][i]) continue;
      a += S[i] && fg[j][i]; b += !S[i] && fg[j][i]; cc += S[i] && !fg[j][i];
    }
    CAPTURE(j);
    CHECK(r[j] == Approx(a + b + cc ? static_cast<float>(a) / static_cast<float>(a + b + cc) : 1.f).margin(1e-6));
  }
}
