#pragma once
// SAM-like failures of the synthetic oracle (synth/oracle_segmenter.hpp): the mistakes a
// promptable image or video segmenter makes on renders, as seeded operations on a frame's mask
// and on the labels the frame shows (an IdImage: per pixel the object it shows, -1 none). Each
// is off by default and decided per frame from the oracle's seed, the frame and its camera.
//
//  - wrong (p_wrong): the frame gets the mask of another object it shows instead of the
//    target's: any label >= 0 other than the target (the neighbour, a distractor, the floor)
//    covering at least 0.1% of the frame, uniformly. A frame that shows no other label keeps its
//    mask (what a segmenter cannot see it cannot pick).
//  - part (p_part): the mask is cut by a line through its centroid at a uniform angle; the
//    pixels strictly on one side stay. Why a line and not the largest piece after an erosion:
//    SAM's part answers (one of its multimask outputs: a handle, a top, one half) drop a whole
//    side of the object, while an erosion keeps the bulk of a compact object and takes the thin
//    parts first. The cut keeps about half the mask and one contiguous side; for any non-empty
//    mask it is a strict subset (the pixels' offsets from their centroid sum to zero, so some
//    lie on the dropped side or on the line).
//  - leak (p_leak): a background piece touching the object is included: one label other than
//    the target (>= 0), chosen uniformly among those with a pixel within 2 px of the mask (a seam
//    of one unlabelled edge pixel does not separate two touching surfaces), and the pixels of
//    that label within leak_px of the mask that are 4-connected, through such pixels, to one of
//    those within 2 px. So the floor under the object, or a touching neighbour, bleeds into the
//    mask up to leak_px from its contour; nothing else is added.
//  - drift (drift_px): frame k's mask is shifted by round(k drift_px) px along one direction
//    drawn once from the seed (the same for every frame): a video segmenter propagating from
//    the prompted frame 0 (exact) drifts away from the object as the sequence goes on.
// Applied in this order (wrong, part, leak, drift), before the oracle's older failure models.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <numbers>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/random.hpp"

namespace vcar::synth {

struct SamFailures {
  double p_wrong = 0.0;  // probability of another object's mask
  double p_part = 0.0;   // probability of a part (half-plane cut through the centroid)
  double p_leak = 0.0;   // probability of a touching background piece included
  int leak_px = 8;       // how far from the mask a leak reaches (px)
  float drift_px = 0.f;  // frame k shifted by k drift_px px

  bool any() const { return p_wrong > 0.0 || p_part > 0.0 || p_leak > 0.0 || drift_px != 0.f; }
  bool needs_labels() const { return p_wrong > 0.0 || p_leak > 0.0; }
  void validate() const {
    auto prob = [](double p, const char* name) {
      if (!(p >= 0.0 && p <= 1.0)) throw Error("must be in [0, 1]", name);
    };
    prob(p_wrong, "OracleParams.p_wrong");
    prob(p_part, "OracleParams.p_part");
    prob(p_leak, "OracleParams.p_leak");
    if (leak_px < 1) throw Error("must be >= 1", "OracleParams.leak_px");
    if (!(drift_px >= 0.f) || !std::isfinite(drift_px)) throw Error("must be >= 0", "OracleParams.drift_px");
  }
};

namespace sam {

// Another label (>= 0, not `target`) covering at least 0.1% of the frame, uniformly; `target`
// when there is none.
inline int other_label(const IdImage& labels, int target, Rng& rng) {
  std::map<int, std::size_t> n;
  for (int id : labels.id)
    if (id >= 0 && id != target) ++n[id];
  const double min_px = 0.001 * static_cast<double>(labels.id.size());
  std::vector<int> ok;
  for (const auto& [id, c] : n)
    if (static_cast<double>(c) >= min_px) ok.push_back(id);
  if (ok.empty()) return target;
  return ok[static_cast<std::size_t>(rng.uniform_int(0, static_cast<int>(ok.size()) - 1))];
}

// The pixels of m strictly on the side (cos a, sin a) of the line through its centroid.
inline Mask cut_through_centroid(const Mask& m, float angle) {
  double sx = 0, sy = 0;
  std::size_t n = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      if (m(x, y)) { sx += x + 0.5; sy += y + 0.5; ++n; }
  Mask out(m.width, m.height, 1);
  if (n == 0) return out;
  const double cx = sx / n, cy = sy / n, nx = std::cos(angle), ny = std::sin(angle);
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      if (m(x, y) && nx * (x + 0.5 - cx) + ny * (y + 0.5 - cy) > 0.0) out(x, y) = 255;
  return out;
}

// Adds to m the piece of one other label touching it (see the top of this file); the label
// picked, or -1 when nothing touches.
inline int leak(Mask& m, const IdImage& labels, int target, int reach_px, Rng& rng) {
  const std::vector<float> d2 = squared_distance(m, true);
  const float reach2 = static_cast<float>(reach_px) * static_cast<float>(reach_px);
  auto candidate = [&](std::size_t k, int id) {
    return m.data[k] == 0 && labels.id[k] == id && d2[k] <= reach2;
  };
  std::map<int, bool> touching;
  for (std::size_t k = 0; k < d2.size(); ++k) {
    const int id = labels.id[k];
    if (id >= 0 && id != target && m.data[k] == 0 && d2[k] <= 4.f) touching[id] = true;
  }
  if (touching.empty()) return -1;
  std::vector<int> ids;
  for (const auto& [id, t] : touching) ids.push_back(id);
  const int id = ids[static_cast<std::size_t>(rng.uniform_int(0, static_cast<int>(ids.size()) - 1))];
  std::vector<std::size_t> stack;
  std::vector<char> added(d2.size(), 0);
  for (std::size_t k = 0; k < d2.size(); ++k)
    if (candidate(k, id) && d2[k] <= 4.f) { added[k] = 1; stack.push_back(k); }
  const std::size_t W = static_cast<std::size_t>(m.width), H = static_cast<std::size_t>(m.height);
  while (!stack.empty()) {
    const std::size_t k = stack.back();
    stack.pop_back();
    const std::size_t x = k % W, y = k / W;
    const std::size_t nb[4] = {x > 0 ? k - 1 : k, x + 1 < W ? k + 1 : k, y > 0 ? k - W : k, y + 1 < H ? k + W : k};
    for (std::size_t j : nb)
      if (!added[j] && candidate(j, id)) { added[j] = 1; stack.push_back(j); }
  }
  for (std::size_t k = 0; k < d2.size(); ++k)
    if (added[k]) m.data[k] = 255;
  return id;
}

// The drift direction of an oracle with this seed (radians).
inline float drift_angle(std::uint64_t seed) {
  Rng rng(seed, 0xD81F7u);
  return rng.uniform(0.f, 2.f * std::numbers::pi_v<float>);
}

// Frame k's drift: shifted by round(k drift_px) px along `angle`.
inline Mask drift(const Mask& m, std::size_t k, float drift_px, float angle) {
  const double d = static_cast<double>(k) * drift_px;
  const int dx = static_cast<int>(std::lround(d * std::cos(angle))), dy = static_cast<int>(std::lround(d * std::sin(angle)));
  return dx == 0 && dy == 0 ? m : shift(m, dx, dy);
}

}  // namespace sam

}  // namespace vcar::synth
