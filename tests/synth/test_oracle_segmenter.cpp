#include <catch2/catch.hpp>

#include <set>

#include "vcar/backends/cpu/tiled_renderer.hpp"
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

// ---- the rendered (honest) mode and the SAM-like failures -------------------------------------

namespace {
// A generated world of Gaussians and a camera on the neighbour's side (+x of the target), so the
// neighbour stands in front of part of the target.
struct GaussianWorld {
  World w;
  vcar::Camera cam;
};
const GaussianWorld& gaussian_world() {
  static const GaussianWorld g = [] {
    WorldParams p;
    p.seed = 3;
    p.n_gaussians = 30000;
    GaussianWorld out{generate_world(p), {}};
    const auto [c, r] = out.w.bounds(out.w.target_id);
    out.cam = vcar::Camera::look_at(c + Eigen::Vector3f(4.f * r, -1.5f * r, 1.5f * r), c, {0, 0, 1},
                                    make_intrinsics(160, 120), "train_000");
    return out;
  }();
  return g;
}
OracleParams rendered_params() {
  OracleParams p;
  p.mode = OracleMode::rendered;
  return p;
}
std::size_t overlap(const vcar::Mask& a, const vcar::Mask& b) {
  std::size_t n = 0;
  for (std::size_t k = 0; k < a.data.size(); ++k) n += a.data[k] && b.data[k];
  return n;
}
}  // namespace

TEST_CASE("rendered mode: the target's dominant pixels of what the frame draws; needs a renderer and the drawn set") {
  const auto& [w, cam] = gaussian_world();
  vcar::cpu::TiledRenderer renderer;
  const OracleSegmenter oracle(w, rendered_params(), renderer);
  const RenderedLabels labels(w);
  OracleSegmenter::FrameCasts casts;
  const auto whole = oracle.mask(cam, 0, false, casts, nullptr);
  REQUIRE(whole);
  CHECK(whole->data == mask_of(labels.label_image(cam, nullptr, renderer), w.target_id).data);
  const vcar::Mask vis = visible_mask(w, cam, w.target_id);
  // The render shows what the ray cast sees, up to a band along the contour (79% of the visible
  // mask here: a small, mostly hidden target at 160 x 120; test_rendered_labels measures the band).
  CHECK(overlap(*whole, vis) > count(vis) * 3 / 4);
  CHECK_THROWS_AS(OracleSegmenter(w, rendered_params()), vcar::Error);  // no renderer
  OracleSegmenter::FrameCasts c2;
  CHECK_THROWS_AS(oracle.mask(cam, 0, true, c2, nullptr), vcar::Error);  // a subset, but which?
}

TEST_CASE("rendered mode: a subset without the target gives an empty mask; a foreign object's Gaussians stay out; dropped pieces are missing") {
  const auto& [w, cam] = gaussian_world();
  vcar::cpu::TiledRenderer renderer;
  const OracleSegmenter honest(w, rendered_params(), renderer);
  const OracleSegmenter old(w, {}, renderer);  // by_name: the silhouette for subsets
  const std::vector<vcar::Index> target = w.gaussians_of(w.target_id), nb = w.gaussians_of(w.neighbour_id);
  std::vector<vcar::Index> both = target;
  both.insert(both.end(), nb.begin(), nb.end());
  OracleSegmenter::FrameCasts casts;
  CHECK(count(*honest.mask(cam, 0, true, casts, &nb)) == 0);
  const vcar::Mask alone = *honest.mask(cam, 0, true, casts, &target);
  const vcar::Mask with_nb = *honest.mask(cam, 0, true, casts, &both);
  const vcar::Mask neighbour_shows = mask_of(RenderedLabels(w).label_image(cam, &both, renderer), w.neighbour_id);
  const vcar::Mask sil = *old.mask(cam, 0, true);
  CHECK(count(neighbour_shows) > 1000);
  CHECK(overlap(with_nb, neighbour_shows) == 0);          // the foreign pieces stay out
  CHECK(overlap(sil, neighbour_shows) > 1000);             // where the old oracle answered the silhouette
  CHECK(count(with_nb) < count(alone) / 2);                // the neighbour hides much of the target here
  CHECK(overlap(alone, silhouette_mask(w, cam, w.target_id)) > count(alone) * 8 / 10);  // 85%: the Gaussians' spread
  // Half of the target dropped (its upper half kept): the mask lacks the rest.
  const float cz = w.bounds(w.target_id).first.z();
  std::vector<vcar::Index> upper;
  for (vcar::Index i : target)
    if (w.scene.mean[2][i] > cz) upper.push_back(i);
  const vcar::Mask part = *honest.mask(cam, 0, true, casts, &upper);
  CHECK(count(part) > count(alone) / 4);
  CHECK(count(part) < count(alone) * 3 / 4);
  CHECK(overlap(part, alone) > count(part) * 9 / 10);
}

TEST_CASE("rendered mode reads FrameSequence::drawn frame by frame") {
  const auto& [w, cam] = gaussian_world();
  vcar::cpu::TiledRenderer renderer;
  OracleSegmenter oracle(w, rendered_params(), renderer);
  const std::vector<vcar::Index> nb = w.gaussians_of(w.neighbour_id);
  const std::vector<vcar::Camera> cams(4, cam);
  vcar::FrameSequence f = frames_of(cams);
  f.subset = true;
  f.drawn = [&](std::size_t k) -> const std::vector<vcar::Index>* { return k % 2 ? &nb : nullptr; };
  const auto masks = vcar::segment_all(oracle, f, {});
  for (std::size_t k = 0; k < 4; ++k) {
    REQUIRE(masks[k]);
    INFO("frame " << k);
    CHECK((count(*masks[k]) == 0) == (k % 2 == 1));  // odd frames draw only the neighbour
  }
  f.drawn = nullptr;  // a subset that does not say which Gaussians: refused
  CHECK_THROWS_AS(vcar::segment_all(oracle, f, {}), vcar::Error);
}

TEST_CASE("oracle SAM failures: wrong object, part, leak, drift, each as it says; deterministic") {
  const auto& [w, cam] = gaussian_world();
  vcar::cpu::TiledRenderer renderer;
  const IdImage labels = RenderedLabels(w).label_image(cam, nullptr, renderer);
  const vcar::Mask base = mask_of(labels, w.target_id);
  const std::vector<vcar::Camera> cams(12, cam);

  OracleParams wrong = rendered_params();
  wrong.sam.p_wrong = 1.0;
  OracleSegmenter o_wrong(w, wrong, renderer);
  std::set<int> chosen;
  for (std::size_t k = 0; k < cams.size(); ++k) {
    const vcar::Mask m = *o_wrong.mask(cam, k, false);
    int found = -2;
    for (int id : {-1, 0, 2, 3, 4, 5})
      if (count(mask_of(labels, id)) > 0 && m.data == mask_of(labels, id).data) found = id;
    CHECK(found >= 0);  // another object's mask, never the target's or nothing
    chosen.insert(found);
  }
  CHECK(chosen.size() >= 2);  // not only the fixed neighbour

  OracleParams part = rendered_params();
  part.sam.p_part = 1.0;
  OracleSegmenter o_part(w, part, renderer);
  for (std::size_t k = 0; k < 4; ++k) {
    const vcar::Mask m = *o_part.mask(cam, k, false);
    CHECK(overlap(m, base) == count(m));  // a subset
    CHECK(count(m) < count(base));        // strict
    CHECK(count(m) > count(base) / 5);
  }

  OracleParams leak = rendered_params();
  leak.sam.p_leak = 1.0;
  leak.sam.leak_px = 5;
  OracleSegmenter o_leak(w, leak, renderer);
  const std::vector<float> d2 = squared_distance(base, true);
  for (std::size_t k = 0; k < 4; ++k) {
    const vcar::Mask m = *o_leak.mask(cam, k, false);
    CHECK(overlap(m, base) == count(base));  // nothing of the target lost
    std::set<int> added;
    for (std::size_t i = 0; i < m.data.size(); ++i)
      if (m.data[i] && !base.data[i]) {
        added.insert(labels.id[i]);
        CHECK(d2[i] <= 25.f);
      }
    CHECK(added.size() == 1);  // one other label, not the target, not nothing
    CHECK(*added.begin() >= 0);
    CHECK(*added.begin() != w.target_id);
  }

  // Drift through segment(): frame k of a sequence of one camera moves by about k drift_px.
  OracleParams drift = rendered_params();
  drift.sam.drift_px = 2.f;
  OracleSegmenter o_drift(w, drift, renderer);
  const auto seq = vcar::segment_all(o_drift, frames_of(cams), {});
  CHECK(seq[0]->data == base.data);  // the prompted frame is exact
  auto centre = [](const vcar::Mask& m) {
    Eigen::Vector2d s(0, 0);
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x)
        if (m(x, y)) s += Eigen::Vector2d(x, y);
    return Eigen::Vector2d(s / static_cast<double>(count(m)));
  };
  for (std::size_t k = 1; k < 6; ++k)
    CHECK((centre(*seq[k]) - centre(base)).norm() == Approx(2.0 * k).margin(1.0));  // whole pixels

  // Determinism: the same seed gives the same masks; another seed other masks; the older
  // models' draws do not move when a SAM failure is switched on (streams of their own).
  OracleParams all = rendered_params();
  all.sam = {0.3, 0.3, 0.5, 6, 0.5f};
  all.p_drop = 0.3;
  OracleSegmenter a(w, all, renderer), b(w, all, renderer);
  all.seed = 2;
  OracleSegmenter c(w, all, renderer);
  const auto ma = vcar::segment_all(a, frames_of(cams), {}), mb = vcar::segment_all(b, frames_of(cams), {}),
             mc = vcar::segment_all(c, frames_of(cams), {});
  bool differs = false;
  for (std::size_t k = 0; k < cams.size(); ++k) {
    REQUIRE(ma[k].has_value() == mb[k].has_value());
    if (ma[k]) CHECK(ma[k]->data == mb[k]->data);
    differs = differs || ma[k].has_value() != mc[k].has_value() || (ma[k] && ma[k]->data != mc[k]->data);
  }
  CHECK(differs);
  OracleParams drop_only = rendered_params();
  drop_only.p_drop = 0.3;
  OracleSegmenter d(w, drop_only, renderer);
  const auto md = vcar::segment_all(d, frames_of(cams), {});
  std::size_t dropped = 0;
  for (std::size_t k = 0; k < cams.size(); ++k) {
    CHECK(md[k].has_value() == ma[k].has_value());
    dropped += !md[k];
  }
  CHECK(dropped > 0);
}

TEST_CASE("wrong object in visible mode: another object's visible mask") {
  const World w = two_objects();
  OracleParams p;
  p.sam.p_wrong = 1.0;
  const auto cam = front();
  const auto m = OracleSegmenter(w, p).mask(cam, 0);
  REQUIRE(m);
  CHECK(m->data == visible_mask(w, cam, 2).data);  // the only other object in view
  p.sam.p_wrong = 2.0;
  CHECK_THROWS_AS(OracleSegmenter(w, p), vcar::Error);
}
