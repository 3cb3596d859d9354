#include <catch2/catch.hpp>

#include <optional>
#include <random>

#include "vcar/algo/visibility_voting.hpp"

#include "point_scene.hpp"

using vcar::Camera;
using vcar::Index;
using vcar::Mask;

namespace {

// Identity pose, fx = fy = 10, principal point (5, 5), 10 x 10: u = 10 x / z + 5.
Camera unit_camera(const char* name) {
  Camera c;
  c.name = name;
  c.width = 10; c.height = 10; c.fx = 10; c.fy = 10; c.cx = 5; c.cy = 5;
  return c;
}


vcar::GaussianScene random_scene(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  std::vector<Eigen::Vector3f> mus(n);
  for (auto& m : mus) m = {U(rng), U(rng), U(rng)};
  return scene_of(mus);
}

std::vector<Camera> ring_cameras(int n) {
  std::vector<Camera> cams;
  for (int j = 0; j < n; ++j) {
    const float a = 6.2831853f * j / n;
    const Eigen::Vector3f eye(2.5f * std::cos(a), 0.7f * std::sin(3.f * a), 2.5f * std::sin(a));
    cams.push_back(Camera::look_at(eye, Eigen::Vector3f::Zero(), {0, -1, 0}, {37, 23, 30, 31, 18.5f, 11.5f},
                                   "cam" + std::to_string(j)));
  }
  return cams;
}

Mask random_mask(int w, int h, std::mt19937& rng) {
  Mask m(w, h, 1);
  for (auto& b : m.data) b = static_cast<std::uint8_t>(rng() % 3 == 0 ? (1 + rng() % 255) : 0);
  return m;
}

// One random mask per camera, drawn in camera order.
std::vector<Mask> random_masks(const std::vector<Camera>& cams, std::mt19937& rng) {
  std::vector<Mask> masks;
  for (const auto& c : cams) masks.push_back(random_mask(c.width, c.height, rng));
  return masks;
}

}  // namespace

namespace {

// Brute-force Eq. 1-2 counts over the views with a mask (the per-mean definition).
void brute_counts(const vcar::GaussianScene& scene, const std::vector<Camera>& cams,
                  const std::vector<const Mask*>& masks, std::vector<int>& V, std::vector<int>& F) {
  V.assign(scene.size(), 0);
  F.assign(scene.size(), 0);
  for (std::size_t j = 0; j < cams.size(); ++j) {
    if (!masks[j]) continue;
    for (std::size_t i = 0; i < scene.size(); ++i) {
      const Eigen::Vector3f t = cams[j].to_camera(scene.mu(i));
      if (!(t.z() > 0)) continue;
      const float u = cams[j].fx * t.x() / t.z() + cams[j].cx, v = cams[j].fy * t.y() / t.z() + cams[j].cy;
      if (!vcar::inside_image(u, v, cams[j].width, cams[j].height)) continue;
      ++V[i];
      F[i] += vcar::mask_at(*masks[j], u, v);
    }
  }
}

// A disc mask (large uniform regions: the chunks of the voter are decided whole).
Mask disc_mask(int W, int H, float cx, float cy, float r) {
  Mask m(W, H, 1, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) m(x, y) = (x + 0.5f - cx) * (x + 0.5f - cx) + (y + 0.5f - cy) * (y + 0.5f - cy) < r * r;
  return m;
}

}  // namespace

TEST_CASE("Eq. 1-3 by hand: boundaries, floor lookup, invisible views and a null mask") {
  const auto scene = scene_of({
      {0, 0, 1},        // 0: pixel (5,5)
      {0.5f, 0, 1},     // 1: u = 10 exactly -> outside
      {0, 0, -1},       // 2: behind camera A, in front of camera D
      {-0.5f, -0.5f, 1},  // 3: u = v = 0 -> pixel (0,0), inside
      {0.09f, 0, 1},    // 4: u = 5.9 -> floor -> pixel (5,5)
      {0.1f, 0, 1},     // 5: u = 6 exactly -> pixel (6,5)
      {0, 0, 0},        // 6: z = 0 -> invisible everywhere
  });
  Camera A = unit_camera("A");
  Camera D = unit_camera("D");
  D.R_w = Eigen::Vector3f(1, -1, -1).asDiagonal();  // half turn about x: looks toward -z
  Mask mA(10, 10, 1, 0), mB(10, 10, 1, 0), mD(10, 10, 1, 255);
  mA(5, 5) = 1;
  mA(0, 0) = 200;

  vcar::VisibilityVoting vote(scene);
  vote.add_view(A, &mA);
  vote.add_view(A, &mB);       // same pose, all background
  vote.add_view(A, nullptr);   // no evidence: nothing counted
  vote.add_view(D, &mD);       // everything at z = 1 is behind this camera
  CHECK(vote.views() == 3);

  const std::vector<int> V = {2, 0, 1, 2, 2, 2, 0}, F = {1, 0, 1, 1, 1, 0, 0};
  for (std::size_t i = 0; i < scene.size(); ++i) {
    INFO("Gaussian " << i);
    CHECK(vote.visible(i) == V[i]);
    CHECK(vote.foreground(i) == F[i]);
    CHECK(vote.ratio(i) == Approx(static_cast<float>(F[i]) / std::max(V[i], 1)));  // Eq. 3
  }
  CHECK(vote.selected(0.5f) == std::vector<Index>{0, 2, 3, 4});
  CHECK(vote.selected(0.6f) == std::vector<Index>{2});
  CHECK(vote.labels(0.5f) == std::vector<std::uint8_t>{1, 0, 1, 1, 1, 0, 0});
  CHECK(vote.selected(0.f).size() == scene.size());  // R >= 0 always (max(., 1) in Eq. 3)
}

TEST_CASE("voting equals a scalar brute force, for any block size and thread count") {
  const auto scene = random_scene(3001, 7);  // not a multiple of the SIMD width
  const auto cams = ring_cameras(11);
  std::mt19937 rng(3);
  std::vector<std::optional<Mask>> masks;
  for (std::size_t j = 0; j < cams.size(); ++j) {
    if (j % 4 == 2) masks.emplace_back();  // a few views without evidence
    else masks.emplace_back(random_mask(cams[j].width, cams[j].height, rng));
  }
  std::vector<const Mask*> ptrs;
  for (const auto& m : masks) ptrs.push_back(m ? &*m : nullptr);
  std::vector<int> V, F;
  brute_counts(scene, cams, ptrs, V, F);
  int visible_somewhere = 0;
  for (int v : V) visible_somewhere += v > 0;
  REQUIRE(visible_somewhere > 100);

  for (int threads : {1, 2}) {
    for (std::size_t block : {1, 3, 8}) {
      vcar::set_num_threads(threads);
      vcar::VisibilityVoting vote(scene);
      vote.accumulator().block_views = block;
      vote.accumulator().chunk = 512;
      for (std::size_t j = 0; j < cams.size(); ++j) vote.add_view(cams[j], masks[j] ? &*masks[j] : nullptr);
      int mismatches = 0;
      for (std::size_t i = 0; i < scene.size(); ++i)
        mismatches += (vote.visible(i) != V[i]) + (vote.foreground(i) != F[i]);
      INFO("threads " << threads << " block " << block);
      CHECK(mismatches == 0);
    }
  }
  vcar::set_num_threads(vcar::max_threads());
}

TEST_CASE("a candidate subset votes like the full scene at those indices") {
  const auto scene = random_scene(500, 11);
  const auto cams = ring_cameras(5);
  std::mt19937 rng(5);
  const std::vector<Mask> masks = random_masks(cams, rng);
  const std::vector<Index> subset = {499, 3, 250, 17, 0, 42};
  vcar::VisibilityVoting all(scene), sub(scene, subset);
  for (std::size_t j = 0; j < cams.size(); ++j) { all.add_view(cams[j], &masks[j]); sub.add_view(cams[j], &masks[j]); }
  REQUIRE(sub.size() == subset.size());
  std::vector<Index> expect;
  for (std::size_t k = 0; k < subset.size(); ++k) {
    CHECK(sub.candidate(k) == subset[k]);
    CHECK(sub.visible(k) == all.visible(subset[k]));
    CHECK(sub.foreground(k) == all.foreground(subset[k]));
    CHECK(sub.ratio_of(subset[k]) == all.ratio_of(subset[k]));
    CHECK(sub.ratio_of(subset[k]) == sub.ratio(k));
    if (all.ratio(subset[k]) >= 0.3f) expect.push_back(subset[k]);
  }
  std::sort(expect.begin(), expect.end());
  CHECK(sub.selected(0.3f) == expect);  // ascending scene indices
  CHECK_THROWS_AS(sub.ratio_of(1), vcar::Error);  // not a candidate
  // A moved accumulator keeps voting on its copied means.
  vcar::VisibilityVoting moved = std::move(sub);
  moved.add_view(cams[0], &masks[0]);
  all.add_view(cams[0], &masks[0]);
  for (std::size_t k = 0; k < subset.size(); ++k) CHECK(moved.visible(k) == all.visible(subset[k]));
}

TEST_CASE("selected with ratios: ascending scene indices, each with its Eq. 3 ratio") {
  // Candidates out of order, scene indices past 2^10 (two of the sort's 10-bit passes).
  const auto scene = random_scene(4000, 13);
  const auto cams = ring_cameras(6);
  std::mt19937 rng(8);
  const std::vector<Mask> masks = random_masks(cams, rng);
  std::vector<Index> subset(4000);
  for (std::size_t k = 0; k < subset.size(); ++k) subset[k] = static_cast<Index>((k * 3761) % 4000);  // a permutation
  std::vector<Index> first_half(subset.begin(), subset.begin() + 2000);
  for (const auto& cand : {subset, first_half}) {
    vcar::VisibilityVoting v(scene, cand);
    for (std::size_t j = 0; j < cams.size(); ++j) v.add_view(cams[j], &masks[j]);
    for (float tau : {0.f, 0.4f, 0.75f, 2.f}) {
      std::vector<Index> idx;
      std::vector<float> ratios;
      v.selected(tau, idx, ratios);
      std::vector<Index> want;  // brute force: every candidate's ratio against tau
      for (Index i : cand)
        if (v.ratio_of(i) >= tau) want.push_back(i);
      std::sort(want.begin(), want.end());
      CHECK(idx == want);
      CHECK(v.selected(tau) == want);
      REQUIRE(ratios.size() == idx.size());
      int wrong = 0;
      for (std::size_t k = 0; k < idx.size(); ++k) wrong += ratios[k] != v.ratio_of(idx[k]) || !(ratios[k] >= tau);
      CHECK(wrong == 0);
    }
  }
}

TEST_CASE("selected over several blocks of sorted positions: the brute-force picks for any thread count") {
  // 140001 candidates: three blocks of 2^16 sorted positions, the last one partial.
  const auto scene = random_scene(140001, 19);
  const auto cams = ring_cameras(4);
  std::mt19937 rng(23);
  const std::vector<Mask> masks = random_masks(cams, rng);
  const int saved = vcar::max_threads();
  for (int threads : {1, std::max(2, saved)}) {
    vcar::set_num_threads(threads);
    vcar::VisibilityVoting v(scene);
    for (std::size_t j = 0; j < cams.size(); ++j) v.add_view(cams[j], &masks[j]);
    for (float tau : {0.f, 0.5f, 0.9f}) {
      INFO(threads << " threads, tau " << tau);
      std::vector<Index> idx, want;
      std::vector<float> ratios;
      v.selected(tau, idx, ratios);
      for (std::size_t i = 0; i < scene.size(); ++i)
        if (v.ratio_of(static_cast<Index>(i)) >= tau) want.push_back(static_cast<Index>(i));
      if (tau == 0.f) CHECK(want.size() == scene.size());  // R >= 0 always
      else CHECK((want.size() > 1000 && want.size() + 1000 < scene.size()));  // picks in every block, not all
      CHECK(idx == want);
      REQUIRE(ratios.size() == idx.size());
      int wrong = 0;
      for (std::size_t k = 0; k < idx.size(); ++k) wrong += ratios[k] != v.ratio_of(idx[k]);
      CHECK(wrong == 0);
    }
  }
  vcar::set_num_threads(saved);
}

TEST_CASE("MultiObjectVoting equals K single votes") {
  const auto scene = random_scene(2000, 13);
  const auto cams = ring_cameras(9);
  std::mt19937 rng(17);
  constexpr int K = 3;
  std::vector<std::array<Mask, K>> masks;
  for (const auto& c : cams)
    masks.push_back({random_mask(c.width, c.height, rng), random_mask(c.width, c.height, rng),
                     random_mask(c.width, c.height, rng)});
  vcar::MultiObjectVoting multi(scene, K);
  std::vector<vcar::VisibilityVoting> single;
  for (int k = 0; k < K; ++k) single.emplace_back(scene);
  for (std::size_t j = 0; j < cams.size(); ++j) {
    if (j == 4) {  // a view without evidence for every object
      std::array<const Mask*, K> none{};
      multi.add_view(cams[j], none);
      continue;
    }
    std::array<const Mask*, K> ptrs{&masks[j][0], &masks[j][1], &masks[j][2]};
    multi.add_view(cams[j], ptrs);
    for (int k = 0; k < K; ++k) single[k].add_view(cams[j], ptrs[k]);
  }
  for (int k = 0; k < K; ++k) {
    int diff = 0;
    for (std::size_t i = 0; i < scene.size(); ++i)
      diff += (multi.visible(i) != single[k].visible(i)) + (multi.foreground(k, i) != single[k].foreground(i));
    CHECK(diff == 0);
    CHECK(multi.selected(k, 0.5f) == single[k].selected(0.5f));
  }
  // Masks of different objects differ, so the per-object results must too.
  CHECK(multi.selected(0, 0.5f) != multi.selected(1, 0.5f));
}

TEST_CASE("occlusion-aware visibility uses the normalised rendered depth") {
  const auto scene = scene_of({{0, 0, 1}, {0, 0, 3}, {0, 0, 2.09f}, {0, 0, 2.11f}, {-1.05f, -1.05f, 3}});  // 4: u = v = 1.5
  const Camera A = unit_camera("A");
  Mask m(10, 10, 1, 255);
  vcar::ImageF depth(10, 10, 1, 1.f), alpha(10, 10, 1, 0.5f);  // normalised depth 1 / 0.5 = 2
  alpha(1, 1) = 0.49f;  // pixel (1,1): no surface -> unoccluded (Gaussian 4 projects there)
  vcar::VisibilityVoting vote(scene);
  vote.add_view(A, &m, &depth, &alpha, 0.05f);  // visible iff z <= 2 * 1.05 = 2.1
  CHECK(vote.visible(0) == 1);
  CHECK(vote.visible(1) == 0);
  CHECK(vote.visible(2) == 1);
  CHECK(vote.visible(3) == 0);
  CHECK(vote.visible(4) == 1);
  vote.add_view(A, &m, nullptr, nullptr, 0.05f);  // no images: plain Eq. 1
  CHECK(vote.visible(1) == 1);
}

TEST_CASE("voting rejects bad masks naming the view, and more than 65535 views") {
  const auto scene = scene_of({{0, 0, 1}});
  const Camera A = unit_camera("IMG_42");
  Mask wrong(9, 10, 1, 0);
  vcar::VisibilityVoting vote(scene);
  try {
    vote.add_view(A, &wrong);
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(e.where().find("IMG_42") != std::string::npos);
  }
  vcar::MultiObjectVoting multi(scene, 2);
  Mask ok(10, 10, 1, 0);
  std::array<const Mask*, 2> mixed{&ok, nullptr};
  CHECK_THROWS_AS(multi.add_view(A, mixed), vcar::Error);

  Mask fg(10, 10, 1, 1);
  for (std::size_t j = 0; j < vcar::MultiObjectVoting::max_views; ++j) vote.add_view(A, &fg);
  CHECK(vote.visible(0) == 65535);
  CHECK(vote.foreground(0) == 65535);
  CHECK_THROWS_AS(vote.add_view(A, &fg), vcar::Error);
  CHECK_NOTHROW(vote.add_view(A, nullptr));  // no evidence counts nothing
}

TEST_CASE("chunked voting (whole chunks decided per view) equals the per-mean brute force") {
  // Many means in a small cube seen from a ring at 160 x 120 with disc masks: most chunks fall
  // wholly inside a disc, outside it or outside the image, the rest straddle an edge.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(-0.6f, 0.6f);
  std::vector<Eigen::Vector3f> mus(20000);
  for (auto& m : mus) m = {U(rng), U(rng), U(rng)};
  mus[17] = {NAN, 0, 0};  // a non-finite mean: never visible
  const auto scene = scene_of(mus);
  std::vector<Camera> cams;
  std::vector<Mask> discs;
  for (int j = 0; j < 12; ++j) {
    const float a = 6.2831853f * j / 12;
    const Eigen::Vector3f eye(1.6f * std::cos(a), 0.4f * std::sin(2.f * a), 1.6f * std::sin(a));  // some inside the cube's reach
    cams.push_back(Camera::look_at(eye, Eigen::Vector3f(0.1f * j / 12, 0, 0), {0, -1, 0}, {160, 120, 110, 110, 80, 60},
                                   "ring" + std::to_string(j)));
    discs.push_back(disc_mask(160, 120, 70.f + 2 * j, 55.f, 25.f + 3 * j));
  }
  cams.push_back(Camera::look_at({0, 0, 0.3f}, {0, 0, 2}, {0, -1, 0}, {160, 120, 110, 110, 80, 60}, "inside"));  // straddles z = 0
  discs.push_back(disc_mask(160, 120, 80, 60, 40));
  std::vector<const Mask*> ptrs;
  for (const Mask& m : discs) ptrs.push_back(&m);
  std::vector<int> V, F;
  brute_counts(scene, cams, ptrs, V, F);
  for (int threads : {1, 2}) {
    vcar::set_num_threads(threads);
    vcar::VisibilityVoting vote(scene);
    for (std::size_t j = 0; j < cams.size(); ++j) vote.add_view(cams[j], ptrs[j]);
    int mismatches = 0;
    for (std::size_t i = 0; i < scene.size(); ++i) mismatches += (vote.visible(i) != V[i]) + (vote.foreground(i) != F[i]);
    INFO("threads " << threads);
    CHECK(mismatches == 0);
  }
}

TEST_CASE("remove_view takes a view's votes back: the counters equal a vote without it") {
  std::mt19937 rng(5);
  const auto scene = random_scene(5000, 9);
  const auto cams = ring_cameras(7);
  const std::vector<Mask> masks = random_masks(cams, rng);
  vcar::VisibilityVoting vote(scene);
  for (std::size_t j = 0; j < cams.size(); ++j) vote.add_view(cams[j], &masks[j]);
  vote.remove_view(cams[2], &masks[2]);
  vote.remove_view(cams[5], &masks[5]);
  vote.remove_view(cams[5], nullptr);  // no evidence: nothing taken back
  CHECK(vote.views() == 5);
  std::vector<const Mask*> kept;
  for (std::size_t j = 0; j < cams.size(); ++j) kept.push_back(j == 2 || j == 5 ? nullptr : &masks[j]);
  std::vector<int> V, F;
  brute_counts(scene, cams, kept, V, F);
  int mismatches = 0;
  for (std::size_t i = 0; i < scene.size(); ++i) mismatches += (vote.visible(i) != V[i]) + (vote.foreground(i) != F[i]);
  CHECK(mismatches == 0);
  vcar::VisibilityVoting empty(scene);
  CHECK_THROWS_AS(empty.remove_view(cams[0], &masks[0]), vcar::Error);
}
