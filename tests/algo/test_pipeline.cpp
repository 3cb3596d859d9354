// The coarse-to-fine pipeline on small generated scenes with mock renderers and segmenters
// whose right answer is known by construction.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "vcar/algo/pipeline.hpp"
#include "vcar/synth/mask_ops.hpp"

namespace {

constexpr int kW = 160, kH = 120;

// Two blobs of small isotropic Gaussians: A (the target) around (0,0,0), B around (2,0,0).
struct TwoBlobs {
  vcar::GaussianScene scene;
  std::vector<vcar::Index> a, b;
  static constexpr float radius = 0.3f;
};

TwoBlobs two_blobs(int per_blob = 300, float log_s = std::log(0.02f)) {
  TwoBlobs t;
  t.scene.resize(2 * per_blob);
  std::mt19937 rng(3);
  std::normal_distribution<float> n01(0.f, 1.f);
  for (int i = 0; i < 2 * per_blob; ++i) {
    Eigen::Vector3f p;
    do p = {n01(rng), n01(rng), n01(rng)}; while (p.norm() < 1e-3f);
    p = p.normalized() * TwoBlobs::radius * std::cbrt(std::uniform_real_distribution<float>(0, 1)(rng));
    const bool in_a = i < per_blob;
    if (!in_a) p.x() += 2.f;
    t.scene.set(i, p, Eigen::Vector3f::Constant(log_s), {1, 0, 0, 0}, 2.f);
    (in_a ? t.a : t.b).push_back(static_cast<vcar::Index>(i));
  }
  return t;
}

vcar::Intrinsics intrinsics() { return {kW, kH, 120.f, 120.f, kW / 2.f, kH / 2.f}; }

// Forward-facing rig: cameras on a small patch at z = -4 looking +z (the back is never seen).
std::vector<vcar::Camera> forward_rig(int n = 9) {
  std::vector<vcar::Camera> cams;
  for (int k = 0; k < n; ++k) {
    const float dx = 0.3f * static_cast<float>(k % 3 - 1), dy = 0.3f * static_cast<float>(k / 3 - 1);
    cams.push_back(vcar::Camera::look_at({1.f + dx, dy, -4.f}, {1.f + dx, dy, 0.f}, {0, -1, 0},
                                         intrinsics(), "train_" + std::to_string(k)));
  }
  return cams;
}

// 360 rig: a ring of cameras around the origin (in the y = 0 plane, up = -y).
std::vector<vcar::Camera> orbit_rig(int n = 16) {
  std::vector<vcar::Camera> cams;
  for (int k = 0; k < n; ++k) {
    const float a = 2.f * static_cast<float>(M_PI) * static_cast<float>(k) / static_cast<float>(n);
    const float e = (k % 2 ? 0.6f : -0.6f);
    cams.push_back(vcar::Camera::look_at({3.f * std::cos(a), 3.f * std::sin(e), 3.f * std::sin(a)},
                                         {0, 0, 0}, {0, -1, 0}, intrinsics(), "orbit_" + std::to_string(k)));
  }
  return cams;
}

auto blank_renderer() {
  return vcar::make_renderer([](const vcar::RenderRequest& q) {
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    return out;
  });
}

// The mask of blob A: the projected disc of its bounding sphere (slightly enlarged).
vcar::Mask blob_a_mask(const vcar::Camera& c) {
  vcar::Mask m(c.width, c.height, 1);
  const Eigen::Vector3f t = c.to_camera({0, 0, 0});
  if (t.z() <= 0.f) return m;
  const float u = c.fx * t.x() / t.z() + c.cx, v = c.fy * t.y() / t.z() + c.cy;
  const float r = c.fx * (TwoBlobs::radius + 0.08f) / t.z();
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x)
      if ((x + 0.5f - u) * (x + 0.5f - u) + (y + 0.5f - v) * (y + 0.5f - v) <= r * r) m(x, y) = 255;
  return m;
}

// Renders blob A's disc at depth 4 over a wall at depth 4.5 (the whole scene), or over nothing
// (a subset: the fine round's renders of G_coarse): the occlusion edges of Eq. R11-R12.
auto disc_over_wall_renderer() {
  return vcar::make_renderer([](const vcar::RenderRequest& q) {
    vcar::RenderOutput out;
    const vcar::Mask disc = blob_a_mask(*q.camera);
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    out.depth = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    for (std::size_t k = 0; k < disc.data.size(); ++k) {
      out.alpha.data[k] = disc.data[k] || !q.subset ? 1.f : 0.f;
      out.depth.data[k] = disc.data[k] ? 4.f : (q.subset ? 0.f : 4.5f);
    }
    return out;
  });
}

auto disc_segmenter(int* rounds = nullptr) {
  return vcar::make_segmenter([rounds](const vcar::FrameSequence& f, const vcar::Prompt&) {
    if (rounds) ++*rounds;
    std::vector<std::optional<vcar::Mask>> masks;
    for (const auto& c : f.cameras) masks.emplace_back(blob_a_mask(c));
    return masks;
  });
}

bool same_set(std::vector<vcar::Index> got, std::vector<vcar::Index> want) {
  std::sort(want.begin(), want.end());
  return got == want;
}

}  // namespace

TEST_CASE("pipeline selects blob A from a forward-facing rig and runs SSS") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  auto renderer = blank_renderer();
  int rounds = 0;
  auto seg = disc_segmenter(&rounds);
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  std::vector<std::string> stages;
  const auto r = vcar::segment(w.scene, cams, prompt, renderer, seg, vcar::VcarParams::nvos(),
                               [&](const vcar::Progress& p) {
                                 if (p.views == 0) stages.emplace_back(p.stage);
                                 return true;
                               });
  const auto& d = r.diagnostics;
  CHECK(d.max_gap_deg > 90.0);          // the back of the object is never seen
  CHECK(d.sss_triggered);
  CHECK(d.sampled_cameras.size() == 32);  // S1 x S2
  CHECK(rounds == 2);
  CHECK(same_set(r.indices, w.a));
  CHECK(r.scores.size() == r.indices.size());
  CHECK(r.log_scale[0].size() == r.indices.size());
  CHECK(d.n_coarse == w.a.size());
  CHECK(std::is_sorted(r.indices.begin(), r.indices.end()));
  CHECK(stages.front() == "coarse");
  CHECK(std::find(stages.begin(), stages.end(), "sss") != stages.end());
  // The sphere centre is blob A's centre, its radius eta times the reference distance.
  CHECK(d.sphere.c.norm() < 0.05f);
  CHECK(d.sphere.r == Approx(1.2f * (cams[4].position() - d.sphere.c).norm()).epsilon(1e-4));
}

TEST_CASE("pipeline skips SSS when the training views surround the object") {
  auto w = two_blobs();
  const auto cams = orbit_rig();
  auto renderer = blank_renderer();
  int rounds = 0;
  auto seg = disc_segmenter(&rounds);
  const auto r = vcar::segment(w.scene, cams, {}, renderer, seg, vcar::VcarParams::nvos());
  CHECK(r.diagnostics.max_gap_deg < 90.0);
  CHECK_FALSE(r.diagnostics.sss_triggered);
  CHECK(rounds == 1);
  CHECK(same_set(r.indices, w.a));
}

TEST_CASE("pipeline stages can be switched off") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  auto renderer = blank_renderer();
  int rounds = 0;
  auto seg = disc_segmenter(&rounds);
  auto p = vcar::VcarParams::nvos();
  p.enable_sss = false;
  p.enable_abr = false;
  const auto r = vcar::segment(w.scene, cams, {}, renderer, seg, p);
  CHECK(rounds == 1);
  CHECK_FALSE(r.diagnostics.sss_triggered);
  CHECK(r.diagnostics.abr_flagged == 0);
  for (std::size_t k = 0; k < r.indices.size(); ++k)  // scales untouched without ABR
    CHECK(r.log_scale[0][k] == w.scene.log_scale[0][r.indices[k]]);
}

TEST_CASE("with SSS disabled the sphere and view completeness are not computed") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  auto renderer = blank_renderer();
  auto seg = disc_segmenter();
  auto p = vcar::VcarParams::nvos();
  p.enable_sss = false;
  std::vector<std::string> stages;
  const auto r = vcar::segment(w.scene, cams, {}, renderer, seg, p, [&](const vcar::Progress& q) {
    if (q.views == 0) stages.emplace_back(q.stage);
    return true;
  });
  CHECK(std::find(stages.begin(), stages.end(), "view_completeness") == stages.end());
  CHECK(r.diagnostics.max_gap_deg == 0.0);
  CHECK(r.diagnostics.valid_cameras == 0);
  CHECK(same_set(r.indices, w.a));
}

TEST_CASE("reference_code: the fine round re-votes the training views even when SSS does not trigger") {
  auto w = two_blobs();
  const auto cams = orbit_rig();
  auto renderer = blank_renderer();
  int rounds = 0;
  auto seg = disc_segmenter(&rounds);
  auto p = vcar::VcarParams::reference_code();
  p.min_frame_content = 0.f;  // the blank renderer draws nothing
  const auto r = vcar::segment(w.scene, cams, {}, renderer, seg, p);
  CHECK_FALSE(r.diagnostics.sss_triggered);
  CHECK(rounds == 2);
  CHECK(same_set(r.indices, w.a));
  p.force_fine_round = false;
  rounds = 0;
  (void)vcar::segment(w.scene, cams, {}, renderer, seg, p);
  CHECK(rounds == 1);
}

TEST_CASE("reference_code's empty-frame filter drops near-empty training frames of the fine round, never the prompt frame") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  auto renderer = blank_renderer();  // alpha 0 everywhere: every frame is empty
  std::vector<std::size_t> frames_per_round;
  auto seg = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    frames_per_round.push_back(f.size());
    std::vector<std::optional<vcar::Mask>> masks;
    for (const auto& c : f.cameras) masks.emplace_back(blob_a_mask(c));
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  const auto r = vcar::segment(w.scene, cams, prompt, renderer, seg, vcar::VcarParams::reference_code());
  REQUIRE(frames_per_round.size() == 2);
  CHECK(frames_per_round[0] == cams.size());
  CHECK(frames_per_round[1] == 1);  // only the prompt frame survives
  CHECK(r.diagnostics.sss_triggered);
}

TEST_CASE("robust preset: fine-round frames render a subset (FrameSequence::subset) and depth comes with them") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  int depth_requests = 0, renders = 0;
  auto renderer = vcar::make_renderer([&](const vcar::RenderRequest& q) {
    ++renders;
    depth_requests += q.want_depth;
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    if (q.want_depth) out.depth = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    return out;
  });
  std::vector<bool> subset_flags;
  auto seg = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    subset_flags.push_back(f.subset);
    std::vector<std::optional<vcar::Mask>> masks;
    for (std::size_t k = 0; k < f.size(); ++k) {
      (void)f.image(k);  // a segmenter that looks at the pixels
      masks.emplace_back(blob_a_mask(f.cameras[k]));
    }
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  const auto r = vcar::segment(w.scene, cams, prompt, renderer, seg);  // default: VcarParams::robust()
  CHECK(subset_flags == std::vector<bool>{false, true});
  CHECK(same_set(r.indices, w.a));
  // Every frame rendered once for the segmenter, with depth (the occlusion test of both rounds);
  // the lambda answers all frames before voting, so the occlusion test renders depth again.
  CHECK(depth_requests == renders);
  CHECK(renders >= static_cast<int>(cams.size() + cams.size() + 32));
}

TEST_CASE("a fine round without any mask keeps G_coarse and ABR on the coarse masks (a mask folder's fine round)") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  auto renderer = disc_over_wall_renderer();
  // Answers the whole scene's frames (the coarse round) and no frame of a subset (the fine round),
  // as a folder of the captures' masks would once it answers "no mask" for renders of G_coarse.
  auto seg = vcar::make_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> masks(f.size());
    if (!f.subset)
      for (std::size_t k = 0; k < f.size(); ++k) masks[k] = blob_a_mask(f.cameras[k]);
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  for (auto p : {vcar::VcarParams::robust(), vcar::VcarParams::nvos()}) {
    const auto r = vcar::segment(w.scene, cams, prompt, renderer, seg, p);
    p.enable_sss = false;
    p.force_fine_round = false;
    const auto coarse_only = vcar::segment(w.scene, cams, prompt, renderer, seg, p);
    CHECK(r.diagnostics.sss_triggered);
    CHECK(r.diagnostics.masks_missing == cams.size() + r.diagnostics.sampled_cameras.size());
    CHECK(same_set(r.indices, w.a));
    CHECK(r.indices == coarse_only.indices);
    CHECK(r.scores == coarse_only.scores);
    CHECK(r.log_scale == coarse_only.log_scale);  // ABR read the coarse round's masks
    CHECK(r.diagnostics.n_fine == r.diagnostics.n_coarse);
    CHECK(r.diagnostics.tau_fine_applied == 0.f);
    CHECK(r.diagnostics.note.find("no frame of the fine round had a mask") != std::string::npos);
    CHECK(coarse_only.diagnostics.note.empty());
  }
}

TEST_CASE("RenderNeed: a fine round that reads alpha only (Eq. R6 alone) keeps its renders and asks no depth") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  int depth_requests = 0, renders = 0;
  auto renderer = vcar::make_renderer([&](const vcar::RenderRequest& q) {
    ++renders;
    depth_requests += q.want_depth;
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    if (q.want_depth) out.depth = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    return out;
  });
  // Each frame answered as soon as it is drawn: the round's kept render is the one voted.
  auto seg = vcar::make_streaming_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&, const vcar::MaskSink& sink) {
    for (std::size_t k = 0; k < f.size(); ++k) {
      (void)f.image(k);
      const vcar::Mask m = blob_a_mask(f.cameras[k]);
      sink(k, &m);
    }
  });
  auto p = vcar::VcarParams::robust();  // R6 on; every mechanism that reads depth off
  p.evidence.occlusion = false;
  p.snap.enabled = false;
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  const auto r = vcar::segment(w.scene, cams, prompt, renderer, seg, p);
  CHECK(same_set(r.indices, w.a));
  CHECK(r.diagnostics.sss_triggered);
  CHECK(depth_requests == 0);
  CHECK(renders == static_cast<int>(cams.size() + cams.size() + 32));  // no frame rendered twice
}

TEST_CASE("FrameSequence::drawn: unset in the coarse round (the whole scene), the rendered subset in the fine round") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  std::vector<std::vector<vcar::Index>> rendered;  // the subset of each render (empty: the whole scene)
  std::vector<bool> whole;
  auto renderer = vcar::make_renderer([&](const vcar::RenderRequest& q) {
    whole.push_back(q.subset == nullptr);
    rendered.push_back(q.subset ? *q.subset : std::vector<vcar::Index>{});
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    if (q.want_depth) out.depth = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    return out;
  });
  int rounds = 0, fine_frames = 0;
  auto seg = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    ++rounds;
    CHECK(static_cast<bool>(f.drawn) == f.subset);
    std::vector<std::optional<vcar::Mask>> masks;
    for (std::size_t k = 0; k < f.size(); ++k) {
      (void)f.image(k);
      if (f.drawn) {  // names exactly what frame k's render drew
        const std::vector<vcar::Index>* d = f.drawn(k);
        REQUIRE(d != nullptr);
        REQUIRE_FALSE(whole.back());
        CHECK(*d == rendered.back());
        ++fine_frames;
      } else {
        CHECK(whole.back());
      }
      masks.emplace_back(blob_a_mask(f.cameras[k]));
    }
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  const auto r = vcar::segment(w.scene, cams, prompt, renderer, seg);
  CHECK(rounds == 2);
  CHECK(fine_frames > 0);
  CHECK(same_set(r.indices, w.a));
}

TEST_CASE("Eq. R8: ABR reads the training masks widened by their undershoot only when the fine vote is split") {
  auto w = two_blobs();
  const auto cams = forward_rig();
  // Renders of a subset (the fine round) show blob A's disc, depth far behind every Gaussian (no
  // occlusion); renders of the whole scene are blank.
  auto renderer = vcar::make_renderer([&](const vcar::RenderRequest& q) {
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 0.f);
    if (q.subset) {
      const vcar::Mask disc = blob_a_mask(*q.camera);
      for (std::size_t k = 0; k < disc.data.size(); ++k) out.alpha.data[k] = disc.data[k] ? 1.f : 0.f;
    }
    if (q.want_depth) {
      out.depth = out.alpha;
      for (float& d : out.depth.data) d *= 100.f;
    }
    return out;
  });
  // The coarse round gets blob A's disc eroded by `erode_coarse` px; the fine round the disc
  // eroded by `erode` px.
  int erode = 0, erode_coarse = 0;
  auto eroded_by = [](const vcar::Mask& m, int px) {
    vcar::Mask e = m;
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x)
        for (int d = 1; d <= px && e(x, y); ++d)
          if (x - d < 0 || x + d >= m.width || y - d < 0 || y + d >= m.height || !m(x - d, y) || !m(x + d, y) ||
              !m(x, y - d) || !m(x, y + d))
            e(x, y) = 0;
    return e;
  };
  auto seg = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> masks;
    for (const auto& c : f.cameras) masks.emplace_back(eroded_by(blob_a_mask(c), f.subset ? erode : erode_coarse));
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  auto p = vcar::VcarParams::robust();
  p.force_fine_round = true;
  p.phi_s_deg = vcar::VcarParams::nvos().phi_s_deg;  // the rim's ratios below are those of the paper's spiral
  auto run = [&](int px) {
    erode = px;
    return vcar::segment(w.scene, cams, prompt, renderer, seg, p).diagnostics;
  };
  // Masks 5 px inside the render: blob A's rim falls outside them in every view, the vote splits.
  // Eq. R14: the round's threshold is the valley of its ratios (a bin centre at or above
  // tau_coarse); here the rim's ratios spread below tau_fine with nothing else in G_coarse, so
  // the valley lies below it, and R7 finds the vote split against it.
  const auto bin_centre = [&](float t) { return std::abs(t * 20.f - 0.5f - std::round(t * 20.f - 0.5f)) < 1e-4f; };
  const vcar::Diagnostics eroded = run(5);
  INFO("R14 on eroded masks: " << eroded.tau_fine_applied);
  REQUIRE(bin_centre(eroded.tau_fine_applied));
  CHECK(eroded.tau_fine_applied >= p.tau_coarse);
  CHECK(eroded.tau_fine_applied < p.tau_fine);
  // R14 off: R7 weighs tau_strict against tau_fine (0.8), and against 0.8 these masks' vote is
  // decisive (the rim sits below 0.8): the strict threshold, and fewer of the object kept.
  p.valley.enabled = false;
  const vcar::Diagnostics no_valley = run(5);
  CHECK(no_valley.tau_fine_applied == p.strict.tau);
  CHECK(eroded.n_fine > no_valley.n_fine);
  p.valley.enabled = true;
  // Exact masks: the vote is decisive against its valley, R7's strict threshold.
  CHECK(run(0).tau_fine_applied == p.strict.tau);
  // R7 off: the eroded masks' vote keeps its valley; the exact masks measure no undershoot
  // (R14's first gate: their median e_j is 0) and their vote is a spike at 1 (not spread: the
  // second gate), so their round keeps tau_fine.
  p.strict.tau = 0.f;
  CHECK(run(5).tau_fine_applied == eroded.tau_fine_applied);
  CHECK(run(0).tau_fine_applied == p.tau_fine);
  // Without R6a (R6 off) the first gate never opens (every e_j reads 0); the second reads the
  // vote itself: without R6's band the eroded masks leave fewer than half of G_coarse in the top
  // bin, the vote is spread, and its valley is the threshold.
  p.undershoot.band = 0.f;
  const float no_band = run(5).tau_fine_applied;
  REQUIRE(bin_centre(no_band));
  CHECK(no_band >= p.tau_coarse);
  CHECK(no_band != p.tau_fine);
  // Neither gate: R14 off reads tau_fine.
  p.valley.enabled = false;
  CHECK(run(5).tau_fine_applied == p.tau_fine);
  p = vcar::VcarParams::robust();
  p.force_fine_round = true;
  p.phi_s_deg = vcar::VcarParams::nvos().phi_s_deg;
  CHECK(eroded.abr_masks_widened == cams.size());  // every training view has an undershooting mask
  // Exact masks: a decisive vote, ABR reads them as they are.
  const vcar::Diagnostics exact = run(0);
  REQUIRE(exact.tau_fine_applied == p.strict.tau);
  CHECK(exact.abr_masks_widened == 0);
  // Eq. R6c: the vote without R6 splits on eroded masks, so R6 shapes the result; on exact
  // masks it is decisive and is the result.
  CHECK(eroded.undershoot_applied);
  CHECK(!exact.undershoot_applied);
  // Switched off (R6 and R8 are one correction), or in the paper's preset: never.
  p.undershoot.band = 0.f;
  CHECK(run(5).abr_masks_widened == 0);
  p = vcar::VcarParams::nvos();
  p.force_fine_round = true;
  CHECK(run(5).abr_masks_widened == 0);

  // The paper's presets never apply R6.
  erode_coarse = 2;
  p = vcar::VcarParams::robust();
  p.force_fine_round = true;
  p.snap.enabled = false;  // R12 would grow the eroded coarse masks back
  auto full = [&](int px, const vcar::VcarParams& q) {
    erode = px;
    return vcar::segment(w.scene, cams, prompt, renderer, seg, q);
  };
  auto nv = vcar::VcarParams::nvos();
  nv.force_fine_round = true;
  CHECK(!full(5, nv).diagnostics.undershoot_applied);

  // Eq. R6c: a decisive vote without R6 gives the selection of a run without R6, bit for bit;
  // a split one is R6's.
  vcar::VcarParams no_r6 = p;
  no_r6.undershoot.band = 0.f;
  const vcar::SegmentationResult g0 = full(0, p), n0 = full(0, no_r6);
  CHECK(g0.indices == n0.indices);
  CHECK(g0.scores == n0.scores);
  CHECK(!g0.diagnostics.undershoot_applied);
  const vcar::SegmentationResult g5 = full(5, p);
  CHECK(g5.diagnostics.undershoot_applied);

  // Eq. R8 reads the Gaussians' own footprints after a split vote, whatever abr_lowpass says.
  vcar::VcarParams own = p, own_no_r6 = no_r6;
  own.abr_lowpass = false;
  own_no_r6.abr_lowpass = false;
  const vcar::SegmentationResult s_own = full(5, own);
  REQUIRE(p.abr_lowpass);
  CHECK(g5.log_scale == s_own.log_scale);
  CHECK(full(5, no_r6).log_scale != full(5, own_no_r6).log_scale);  // the low-pass matters here
}

TEST_CASE("Eq. R11: masks that overshoot the render's occlusion edges are eroded; exact ones are not") {
  // Blob A (radius 0.3, its masks' disc 0.38) with a ring of background Gaussians around its
  // waist, radius 0.40-0.46 in the plane z = 0 (what touches an object: the table it stands on),
  // in front of a wall at z = 0.5. Forward rig at z = -4.
  auto w = two_blobs();
  std::vector<vcar::Index> shell;
  {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> r01(0.f, 1.f);
    const std::size_t base = w.scene.size();
    w.scene.resize(base + 200);
    for (std::size_t i = 0; i < 200; ++i) {
      const float a = 6.2831853f * r01(rng), r = 0.40f + 0.06f * r01(rng);
      w.scene.set(base + i, {r * std::cos(a), r * std::sin(a), 0.f}, Eigen::Vector3f::Constant(std::log(0.02f)),
                  {1, 0, 0, 0}, 2.f);
      shell.push_back(static_cast<vcar::Index>(base + i));
    }
  }
  const auto cams = forward_rig();
  auto renderer = disc_over_wall_renderer();
  int dilate_px = 5;  // the segmenter's disc (11.4 px at depth 4), dilated: the ring (12-14 px) inside
  bool fine_only = false;  // dilate only the fine round's masks (renders of a subset)
  auto seg = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> masks;
    for (const auto& c : f.cameras)
      masks.emplace_back(vcar::synth::dilate_erode(blob_a_mask(c), fine_only && !f.subset ? 0 : dilate_px));
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  auto run = [&](const vcar::VcarParams& p) { return vcar::segment(w.scene, cams, prompt, renderer, seg, p); };
  auto holds_any = [](const std::vector<vcar::Index>& got, const std::vector<vcar::Index>& some) {
    return std::any_of(some.begin(), some.end(),
                       [&](vcar::Index i) { return std::binary_search(got.begin(), got.end(), i); });
  };
  auto holds_all = [](const std::vector<vcar::Index>& got, const std::vector<vcar::Index>& all) {
    return std::all_of(all.begin(), all.end(),
                       [&](vcar::Index i) { return std::binary_search(got.begin(), got.end(), i); });
  };
  const vcar::VcarParams robust = vcar::VcarParams::robust();
  vcar::VcarParams off = robust;
  off.snap.enabled = false;  // R11 (and R12, which does not act on dilated masks) off
  const vcar::SegmentationResult on_r = run(robust), off_r = run(off);
  // Without R11 the dilated masks keep the shell; with it every mask is eroded (both rounds),
  // the shell goes and blob A stays whole.
  CHECK(holds_any(off_r.indices, shell));
  CHECK(off_r.diagnostics.overshoot_eroded == 0);
  CHECK(on_r.diagnostics.overshoot_eroded >= cams.size());
  CHECK(!holds_any(on_r.indices, shell));
  CHECK(holds_all(on_r.indices, w.a));
  // Exact masks: their contour is the render's edge (o_j = 0 < o_min), nothing eroded.
  dilate_px = 0;
  const vcar::SegmentationResult exact = run(robust);
  CHECK(exact.diagnostics.overshoot_eroded == 0);
  CHECK(exact.indices == run(off).indices);
  // The paper's presets never erode.
  dilate_px = 5;
  CHECK(run(vcar::VcarParams::nvos()).diagnostics.overshoot_eroded == 0);
  // The fine round applies R11 only after the coarse round found overshooting masks: with exact
  // coarse masks its dilated masks are voted as they are (they add nothing outside G_coarse).
  fine_only = true;
  const vcar::SegmentationResult fine_dilated = run(robust);
  CHECK(fine_dilated.diagnostics.overshoot_eroded == 0);
  CHECK(fine_dilated.indices == run(off).indices);
}

TEST_CASE("Eq. R12: coarse-round masks that stop short of the render's occlusion edges grow to them") {
  // Blob A (radius 0.3: centres up to 9 px from its centre at depth 4) seen through masks of its
  // disc (11.4 px) eroded by 4 px in the coarse round (the fine round's are exact): its rim lies
  // outside every training mask, and G_coarse lacks it. The render of the whole
  // scene shows the disc at depth 4 in front of a wall at 4.5, so the gap between each mask and
  // the disc's edge is depth-continuous and the mask grows back to the disc.
  auto w = two_blobs();
  const auto cams = forward_rig();
  auto renderer = disc_over_wall_renderer();
  auto seg = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> masks;
    for (const auto& c : f.cameras) masks.emplace_back(vcar::synth::dilate_erode(blob_a_mask(c), f.subset ? 0 : -4));
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 4;
  auto run = [&](const vcar::VcarParams& p) { return vcar::segment(w.scene, cams, prompt, renderer, seg, p); };
  auto count_in = [](const std::vector<vcar::Index>& got, const std::vector<vcar::Index>& some) {
    return std::count_if(some.begin(), some.end(),
                         [&](vcar::Index i) { return std::binary_search(got.begin(), got.end(), i); });
  };
  const vcar::VcarParams robust = vcar::VcarParams::robust();
  vcar::VcarParams off = robust;
  off.snap.enabled = false;  // R12 (and R11, which does not act on eroded masks) off
  const vcar::SegmentationResult on_r = run(robust), off_r = run(off);
  CHECK(off_r.diagnostics.masks_grown == 0);
  CHECK(on_r.diagnostics.masks_grown == cams.size());  // every training mask, in the coarse round
  // Without R12 blob A loses its rim; with it G_coarse and the result hold blob A whole, and
  // blob B stays out.
  CHECK(on_r.diagnostics.n_coarse > off_r.diagnostics.n_coarse);
  CHECK(count_in(off_r.indices, w.a) < static_cast<std::ptrdiff_t>(w.a.size()));
  CHECK(count_in(on_r.indices, w.a) == static_cast<std::ptrdiff_t>(w.a.size()));
  CHECK(count_in(on_r.indices, w.b) == 0);
  // The paper's presets never grow a mask.
  CHECK(run(vcar::VcarParams::nvos()).diagnostics.masks_grown == 0);
}

TEST_CASE("pipeline: bad input and edge cases") {
  auto w = two_blobs(100);
  const auto cams = forward_rig();
  auto renderer = blank_renderer();
  auto seg = disc_segmenter();
  const auto P = vcar::VcarParams::nvos();

  SECTION("empty scene is an error") {
    vcar::GaussianScene empty;
    CHECK_THROWS_AS(vcar::segment(empty, cams, {}, renderer, seg, P), vcar::Error);
  }
  SECTION("no cameras, or a reference view out of range") {
    CHECK_THROWS_AS(vcar::segment(w.scene, {}, {}, renderer, seg, P), vcar::Error);
    vcar::Prompt pr;
    pr.reference_view = cams.size();
    CHECK_THROWS_WITH(vcar::segment(w.scene, cams, pr, renderer, seg, P), Catch::Contains("reference view"));
  }
  SECTION("all masks empty: a clear empty result, not a crash") {
    auto none = vcar::make_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&) {
      std::vector<std::optional<vcar::Mask>> m;
      for (auto& c : f.cameras) m.emplace_back(vcar::Mask(c.width, c.height, 1));
      return m;
    });
    const auto r = vcar::segment(w.scene, cams, {}, renderer, none, P);
    CHECK(r.indices.empty());
    CHECK_FALSE(r.diagnostics.note.empty());
  }
  SECTION("no training view sees the object") {
    std::vector<vcar::Camera> away;
    for (auto c : cams) {  // turned around: everything is behind them
      away.push_back(vcar::Camera::look_at(c.position(), c.position() - Eigen::Vector3f(0, 0, 1), {0, -1, 0}, intrinsics(), c.name));
    }
    const auto r = vcar::segment(w.scene, away, {}, renderer, seg, P);
    CHECK(r.indices.empty());
    CHECK(r.diagnostics.n_coarse == 0);
  }
  SECTION("all masks full: every Gaussian seen by a view is selected") {
    auto full = vcar::make_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&) {
      std::vector<std::optional<vcar::Mask>> m;
      for (auto& c : f.cameras) m.emplace_back(vcar::Mask(c.width, c.height, 1, 255));
      return m;
    });
    auto p = P;
    p.enable_sss = false;
    const auto r = vcar::segment(w.scene, cams, {}, renderer, full, p);
    CHECK(r.indices.size() == w.scene.size());
  }
  SECTION("a single training view") {
    const std::vector<vcar::Camera> one{cams[4]};
    const auto r = vcar::segment(w.scene, one, {}, renderer, seg, P);
    CHECK(same_set(r.indices, w.a));
    CHECK(r.diagnostics.max_gap_deg > 90.0);
  }
  SECTION("duplicate cameras change nothing") {
    std::vector<vcar::Camera> dup = cams;
    dup.insert(dup.end(), cams.begin(), cams.end());
    auto p = P;
    p.enable_sss = false;
    const auto r1 = vcar::segment(w.scene, cams, {}, renderer, seg, p);
    const auto r2 = vcar::segment(w.scene, dup, {}, renderer, seg, p);
    CHECK(r1.indices == r2.indices);
  }
  SECTION("reference camera at the object centre") {
    std::vector<vcar::Camera> c2 = cams;
    c2[0] = vcar::Camera::look_at({0, 0, 0}, {0, 0, 1}, {0, -1, 0}, intrinsics(), "inside");
    vcar::Prompt pr;
    pr.reference_view = 0;
    auto p = P;
    p.force_sss = true;
    // Either a documented fallback radius or a clear error, never a crash or a NaN.
    try {
      const auto r = vcar::segment(w.scene, c2, pr, renderer, seg, p);
      CHECK(std::isfinite(r.diagnostics.sphere.r));
      CHECK(r.diagnostics.sphere.r > 0.f);
    } catch (const vcar::Error& e) {
      CHECK(std::string(e.what()).size() > 0);
    }
  }
  SECTION("Gaussians with zero or huge scales") {
    auto z = two_blobs(100, -30.f);
    for (vcar::Index i : z.a) if (i % 7 == 0) for (int d = 0; d < 3; ++d) z.scene.log_scale[d][i] = 8.f;
    const auto r = vcar::segment(z.scene, cams, {}, renderer, seg, P);
    for (auto& col : r.log_scale) for (float v : col) CHECK(std::isfinite(v));
    CHECK(r.indices.size() >= z.a.size() * 8 / 10);
  }
  SECTION("a segmenter that throws is named by round") {
    auto bad = vcar::make_segmenter([](const vcar::FrameSequence&, const vcar::Prompt&) -> std::vector<std::optional<vcar::Mask>> {
      throw std::runtime_error("model weights missing");
    });
    CHECK_THROWS_WITH(vcar::segment(w.scene, cams, {}, renderer, bad, P),
                      Catch::Contains("coarse round") && Catch::Contains("model weights missing"));
  }
  SECTION("a wrong-size mask names the view") {
    auto small = vcar::make_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&) {
      std::vector<std::optional<vcar::Mask>> m(f.size());
      m[1] = vcar::Mask(10, 10, 1);
      return m;
    });
    CHECK_THROWS_WITH(vcar::segment(w.scene, cams, {}, renderer, small, P),
                      Catch::Contains("train_1") && Catch::Contains("10x10"));
  }
  SECTION("the progress callback cancels") {
    int calls = 0;
    CHECK_THROWS_AS(vcar::segment(w.scene, cams, {}, renderer, seg, P,
                                  [&](const vcar::Progress&) { return ++calls < 3; }),
                    vcar::Cancelled);
  }
}
