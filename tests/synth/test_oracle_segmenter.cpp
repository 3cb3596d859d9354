#include <catch2/catch.hpp>

#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"

using namespace vcar::synth;

static_assert(vcar::Segmenter<OracleSegmenter>);

namespace {
// A sphere (target, id 1) beside a box (neighbour, id 2), both in front of the camera.
World two_objects() {
  World w;
  Primitive s;
  s.type = PrimitiveType::sphere;
  s.params = {0.4f, 0, 0};
  s.object_id = 1;
  w.primitives.push_back(s);
  Primitive b;
  b.type = PrimitiveType::box;
  b.params = {0.3f, 0.3f, 0.3f};
  b.t = {0.7f, 0.f, 0.f};
  b.object_id = 2;
  w.primitives.push_back(b);
  w.target_id = 1;
  w.neighbour_id = 2;
  return w;
}
vcar::Camera front(const std::string& name = "train_000", float dx = 0.f) {
  return vcar::Camera::look_at({dx, -3, 0}, {dx, 0, 0}, {0, 0, 1}, make_intrinsics(320, 240), name);
}
std::vector<vcar::Camera> many(int n) {
  std::vector<vcar::Camera> c;
  for (int k = 0; k < n; ++k) {  // small images: the count matters, not the pixels
    c.push_back(front("v" + std::to_string(k), 0.001f * k));
    c.back().set_intrinsics(make_intrinsics(64, 48));
  }
  return c;
}
vcar::FrameSequence frames_of(const std::vector<vcar::Camera>& cams) {
  vcar::FrameSequence f;
  f.cameras = cams;
  f.image = [](std::size_t) -> vcar::ImageRGB8 { throw std::runtime_error("the oracle must not render"); };
  return f;
}
double radius(const vcar::Mask& m) { return std::sqrt(count(m) / M_PI); }
}  // namespace

TEST_CASE("the perfect oracle answers the visible ground truth without rendering, deterministically") {
  const World w = two_objects();
  OracleSegmenter oracle(w);
  const auto cams = many(3);
  const auto a = vcar::segment_all(oracle, frames_of(cams), {});
  const auto b = vcar::segment_all(oracle, frames_of(cams), {});
  for (std::size_t k = 0; k < cams.size(); ++k) {
    REQUIRE(a[k]);
    CHECK(a[k]->data == visible_mask(w, cams[k], 1).data);
    CHECK(a[k]->data == b[k]->data);
  }
}

TEST_CASE("dilation / erosion by k px grows / shrinks the target's disc by k +- 1") {
  World w = two_objects();
  w.primitives.pop_back();  // the sphere alone: a disc
  const auto cam = front();
  const double r0 = radius(visible_mask(w, cam, 1));
  for (int k : {2, 5, -4}) {
    OracleParams p;
    p.dilate_px = k;
    OracleSegmenter oracle(w, p);
    CHECK(radius(*oracle.mask(cam, 0)) == Approx(r0 + k).margin(1.0));
  }
}

TEST_CASE("drop probability p over many frames") {
  const World w = two_objects();
  OracleParams p;
  p.p_drop = 0.3;
  p.seed = 5;
  OracleSegmenter oracle(w, p);
  const auto cams = many(400);
  int dropped = 0;
  // Mask-free check of the drop decision: the sink gets nullptr for dropped frames.
  oracle.segment(frames_of(cams), {}, [&](std::size_t, const vcar::Mask* m) { dropped += m == nullptr; });
  CHECK(dropped / 400.0 == Approx(0.3).margin(0.07));  // ~4 binomial sd
}

TEST_CASE("neighbour swap returns the neighbour's mask; probability p") {
  const World w = two_objects();
  OracleParams p;
  p.p_swap = 1.0;
  auto cam = front();
  CHECK(OracleSegmenter(w, p).mask(cam, 0)->data == visible_mask(w, cam, 2).data);
  p.p_swap = 0.5;
  OracleSegmenter half(w, p);
  cam.set_intrinsics(make_intrinsics(64, 48));  // small images: the count matters
  const vcar::Mask target = visible_mask(w, cam, 1), nb = visible_mask(w, cam, 2);
  int swapped = 0, n = 200;
  for (int k = 0; k < n; ++k) {
    const auto m = half.mask(cam, static_cast<std::size_t>(k));
    REQUIRE((m->data == target.data || m->data == nb.data));
    swapped += m->data == nb.data;
  }
  CHECK(swapped / double(n) == Approx(0.5).margin(0.15));
}

TEST_CASE("jitter shifts by at most j px; blobs add discs of radius r") {
  World w = two_objects();
  const auto cam = front();
  const vcar::Mask base = visible_mask(w, cam, 1);
  OracleParams p;
  p.jitter_px = 3;
  OracleSegmenter jit(w, p);
  int moved = 0;
  for (std::size_t k = 0; k < 20; ++k) {
    const vcar::Mask m = *jit.mask(cam, k);
    bool found = false;
    for (int dy = -3; dy <= 3 && !found; ++dy)
      for (int dx = -3; dx <= 3 && !found; ++dx)
        if (shift(base, dx, dy).data == m.data) { found = true; moved += dx != 0 || dy != 0; }
    CHECK(found);
  }
  CHECK(moved > 10);
  OracleParams q;
  q.n_blobs = 3;
  q.blob_radius_px = 5.f;
  OracleSegmenter blobs(w, q);
  for (std::size_t k = 0; k < 10; ++k) {
    const vcar::Mask m = *blobs.mask(cam, k);
    std::size_t added = 0, removed = 0;
    for (std::size_t i = 0; i < m.data.size(); ++i) { added += m.data[i] && !base.data[i]; removed += !m.data[i] && base.data[i]; }
    CHECK(removed == 0);
    CHECK(added <= 3 * 100);  // 3 discs of ~ pi 25 = 79 px each, fewer where they overlap the target or the border
  }
}

TEST_CASE("mode: sss_ frames get the silhouette (occluder not drawn), others the visible mask") {
  World w = two_objects();
  w.primitives[1].t = {0.2f, -1.f, 0.f};  // the box now occludes part of the sphere
  OracleSegmenter oracle(w);
  const auto train = front("train_000"), sss = front("sss_003");
  CHECK(oracle.mask(train, 0)->data == visible_mask(w, train, 1).data);
  CHECK(oracle.mask(sss, 0)->data == silhouette_mask(w, sss, 1).data);
  CHECK(count(silhouette_mask(w, sss, 1)) > count(visible_mask(w, sss, 1)) + 100);
  OracleParams p;
  p.mode = OracleMode::visible;
  CHECK(OracleSegmenter(w, p).mask(sss, 0)->data == visible_mask(w, sss, 1).data);
  p.p_drop = 2.0;
  CHECK_THROWS_AS(OracleSegmenter(w, p), vcar::Error);
}

TEST_CASE("target_id picks another object than the world's target (several objects per run)") {
  const World w = two_objects();
  OracleParams p;
  p.target_id = 2;
  const auto cam = front();
  const auto nb = OracleSegmenter(w, p).mask(cam, 0);
  REQUIRE(nb);
  CHECK(nb->data == visible_mask(w, cam, 2).data);
  CHECK(nb->data != visible_mask(w, cam, 1).data);
  p.target_id = -1;  // default: the world's target
  CHECK(OracleSegmenter(w, p).mask(cam, 0)->data == visible_mask(w, cam, 1).data);
}

TEST_CASE("FrameCasts: oracles of one frame share its cast where they see it whole, with the answers of mask()") {
  World w = two_objects();
  w.primitives[1].t = {0.2f, -1.f, 0.f};  // the box occludes part of the sphere
  OracleParams pt, pn;
  pt.target_id = 1;
  pn.target_id = 2;
  pn.dilate_px = 2;  // failure models apply per oracle after the shared cast
  pn.jitter_px = 3;
  const OracleSegmenter target(w, pt), neighbour(w, pn);
  for (const auto& cam : {front("train_000"), front("sss_001")}) {  // visible: one cast; silhouettes: one each
    INFO(cam.name);
    for (bool subset : {false, true}) {
      OracleSegmenter::FrameCasts casts;
      const auto a = target.mask(cam, 4, subset, casts), b = neighbour.mask(cam, 4, subset, casts);
      REQUIRE(a);
      REQUIRE(b);
      CHECK(a->data == target.mask(cam, 4, subset)->data);
      CHECK(b->data == neighbour.mask(cam, 4, subset)->data);
      CHECK(a->data != b->data);
    }
  }
  // A cache of another frame is not reused for this one.
  OracleSegmenter::FrameCasts casts;
  const auto near = front("train_000"), moved = front("train_001", 0.3f);
  (void)target.mask(near, 0, false, casts);
  CHECK(target.mask(moved, 1, false, casts)->data == visible_mask(w, moved, 1).data);
}
