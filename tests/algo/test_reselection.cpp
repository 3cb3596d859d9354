#include <catch2/catch.hpp>

#include <random>

#include "vcar/algo/reselection.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/synth/mask_ops.hpp"

#include "point_scene.hpp"

using vcar::Camera;
using vcar::Mask;

namespace {

// A blob of small Gaussians at the origin and a second one beside it, ring cameras, masks of
// the first blob's disc (one per camera).
struct Fixture {
  vcar::GaussianScene scene;
  std::vector<Camera> cams;
  std::vector<Mask> masks;
};

Fixture fixture(int n_cams = 10) {
  Fixture f;
  std::mt19937 rng(6);
  std::normal_distribution<float> N(0.f, 0.12f);
  const int n = 3000;
  f.scene.resize(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f c = i < n / 2 ? Eigen::Vector3f(0, 0, 0) : Eigen::Vector3f(0.9f, 0, 0);
    f.scene.set(i, c + Eigen::Vector3f(N(rng), N(rng), N(rng)), Eigen::Vector3f::Constant(std::log(0.02f)),
                {1, 0, 0, 0}, 2.f);
  }
  for (int j = 0; j < n_cams; ++j) {
    const float a = 6.2831853f * j / n_cams;
    const Camera c = Camera::look_at({3.f * std::cos(a), 0.5f, 3.f * std::sin(a)}, {0.45f, 0, 0}, {0, -1, 0},
                                     {120, 90, 110, 110, 60, 45}, "cam" + std::to_string(j));
    f.cams.push_back(c);
    Mask m(120, 90, 1, 0);  // the first blob's disc: radius 0.3 around the origin
    const Eigen::Vector3f t = c.to_camera(Eigen::Vector3f::Zero());
    const float u = c.fx * t.x() / t.z() + c.cx, v = c.fy * t.y() / t.z() + c.cy, r = c.fx * 0.3f / t.z();
    for (int y = 0; y < 90; ++y)
      for (int x = 0; x < 120; ++x) m(x, y) = (x + 0.5f - u) * (x + 0.5f - u) + (y + 0.5f - v) * (y + 0.5f - v) < r * r ? 255 : 0;
    f.masks.push_back(m);
  }
  return f;
}

vcar::VcarParams paper_no_sss() {
  vcar::VcarParams p = vcar::VcarParams::nvos();
  p.enable_sss = false;
  return p;
}

template <vcar::Renderer R>
vcar::SegmentationResult segment_with(const Fixture& f, const std::vector<const Mask*>& masks, const vcar::VcarParams& p,
                                      R& r) {
  auto s = vcar::make_segmenter([&](const vcar::FrameSequence& fr, const vcar::Prompt&) {
    std::vector<std::optional<Mask>> out(fr.size());
    for (std::size_t k = 0; k < fr.size(); ++k)
      if (masks[k]) out[k] = *masks[k];  // reference view 0: frame k is view k
    return out;
  });
  return vcar::segment(f.scene, f.cams, vcar::Prompt{}, r, s, p);
}
vcar::SegmentationResult segment_with(const Fixture& f, const std::vector<const Mask*>& masks, const vcar::VcarParams& p) {
  auto r = vcar::make_renderer([](const vcar::RenderRequest& q) {
    vcar::RenderOutput o;
    o.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    return o;
  });
  return segment_with(f, masks, p, r);
}

}  // namespace

TEST_CASE("Reselection equals vcar::segment with the same masks and SSS off, after any edits") {
  const Fixture f = fixture();
  const vcar::VcarParams p = paper_no_sss();
  vcar::Reselection r(f.scene, f.cams, p);
  std::vector<const Mask*> held(f.cams.size(), nullptr);
  for (std::size_t j = 0; j < f.cams.size(); j += 2) {  // half the masks
    r.set_mask(j, &f.masks[j]);
    held[j] = &f.masks[j];
  }
  CHECK(r.masks() == 5);
  auto same = [&](const vcar::SegmentationResult& a, const vcar::SegmentationResult& b) {
    CHECK(a.indices == b.indices);
    CHECK(a.scores == b.scores);
    CHECK(a.log_scale == b.log_scale);
    CHECK(a.diagnostics.abr_compressed == b.diagnostics.abr_compressed);
  };
  same(r.select(), segment_with(f, held, p));
  // One more mask, one replaced by its neighbour's (a wrong mask), one cleared.
  r.set_mask(1, &f.masks[1]);
  held[1] = &f.masks[1];
  r.set_mask(4, &f.masks[7]);
  held[4] = &f.masks[7];
  r.set_mask(6, nullptr);
  held[6] = nullptr;
  CHECK(r.masks() == 5);
  const auto edited = r.select();
  same(edited, segment_with(f, held, p));
  CHECK(edited.diagnostics.masks_missing == 5);
  // Every mask set: the first blob's Gaussians are selected, the second blob's are not.
  for (std::size_t j = 0; j < f.cams.size(); ++j) {
    r.set_mask(j, &f.masks[j]);
    held[j] = &f.masks[j];
  }
  const auto all = r.select();
  same(all, segment_with(f, held, p));
  std::size_t first = 0;
  for (vcar::Index i : all.indices) first += i < 1500;
  CHECK(first > 1200);
  CHECK(all.indices.size() - first < 50);
}

TEST_CASE("Reselection reports the view-completeness gap that SSS would fill, and refuses what it cannot do") {
  Fixture f = fixture(3);
  f.cams.resize(2);  // two nearby views: a large gap
  vcar::VcarParams p = vcar::VcarParams::nvos();
  vcar::Reselection r(f.scene, f.cams, p);
  r.set_mask(0, &f.masks[0]);
  r.set_mask(1, &f.masks[1]);
  const auto res = r.select();
  CHECK(res.diagnostics.max_gap_deg > p.Delta_th_deg);
  CHECK(!res.diagnostics.sss_triggered);
  CHECK(res.diagnostics.note.find("SSS") != std::string::npos);

  CHECK_THROWS_AS(vcar::Reselection(f.scene, f.cams, vcar::VcarParams::robust()), vcar::Error);  // needs a renderer
  auto no_depth = vcar::make_renderer([](const vcar::RenderRequest& q) {
    vcar::RenderOutput o;
    o.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    return o;
  });
  CHECK_THROWS_AS(vcar::Reselection(f.scene, f.cams, no_depth), vcar::Error);  // the default reads depth
  CHECK_THROWS_AS(vcar::Reselection(f.scene, {}, p), vcar::Error);
  CHECK_THROWS_AS(r.set_mask(2, &f.masks[0]), vcar::Error);         // view out of range
  const Mask small(10, 10, 1, 0);
  CHECK_THROWS_AS(r.set_mask(0, &small), vcar::Error);  // wrong size
  CHECK_THROWS_AS(r.select(5), vcar::Error);
  vcar::Reselection none(f.scene, f.cams, p);
  CHECK(none.select().indices.empty());
  CHECK(!none.select().diagnostics.note.empty());
}

TEST_CASE("Reselection's incremental ABR equals vcar::segment over a random sequence of edits") {
  const Fixture f = fixture(12);
  const vcar::VcarParams p = paper_no_sss();
  vcar::Reselection r(f.scene, f.cams, p);
  std::vector<const Mask*> held(f.cams.size(), nullptr);
  for (std::size_t j = 0; j < f.cams.size(); ++j) {
    r.set_mask(j, &f.masks[j]);
    held[j] = &f.masks[j];
  }
  CHECK(!r.last_stats().abr_incremental);
  (void)r.select();
  CHECK(!r.last_stats().abr_incremental);  // nothing to start from
  std::mt19937 rng(9);
  std::uniform_int_distribution<std::size_t> view(0, f.cams.size() - 1);
  std::size_t incremental = 0, fresh = 0, stale = 0;
  for (int step = 0; step < 12; ++step) {
    const int edits = 1 + step % 3;
    for (int e = 0; e < edits; ++e) {
      const std::size_t j = view(rng), other = view(rng);
      // a wrong mask (another view's), the right one back, or none
      const Mask* m = (step + e) % 4 == 3 ? nullptr : (step + e) % 2 ? &f.masks[other] : &f.masks[j];
      r.set_mask(j, m);
      held[j] = m;
    }
    const auto got = r.select();
    const auto want = segment_with(f, held, p);
    CHECK(got.indices == want.indices);
    CHECK(got.log_scale == want.log_scale);
    CHECK(got.diagnostics.abr_compressed == want.diagnostics.abr_compressed);
    const vcar::ReselectionStats& s = r.last_stats();
    CHECK(s.views_changed <= static_cast<std::size_t>(edits));
    if (s.abr_incremental) {
      ++incremental;
      CHECK(s.carried + s.fresh == got.indices.size());
    }
    fresh += s.fresh;
    stale += s.stale;
  }
  CHECK(incremental >= 8);  // the sequence exercises the incremental path
  CHECK(fresh > 0);
  CHECK(stale > 0);
}

TEST_CASE("Reselection with the default preset equals vcar::segment with the same masks and SSS off") {
  // The default's coarse round reads renders (Eq. R3, R11-R12) and weighs views (R13): the
  // renderer's alpha and depth are kept, each mask is edited (R11, R12) when set, and select()
  // votes again. One mask dilated by 4 px (R11 erodes it), one eroded by 3 px (R12 may grow it).
  const Fixture f = fixture();
  vcar::VcarParams p = vcar::VcarParams::robust();
  p.enable_sss = false;
  vcar::cpu::TiledRenderer renderer;
  vcar::Reselection r(f.scene, f.cams, renderer, p);
  const Mask dilated = vcar::synth::dilate_erode(f.masks[2], 4), eroded = vcar::synth::dilate_erode(f.masks[5], -3);
  std::vector<const Mask*> held(f.cams.size(), nullptr);
  for (std::size_t j = 0; j < f.cams.size(); ++j) held[j] = j == 2 ? &dilated : j == 5 ? &eroded : &f.masks[j];
  for (std::size_t j = 0; j < f.cams.size(); ++j) r.set_mask(j, held[j]);
  auto same = [&](const vcar::SegmentationResult& a, const vcar::SegmentationResult& b) {
    CHECK(a.indices == b.indices);
    CHECK(a.scores == b.scores);
    CHECK(a.log_scale == b.log_scale);
    CHECK(a.diagnostics.overshoot_eroded == b.diagnostics.overshoot_eroded);
    CHECK(a.diagnostics.masks_grown == b.diagnostics.masks_grown);
    CHECK(a.diagnostics.abr_compressed == b.diagnostics.abr_compressed);
  };
  const vcar::SegmentationResult all = r.select();
  same(all, segment_with(f, held, p, renderer));
  CHECK(all.diagnostics.overshoot_eroded >= 1);  // the dilated mask
  std::size_t first = 0;
  for (vcar::Index i : all.indices) first += i < 1500;
  CHECK(first > 1200);
  CHECK(all.indices.size() - first < 50);
  // Edits: a mask cleared, one replaced, the dilated one restored; another reference view.
  r.set_mask(7, nullptr);
  held[7] = nullptr;
  r.set_mask(2, &f.masks[2]);
  held[2] = &f.masks[2];
  r.set_mask(4, &f.masks[3]);
  held[4] = &f.masks[3];
  same(r.select(), segment_with(f, held, p, renderer));
  CHECK(r.last_stats().abr_incremental);  // 3 of 9 views changed: ABR carried its state
  CHECK(r.masks() == 9);
  // The default preset is VcarParams::robust(): the same as passing it.
  vcar::Reselection d(f.scene, f.cams, renderer);
  vcar::Reselection e(f.scene, f.cams, renderer, vcar::VcarParams::robust());
  for (std::size_t j = 0; j < f.cams.size(); ++j) d.set_mask(j, held[j]), e.set_mask(j, held[j]);
  CHECK(d.select().indices == e.select().indices);
}
