#pragma once
// Camera rigs around the target, as in the benchmarks the paper reports on: forward-facing
// (LLFF/NVOS: the back of the target is never seen), a 360-degree orbit (LERF-like), sparse
// (4-8 views) and hemisphere-only (one side of the target). Each rig returns the training
// cameras, the reference (prompt) view and held-out evaluation cameras that are not training
// views (NVOS protocol). The world's up vector is +z; cameras stay above the table.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/synth/random.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

struct Rig {
  std::string kind;            // "forward", "orbit", "sparse", "hemisphere"
  std::vector<Camera> train;   // named train_000, train_001, ...
  std::size_t reference = 0;   // index into train of the prompt view
  std::vector<Camera> eval;    // named eval_000, ...; never among train
};

// Pinhole with a centred principal point and horizontal field of view `hfov_deg`.
inline Intrinsics make_intrinsics(int width, int height, float hfov_deg = 60.f) {
  const float f = 0.5f * static_cast<float>(width) / std::tan(0.5f * hfov_deg * std::numbers::pi_v<float> / 180.f);
  return {width, height, f, f, 0.5f * static_cast<float>(width), 0.5f * static_cast<float>(height)};
}

struct RigParams {
  Intrinsics intrinsics = make_intrinsics(320, 240);  // tests; demos use e.g. 960 x 720
  int n_train = 0;            // 0: the rig's default (forward 20, orbit 40, sparse 6, hemisphere 24)
  int n_eval = 0;             // 0: the rig's default (forward 5, others 8)
  float distance = 0.f;       // camera to target centre; 0: from `fill`
  float fill = 0.5f;          // with distance 0: the target's bounding sphere spans this share of the image height
  float elevation_deg = 25.f; // above the table plane (orbit, sparse, forward)
  std::uint64_t seed = 1;     // jitter of positions
};

namespace detail {
constexpr float deg = std::numbers::pi_v<float> / 180.f;

inline std::string view_name(const char* prefix, int k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%s_%03d", prefix, k);
  return buf;
}

inline float rig_distance(const World& w, const RigParams& p) {
  if (p.distance > 0.f) return p.distance;
  if (!(p.fill > 0.f)) throw Error("fill must be > 0", "RigParams.fill");
  const float r = w.bounds(w.target_id).second;
  return p.intrinsics.fy * r / (0.5f * p.fill * static_cast<float>(p.intrinsics.height));
}

// Unit direction from the target towards a camera at azimuth a (0 = the -y "front") and
// elevation e above the table.
inline Eigen::Vector3f direction(float azimuth, float elevation) {
  return {std::sin(azimuth) * std::cos(elevation), -std::cos(azimuth) * std::cos(elevation), std::sin(elevation)};
}

inline void check(const RigParams& p, int n_train, int n_eval) {
  if (p.intrinsics.width <= 0 || p.intrinsics.height <= 0 || !(p.intrinsics.fx > 0.f) || !(p.intrinsics.fy > 0.f))
    throw Error("intrinsics must have a positive size and focal length", "RigParams.intrinsics");
  if (n_train < 2) throw Error("need at least 2 training views", "RigParams.n_train");
  if (n_eval < 1) throw Error("need at least 1 evaluation view", "RigParams.n_eval");
}

// Cameras on a sphere around the target at the given (azimuth, elevation) pairs.
inline std::vector<Camera> ring(const World& w, const RigParams& p, const char* prefix,
                                const std::vector<std::pair<float, float>>& az_el) {
  const Eigen::Vector3f c = w.bounds(w.target_id).first;
  const float d = rig_distance(w, p);
  std::vector<Camera> out;
  for (std::size_t k = 0; k < az_el.size(); ++k)
    out.push_back(Camera::look_at(c + d * direction(az_el[k].first, az_el[k].second), c, w.up, p.intrinsics,
                                  view_name(prefix, static_cast<int>(k))));
  return out;
}
}  // namespace detail

// LLFF/NVOS-like: cameras on a small patch in front of the target (a jittered grid), all with
// the same orientation (parallel optical axes); evaluation cameras at other points of the patch.
inline Rig forward_facing_rig(const World& w, const RigParams& p = {}) {
  const int n_train = p.n_train > 0 ? p.n_train : 20, n_eval = p.n_eval > 0 ? p.n_eval : 5;
  detail::check(p, n_train, n_eval);
  const Eigen::Vector3f c = w.bounds(w.target_id).first;
  const float d = detail::rig_distance(w, p);
  const Eigen::Vector3f centre = c + d * detail::direction(0.f, p.elevation_deg * detail::deg);
  const Camera base = Camera::look_at(centre, c, w.up, p.intrinsics);
  const float half_w = 0.15f * d, half_h = 0.08f * d;  // the patch: 30% x 16% of the distance
  Rng rng(p.seed, 0xF0Du);
  auto at = [&](float a, float b, std::string name) {
    Camera cam = base;
    cam.name = std::move(name);
    const Eigen::Vector3f pos = centre + a * half_w * base.right() + b * half_h * base.up();
    cam.t_w = -(cam.R_w * pos);
    return cam;
  };
  Rig rig;
  rig.kind = "forward";
  const int cols = static_cast<int>(std::ceil(std::sqrt(1.6 * n_train))), rows = (n_train + cols - 1) / cols;
  float best = INFINITY;
  for (int k = 0; k < n_train; ++k) {
    const int i = k / cols, j = k % cols;
    const float a = cols > 1 ? -1.f + 2.f * j / (cols - 1) : 0.f, b = rows > 1 ? -1.f + 2.f * i / (rows - 1) : 0.f;
    const float ja = a + rng.uniform(-0.1f, 0.1f), jb = b + rng.uniform(-0.1f, 0.1f);
    rig.train.push_back(at(ja, jb, detail::view_name("train", k)));
    if (ja * ja + jb * jb < best) { best = ja * ja + jb * jb; rig.reference = static_cast<std::size_t>(k); }
  }
  for (int k = 0; k < n_eval; ++k)  // random points of the patch: never a training position
  {
    const float eb = rng.uniform(-0.9f, 0.9f);  // drawn before ea: argument order is unspecified
    const float ea = rng.uniform(-0.9f, 0.9f);
    rig.eval.push_back(at(ea, eb, detail::view_name("eval", k)));
  }
  return rig;
}

// LERF-like 360-degree orbit: azimuths evenly spaced, elevation wobbling by +-8 degrees;
// evaluation views halfway between training azimuths, 5 degrees higher.
inline Rig orbit_rig(const World& w, const RigParams& p = {}, int default_train = 40) {
  const int n_train = p.n_train > 0 ? p.n_train : default_train, n_eval = p.n_eval > 0 ? p.n_eval : 8;
  detail::check(p, n_train, n_eval);
  const float two_pi = 2.f * std::numbers::pi_v<float>, e = p.elevation_deg * detail::deg;
  std::vector<std::pair<float, float>> tr, ev;
  for (int k = 0; k < n_train; ++k) {
    const float a = two_pi * k / n_train;
    tr.push_back({a, e + 8.f * detail::deg * std::sin(3.f * a)});
  }
  for (int k = 0; k < n_eval; ++k) {
    const float a = two_pi * (std::floor(static_cast<float>(k) * n_train / n_eval) + 0.5f) / n_train;
    ev.push_back({a, e + 5.f * detail::deg});
  }
  Rig rig;
  rig.kind = "orbit";
  rig.train = detail::ring(w, p, "train", tr);
  rig.eval = detail::ring(w, p, "eval", ev);
  rig.reference = 0;  // azimuth 0: the front
  return rig;
}

// Sparse captures: an orbit with few views (default 6; the benchmark range is 4-8).
inline Rig sparse_rig(const World& w, const RigParams& p = {}) {
  Rig rig = orbit_rig(w, p, 6);
  rig.kind = "sparse";
  return rig;
}

// Hemisphere-only: cameras see the target from the front half of directions (azimuth within
// +-80 degrees of the front, elevation 10-60 degrees); the back half is never observed, so the
// largest angular gap exceeds 90 degrees (the SSS trigger).
inline Rig hemisphere_rig(const World& w, const RigParams& p = {}) {
  const int n_train = p.n_train > 0 ? p.n_train : 24, n_eval = p.n_eval > 0 ? p.n_eval : 8;
  detail::check(p, n_train, n_eval);
  const int rows = 3, cols = (n_train + rows - 1) / rows;
  std::vector<std::pair<float, float>> tr, ev;
  std::size_t ref = 0;
  float best = INFINITY;
  for (int k = 0; k < n_train; ++k) {
    const int i = k % rows, j = k / rows;
    const float a = (cols > 1 ? -80.f + 160.f * j / (cols - 1) : 0.f) * detail::deg;
    const float e = (10.f + 25.f * i) * detail::deg;
    tr.push_back({a, e});
    const float score = std::abs(a) + std::abs(e - p.elevation_deg * detail::deg);
    if (score < best) { best = score; ref = static_cast<std::size_t>(k); }
  }
  Rng rng(p.seed, 0x4E5u);
  for (int k = 0; k < n_eval; ++k)
    ev.push_back({rng.uniform(-75.f, 75.f) * detail::deg, rng.uniform(17.f, 53.f) * detail::deg});
  Rig rig;
  rig.kind = "hemisphere";
  rig.train = detail::ring(w, p, "train", tr);
  rig.eval = detail::ring(w, p, "eval", ev);
  rig.reference = ref;
  return rig;
}

// By name: "forward", "orbit", "sparse", "hemisphere".
inline Rig make_rig(const std::string& kind, const World& w, const RigParams& p = {}) {
  if (kind == "forward") return forward_facing_rig(w, p);
  if (kind == "orbit") return orbit_rig(w, p);
  if (kind == "sparse") return sparse_rig(w, p);
  if (kind == "hemisphere") return hemisphere_rig(w, p);
  throw Error("unknown rig '" + kind + "' (forward, orbit, sparse, hemisphere)", "rig");
}

}  // namespace vcar::synth
