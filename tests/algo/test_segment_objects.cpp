// vcar::segment_objects (algo/segment_objects.hpp) and the MultiSegmenter adapter EachObject
// (concepts/multi_segmenter.hpp): each object's result against vcar::segment's with the same
// masks, the conflict rule, and how EachObject orders and maps frames.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "vcar/algo/segment_objects.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"

namespace {

// Two balls of small Gaussians, centres (0,0,0) and (1.2,0,0), radius 0.3.
struct Balls {
  vcar::GaussianScene scene;
  Eigen::Vector3f centre[2] = {{0.f, 0.f, 0.f}, {1.2f, 0.f, 0.f}};
  static constexpr float radius = 0.3f;
};
Balls two_balls() {
  Balls b;
  const int per = 400;
  b.scene.resize(2 * per);
  std::mt19937 rng(11);
  std::normal_distribution<float> n01(0.f, 1.f);
  for (int i = 0; i < 2 * per; ++i) {
    Eigen::Vector3f p;
    do p = {n01(rng), n01(rng), n01(rng)}; while (p.norm() < 1e-3f);
    p = p.normalized() * Balls::radius * std::cbrt(std::uniform_real_distribution<float>(0, 1)(rng));
    b.scene.set(i, b.centre[i / per] + p, Eigen::Vector3f::Constant(std::log(0.02f)), {1, 0, 0, 0}, 2.f);
  }
  return b;
}

// A forward rig of 9 views looking +z at the pair.
std::vector<vcar::Camera> rig() {
  const vcar::Intrinsics k{160, 120, 120.f, 120.f, 80.f, 60.f};
  std::vector<vcar::Camera> cams;
  for (int i = 0; i < 9; ++i) {
    const float dx = 0.3f * static_cast<float>(i % 3 - 1), dy = 0.3f * static_cast<float>(i / 3 - 1);
    cams.push_back(vcar::Camera::look_at({0.6f + dx, dy, -4.f}, {0.6f + dx, dy, 0.f}, {0, -1, 0}, k, "v" + std::to_string(i)));
  }
  return cams;
}

// Ball `o`'s mask: the projected disc of its bounding sphere, enlarged by `grow` (world units).
vcar::Mask ball_mask(const vcar::Camera& c, const Eigen::Vector3f& centre, float grow) {
  vcar::Mask m(c.width, c.height, 1);
  const Eigen::Vector3f t = c.to_camera(centre);
  if (t.z() <= 0.f) return m;
  const float u = c.fx * t.x() / t.z() + c.cx, v = c.fy * t.y() / t.z() + c.cy, r = c.fx * (Balls::radius + grow) / t.z();
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x)
      if ((x + 0.5f - u) * (x + 0.5f - u) + (y + 0.5f - v) * (y + 0.5f - v) <= r * r) m(x, y) = 255;
  return m;
}

// A single-object segmenter answering one ball's disc in every frame but view v7, where it
// answers a part of it (a disc of half the radius: a SAM-like failure, so that view reliability,
// Eq. R13, weighs the views unequally).
struct BallSegmenter {
  Eigen::Vector3f centre;
  float grow = 0.08f;
  int calls = 0;
  void segment(const vcar::FrameSequence& f, const vcar::Prompt&, const vcar::MaskSink& sink) {
    ++calls;
    for (std::size_t k = 0; k < f.size(); ++k) {
      const bool part = f.cameras[k].name == "v7";
      const vcar::Mask m = ball_mask(f.cameras[k], centre, part ? -0.5f * Balls::radius : grow);
      sink(k, &m);
    }
  }
};
static_assert(vcar::Segmenter<BallSegmenter>);

}  // namespace

TEST_CASE("segment_objects: each object as its own vcar::segment run, in two segmenter calls") {
  const Balls b = two_balls();
  const auto cams = rig();
  vcar::cpu::TiledRenderer renderer;
  vcar::VcarParams reliability = vcar::VcarParams::nvos();
  reliability.reliability.enabled = true;  // R13 alone (the default has it too)
  vcar::VcarParams coarse_only = reliability;  // the final scores are then the coarse round's R13 vote
  coarse_only.enable_sss = false;
  for (const vcar::VcarParams& params : {vcar::VcarParams::nvos(), vcar::VcarParams::robust(), reliability, coarse_only}) {
    std::vector<BallSegmenter> per = {{b.centre[0]}, {b.centre[1]}};
    std::vector<vcar::ObjectPrompt> objects(2);
    objects[0].name = "left";
    objects[0].prompt.reference_view = 4;
    objects[1].name = "right";
    objects[1].prompt.reference_view = 2;
    vcar::EachObject<BallSegmenter> each(per);
    const vcar::MultiSegmentation m = vcar::segment_objects(b.scene, cams, objects, renderer, each, params);
    REQUIRE(m.objects.size() == 2);
    CHECK(m.segmenter_calls == (m.objects[0].diagnostics.sss_triggered ? 2u : 1u));
    CHECK(m.conflicts == 0);  // the discs do not overlap in any view
    for (int o = 0; o < 2; ++o) {
      BallSegmenter single{b.centre[o]};
      const vcar::SegmentationResult r = vcar::segment(b.scene, cams, objects[o].prompt, renderer, single, params);
      CHECK(m.objects[o].indices == r.indices);
      CHECK(m.objects[o].scores == r.scores);
      CHECK(m.objects[o].log_scale == r.log_scale);
      CHECK(!r.indices.empty());
    }
  }
}

TEST_CASE("resolve_conflicts: a Gaussian two objects select stays with the higher score, ties with the earlier") {
  std::vector<vcar::SegmentationResult> r(2);
  r[0].indices = {1, 2, 3};
  r[0].scores = {0.9f, 0.6f, 0.7f};
  r[1].indices = {2, 3, 4};
  r[1].scores = {0.8f, 0.7f, 1.0f};
  std::vector<std::size_t> lost;
  CHECK(vcar::resolve_conflicts(r, 5, lost) == 2);
  CHECK(r[0].indices == std::vector<vcar::Index>{1, 3});  // 3: a tie, the earlier object keeps it
  CHECK(r[1].indices == std::vector<vcar::Index>{2, 4});
  CHECK(r[1].scores == std::vector<float>{0.8f, 1.0f});
  CHECK(lost == std::vector<std::size_t>{1, 1});
}

TEST_CASE("EachObject: each request's frames, its prompt's frame first, masks sent back to the call's frames") {
  const auto cams = rig();
  struct Recorder {
    std::vector<std::string> seen;
    void segment(const vcar::FrameSequence& f, const vcar::Prompt& p, const vcar::MaskSink& sink) {
      CHECK(p.reference_view == 0);
      for (std::size_t k = 0; k < f.size(); ++k) {
        seen.push_back(f.cameras[k].name);
        vcar::Mask m(f.cameras[k].width, f.cameras[k].height, 1);
        sink(k, k % 2 ? nullptr : &m);
      }
    }
  };
  std::vector<Recorder> per(2);
  vcar::EachObject<Recorder> each(per);
  vcar::FrameSequence f;
  f.cameras = std::span<const vcar::Camera>(cams.data(), 5);
  std::vector<vcar::ObjectRequest> req(2);
  req[0].name = "a";
  req[0].prompt.reference_view = 2;  // every frame, its prompt on frame 2
  req[0].object = 1;
  req[1].name = "b";
  req[1].prompt.reference_view = 3;  // frames 1-3, its prompt on frame 3
  req[1].first_frame = 1;
  req[1].frames = 3;
  req[1].object = 0;
  std::map<std::pair<std::size_t, std::size_t>, bool> got;  // (frame, request) -> has a mask
  each.segment_objects(f, req, [&](std::size_t k, std::size_t q, const vcar::Mask* m) {
    CHECK(got.count({k, q}) == 0);
    got[{k, q}] = m != nullptr;
  });
  CHECK(per[1].seen == std::vector<std::string>{"v2", "v0", "v1", "v3", "v4"});
  CHECK(per[0].seen == std::vector<std::string>{"v3", "v1", "v2"});
  CHECK(got.size() == 8);
  CHECK(got.at({2, 0}));   // request 0's first call frame (a mask)
  CHECK(!got.at({0, 0}));  // its second (no mask)
  CHECK(got.at({3, 1}));
  CHECK(!got.at({1, 1}));
  CHECK(got.at({2, 1}));
  CHECK(got.count({0, 1}) == 0);
  vcar::ObjectRequest far;
  far.object = 2;
  CHECK_THROWS_AS(each.segment_objects(f, {far}, [](std::size_t, std::size_t, const vcar::Mask*) {}), vcar::Error);
}
