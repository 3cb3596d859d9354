#pragma once
// The synthetic world: analytic primitives resting on a table and touching each other, the
// Gaussians sampled on their surfaces (with 3DGS-like defects), and every Gaussian's true
// object id. Deterministic from (seed, size): same parameters, same bytes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/synth/primitive.hpp"
#include "vcar/synth/random.hpp"

namespace vcar::synth {

// Gaussians copied from a trained scene (e.g. tests/data/donut.ply) and placed in the world.
// Their ground truth needs a Renderer (alpha of their rendering > 0.5), see ground_truth.hpp.
// Robust extents of inserted objects use the quantiles q and 1 - q of their means along an axis:
// one Gaussian in a thousand may stray (a floater of the capture) without changing an object's
// box, its size on a stage or its contact with the floor (synth/stage.hpp).
inline constexpr double robust_extent_quantile = 0.001;

namespace detail {
// The value of rank floor(q (n - 1)) among v (v is reordered; not empty).
inline float quantile(std::vector<float>& v, double q) {
  const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[static_cast<std::size_t>(k)];
}
}  // namespace detail

struct InsertedObject {
  int object_id = 0;
  std::size_t begin = 0, count = 0;  // Gaussians [begin, begin + count) of World::scene
};

struct World {
  std::vector<Primitive> primitives;
  std::vector<InsertedObject> inserted;
  GaussianScene scene;
  std::vector<int> object_id;  // per Gaussian: true object, -1 = background / floater
  int target_id = 1;
  int neighbour_id = 2;        // an object that touches the target
  Eigen::Vector3f up{0.f, 0.f, 1.f};
  std::uint64_t seed = 0;

  // Indices of the Gaussians whose true id is `id` (the ideal selection when id = target).
  std::vector<Index> gaussians_of(int id) const {
    std::vector<Index> out;
    for (std::size_t i = 0; i < object_id.size(); ++i)
      if (object_id[i] == id) out.push_back(static_cast<Index>(i));
    return out;
  }
  // Bounding sphere (centre, radius) of object `id`: its primitives and the robust box of its
  // inserted Gaussians (robust_extent_quantile), so a trained object's stray floaters do not
  // push the rigs' cameras away.
  std::pair<Eigen::Vector3f, float> bounds(int id) const;
  bool has_inserted(int id) const {
    for (const auto& o : inserted) if (o.object_id == id) return true;
    return false;
  }
};

inline std::pair<Eigen::Vector3f, float> World::bounds(int id) const {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  for (const auto& q : primitives)
    if (q.object_id == id) {
      const float r = bounding_radius(q);
      lo = lo.cwiseMin((q.t.array() - r).matrix());
      hi = hi.cwiseMax((q.t.array() + r).matrix());
    }
  std::vector<float> v[3];
  for (const auto& o : inserted)
    if (o.object_id == id)
      for (std::size_t i = o.begin; i < o.begin + o.count; ++i)
        for (int d = 0; d < 3; ++d) v[d].push_back(scene.mean[d][i]);
  Eigen::Vector3f ilo = Eigen::Vector3f::Constant(INFINITY), ihi = -ilo;  // the inserted Gaussians' robust box
  if (!v[0].empty())
    for (int d = 0; d < 3; ++d) {
      ilo[d] = detail::quantile(v[d], robust_extent_quantile);
      ihi[d] = detail::quantile(v[d], 1.0 - robust_extent_quantile);
    }
  lo = lo.cwiseMin(ilo);
  hi = hi.cwiseMax(ihi);
  if (!(lo.x() <= hi.x())) throw Error("no object with id " + std::to_string(id), "world");
  const Eigen::Vector3f c = 0.5f * (lo + hi);
  float r = 0.f;
  for (const auto& q : primitives)
    if (q.object_id == id) r = std::max(r, (q.t - c).norm() + bounding_radius(q));
  if (!v[0].empty()) r = std::max(r, (ilo - c).cwiseAbs().cwiseMax((ihi - c).cwiseAbs()).norm());
  return {c, r};
}

struct WorldParams {
  std::uint64_t seed = 1;
  std::size_t n_gaussians = 100000;  // total, defects included (10k .. 2M)
  float straddler_fraction = 0.003f;  // large Gaussians across contacts (id = sampled surface)
  float needle_fraction = 0.005f;    // elongated needles on surfaces
  float floater_fraction = 0.01f;    // low-opacity floaters in the air (id -1)
  float disc_scale = 0.8f;           // in-plane sigma / local spacing (overlap makes surfaces opaque)
  float normal_scale = 0.05f;        // normal sigma / local spacing (flat discs)
  int n_distractors = 2;             // extra objects on the table, ids 4, 5, ...
  // The target's shape: sphere, torus (concave), cylinder or box; unset = drawn from the seed.
  // Setting it changes nothing else of the world (the seed's draws stay the same).
  std::optional<PrimitiveType> target_type;
};

namespace detail {

// Rotation whose local z is `z` (unit).
inline Eigen::Matrix3f frame_from_z(const Eigen::Vector3f& z) {
  const Eigen::Vector3f x = z.unitOrthogonal(), y = z.cross(x);
  Eigen::Matrix3f R;
  R.col(0) = x; R.col(1) = y; R.col(2) = z;
  return R;
}

inline Texture random_texture(Rng& rng, Pattern pattern) {
  Texture t;
  t.pattern = pattern;
  for (int c = 0; c < 3; ++c) { t.colour_a[c] = rng.uniform(0.35f, 0.95f); t.colour_b[c] = rng.uniform(0.05f, 0.5f); }
  t.frequency = rng.uniform(6.f, 14.f);
  return t;
}

// A buried sample lies inside (or flush with) another primitive or under the table.
inline bool buried(const std::vector<Primitive>& prims, std::size_t self, const Eigen::Vector3f& p) {
  constexpr float tol = 1e-4f;
  for (std::size_t m = 0; m < prims.size(); ++m) {
    if (m == self) continue;
    const Primitive& q = prims[m];
    if (q.type == PrimitiveType::plane) {
      const Eigen::Vector3f l = q.to_local(p);
      if (l.z() < tol && std::abs(l.x()) <= q.params[0] && std::abs(l.y()) <= q.params[1]) return true;
    } else if (sdf(q, p) < tol) {
      return true;
    }
  }
  return false;
}

// Writes one Gaussian: axes (u, n x u, n) with sigmas s, colour rgb.
inline void put_gaussian(GaussianScene& g, std::size_t i, const Eigen::Vector3f& p, const Eigen::Vector3f& n,
                         const Eigen::Vector3f& u, const Eigen::Vector3f& s, float opacity,
                         const Eigen::Vector3f& rgb) {
  Eigen::Matrix3f R;
  R.col(0) = u; R.col(1) = n.cross(u); R.col(2) = n;
  const Eigen::Quaternionf q(R);
  g.set(i, p, s.array().log().matrix(), Eigen::Vector4f(q.w(), q.x(), q.y(), q.z()),
        std::log(opacity / (1.f - opacity)));
  g.set_rgb(i, rgb.cwiseMax(0.f).cwiseMin(1.f));
}

inline Eigen::Vector3f random_tangent(const Eigen::Vector3f& n, Rng& rng) {
  const Eigen::Vector3f e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  const float a = 2.f * std::numbers::pi_v<float> * rng.uniform();
  return std::cos(a) * e1 + std::sin(a) * e2;
}

// Writes Gaussian i as a flat textured disc on primitive P[k] (a sample uniform by area, redrawn
// while buried in another primitive): in-plane sigmas disc_scale h (+-25%), normal sigma
// normal_scale h, where h is the local spacing of the samples; opaque, its colour the texture's
// with a grain. Shared by the world's surfaces and the stage's floor (synth/stage.hpp).
inline void surface_disc(GaussianScene& g, std::size_t i, const std::vector<Primitive>& P, std::size_t k, float h,
                         float disc_scale, float normal_scale, Rng& rng) {
  SurfaceSample smp = sample_surface(P[k], rng);
  for (int attempt = 0; attempt < 64 && buried(P, k, smp.p); ++attempt) smp = sample_surface(P[k], rng);
  // Random draws are sequenced explicitly (argument order is unspecified in C++; see make_layout).
  const float s1 = rng.uniform(0.75f, 1.25f);
  const float s0 = rng.uniform(0.75f, 1.25f);
  const Eigen::Vector3f s(disc_scale * h * s0, disc_scale * h * s1, normal_scale * h);
  const Eigen::Vector3f jitter = Eigen::Vector3f::Constant(rng.uniform(-0.03f, 0.03f));
  const float opacity = rng.uniform(0.92f, 0.99f);
  const Eigen::Vector3f tangent = random_tangent(smp.n, rng);
  put_gaussian(g, i, smp.p, smp.n, tangent, s, opacity, surface_colour(P[k], smp.local) + jitter);
}

// The layout: table (0), target (1), neighbour box touching it (2), a rod leaning on the
// neighbour (3), distractors (4...). Sizes and target shape vary with the seed.
inline std::vector<Primitive> make_layout(const WorldParams& wp) {
  Rng rng(wp.seed, 0xA11u);
  std::vector<Primitive> P;
  Primitive table;
  table.type = PrimitiveType::plane;
  table.params = {1.f, 1.f, 0.f};
  table.object_id = 0;
  table.texture = random_texture(rng, Pattern::noise);
  table.texture.frequency = 5.f;
  P.push_back(table);

  const float s = rng.uniform(0.22f, 0.3f);
  Primitive target;
  target.object_id = 1;
  target.texture = random_texture(rng, Pattern::stripes);
  float extent_x = 0.f, contact_z = 0.f;
  const int drawn = rng.uniform_int(0, 3);
  int kind = drawn;
  if (wp.target_type) {
    switch (*wp.target_type) {
      case PrimitiveType::sphere: kind = 0; break;
      case PrimitiveType::torus: kind = 1; break;
      case PrimitiveType::cylinder: kind = 2; break;
      case PrimitiveType::box: kind = 3; break;
      default: throw Error("the target must be a sphere, torus, cylinder or box", "WorldParams.target_type");
    }
  }
  switch (kind) {
    case 0: target.type = PrimitiveType::sphere; target.params = {s, 0, 0};
            target.t = {0, 0, s}; extent_x = s; contact_z = s; break;
    case 1: target.type = PrimitiveType::torus; target.params = {0.75f * s, 0.3f * s, 0};
            target.t = {0, 0, 0.3f * s}; extent_x = 1.05f * s; contact_z = 0.3f * s; break;
    case 2: target.type = PrimitiveType::cylinder; target.params = {0.7f * s, s, 0};
            target.t = {0, 0, s}; extent_x = 0.7f * s; contact_z = s; break;
    default: target.type = PrimitiveType::box; target.params = {0.8f * s, 0.6f * s, 0.8f * s};
             target.t = {0, 0, 0.8f * s}; extent_x = 0.8f * s; contact_z = 0.8f * s; break;
  }
  P.push_back(target);

  Primitive nb;  // a box whose -x face touches the target's +x extreme point
  nb.type = PrimitiveType::box;
  nb.object_id = 2;
  nb.texture = random_texture(rng, Pattern::checker);
  const float hz = std::max(rng.uniform(0.7f, 1.0f) * s, 0.6f * contact_z + 0.05f);
  nb.params = {rng.uniform(0.5f, 0.7f) * s, rng.uniform(0.7f, 0.9f) * s, hz};
  nb.t = {extent_x + nb.params[0], 0.f, hz};
  P.push_back(nb);

  Primitive rod;  // leans on the neighbour's far top edge, foot on the table
  rod.type = PrimitiveType::rod;
  rod.object_id = 3;
  rod.texture = random_texture(rng, Pattern::solid);
  const float rr = 0.012f;
  const Eigen::Vector3f E(nb.t.x() + nb.params[0], rng.uniform(-0.3f, 0.3f) * nb.params[1], 2.f * hz);
  // Random draws are sequenced explicitly (argument order is unspecified in C++; this is the
  // order the generator has always used, so worlds stay the same bytes on every compiler).
  const float F_dy = rng.uniform(-0.1f, 0.1f);
  const float F_dx = rng.uniform(0.5f, 0.9f);
  const Eigen::Vector3f F(E.x() + F_dx * 2.f * hz, E.y() + F_dy, rr);
  const Eigen::Vector3f d0 = (E - F).normalized();
  const Eigen::Vector3f perp = Eigen::Vector3f(-d0.z(), 0.f, d0.x()).normalized();  // up and away
  const Eigen::Vector3f top = E + rr * (perp.z() > 0.f ? perp : Eigen::Vector3f(-perp));
  const Eigen::Vector3f dir = (top - F).normalized();
  const float len = 1.12f * (top - F).norm();
  rod.R = frame_from_z(dir);
  rod.params = {rr, 0.5f * len, 0.f};
  rod.t = F + 0.5f * len * dir;
  P.push_back(rod);

  // Distractors at free spots of the table (footprint circles kept apart).
  std::vector<std::pair<Eigen::Vector2f, float>> used;
  used.push_back({Eigen::Vector2f(0, 0), extent_x});
  used.push_back({nb.t.head<2>(), std::hypot(nb.params[0], nb.params[1])});
  used.push_back({rod.t.head<2>(), 0.5f * len});
  for (int k = 0; k < wp.n_distractors; ++k) {
    Primitive q;
    q.object_id = 4 + k;
    const float sz = rng.uniform(0.08f, 0.16f);
    float foot = sz;
    switch (rng.uniform_int(0, 3)) {
      case 0: q.type = PrimitiveType::sphere; q.params = {sz, 0, 0}; q.t.z() = sz; break;
      case 1: q.type = PrimitiveType::torus; q.params = {0.7f * sz, 0.3f * sz, 0}; q.t.z() = 0.3f * sz; break;
      case 2: q.type = PrimitiveType::cylinder; q.params = {0.6f * sz, 1.4f * sz, 0}; q.t.z() = 1.4f * sz; break;
      default: q.type = PrimitiveType::box; q.params = {sz, 0.7f * sz, 0.6f * sz}; q.t.z() = 0.6f * sz;
               foot = std::hypot(sz, 0.7f * sz); break;
    }
    q.texture = random_texture(rng, static_cast<Pattern>(rng.uniform_int(0, 3)));
    for (int attempt = 0; attempt < 200; ++attempt) {
      const float cy = rng.uniform(-0.85f, 0.85f);  // drawn before cx (see F above)
      const float cx = rng.uniform(-0.85f, 0.85f);
      const Eigen::Vector2f c(cx, cy);
      bool ok = std::max(std::abs(c.x()), std::abs(c.y())) + foot < 0.98f;
      for (auto& [uc, ur] : used) ok = ok && (c - uc).norm() > ur + foot + 0.05f;
      if (ok) { q.t.head<2>() = c; used.push_back({c, foot}); P.push_back(q); break; }
    }
  }
  return P;
}

}  // namespace detail

// Generates the world: surface discs (density proportional to area, buried samples redrawn),
// then straddlers, needles and floaters. Ids: table 0, target 1, neighbour 2, rod 3,
// distractors 4..; floaters -1.
inline World generate_world(const WorldParams& wp = {}) {
  if (wp.n_gaussians < 100) throw Error("need at least 100 Gaussians", "WorldParams.n_gaussians");
  if (wp.straddler_fraction < 0 || wp.needle_fraction < 0 || wp.floater_fraction < 0 ||
      wp.straddler_fraction + wp.needle_fraction + wp.floater_fraction > 0.5f)
    throw Error("defect fractions must be >= 0 and sum to at most 0.5", "WorldParams");
  World w;
  w.seed = wp.seed;
  w.primitives = detail::make_layout(wp);
  const auto& P = w.primitives;
  const std::size_t N = wp.n_gaussians;
  const std::size_t n_strad = static_cast<std::size_t>(wp.straddler_fraction * N);
  const std::size_t n_needle = static_cast<std::size_t>(wp.needle_fraction * N);
  const std::size_t n_float = static_cast<std::size_t>(wp.floater_fraction * N);
  const std::size_t n_surf = N - n_strad - n_needle - n_float;

  // Budget per primitive proportional to area (largest remainder, deterministic).
  double A_total = 0;
  for (const auto& q : P) A_total += area(q);
  std::vector<std::size_t> count(P.size());
  std::vector<std::pair<double, std::size_t>> rem;
  std::size_t assigned = 0;
  for (std::size_t k = 0; k < P.size(); ++k) {
    const double exact = n_surf * area(P[k]) / A_total;
    count[k] = static_cast<std::size_t>(exact);
    assigned += count[k];
    rem.push_back({exact - count[k], k});
  }
  std::stable_sort(rem.begin(), rem.end(), [](auto& a, auto& b) { return a.first > b.first; });
  for (std::size_t j = 0; assigned < n_surf; ++j, ++assigned) ++count[rem[j % rem.size()].second];
  std::vector<std::size_t> offset(P.size() + 1, 0);
  for (std::size_t k = 0; k < P.size(); ++k) offset[k + 1] = offset[k] + count[k];
  const float h_global = static_cast<float>(std::sqrt(A_total / static_cast<double>(n_surf)));

  w.scene.resize(N, 0);
  w.object_id.assign(N, -1);
  GaussianScene& g = w.scene;

  // Surface discs.
  parallel_for(static_cast<std::int64_t>(n_surf), [&](std::int64_t ii) {
    const std::size_t i = static_cast<std::size_t>(ii);
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(offset.begin(), offset.end(), i) - offset.begin()) - 1;
    Rng rng(wp.seed, 1, i);
    const float h = std::sqrt(area(P[k]) / static_cast<float>(count[k]));
    detail::surface_disc(g, i, P, k, h, wp.disc_scale, wp.normal_scale, rng);
    w.object_id[i] = P[k].object_id;
  });

  // Objects other than the table, for straddlers and needles.
  std::vector<std::size_t> solids;
  for (std::size_t k = 0; k < P.size(); ++k) if (P[k].type != PrimitiveType::plane) solids.push_back(k);

  // Straddlers: big thick discs within 3 h of a contact with another primitive.
  parallel_for(static_cast<std::int64_t>(n_strad), [&](std::int64_t jj) {
    const std::size_t i = n_surf + static_cast<std::size_t>(jj);
    Rng rng(wp.seed, 2, i);
    const std::size_t k = solids[std::min<std::size_t>(solids.size() - 1, static_cast<std::size_t>(jj) % std::min<std::size_t>(3, solids.size()))];
    SurfaceSample smp = sample_surface(P[k], rng);
    for (int attempt = 0; attempt < 2000; ++attempt) {
      bool near_contact = false;
      for (std::size_t m = 0; m < P.size() && !near_contact; ++m)
        near_contact = m != k && std::abs(sdf(P[m], smp.p)) < 3.f * h_global;
      if (near_contact && !detail::buried(P, k, smp.p)) break;
      smp = sample_surface(P[k], rng);
    }
    const float big = h_global * rng.uniform(2.f, 4.f);
    const float s2 = rng.uniform(0.5f, 1.f);  // sequenced: s2, s1, opacity, tangent (see F above)
    const float s1 = rng.uniform(0.6f, 1.f);
    const Eigen::Vector3f s(big, big * s1, h_global * s2);
    const float opacity = rng.uniform(0.5f, 0.9f);
    const Eigen::Vector3f tangent = detail::random_tangent(smp.n, rng);
    detail::put_gaussian(g, i, smp.p, smp.n, tangent, s, opacity, surface_colour(P[k], smp.local));
    w.object_id[i] = P[k].object_id;
  });

  // Needles: one long axis along the surface.
  parallel_for(static_cast<std::int64_t>(n_needle), [&](std::int64_t jj) {
    const std::size_t i = n_surf + n_strad + static_cast<std::size_t>(jj);
    Rng rng(wp.seed, 3, i);
    const std::size_t k = solids[static_cast<std::size_t>(jj) % solids.size()];
    SurfaceSample smp = sample_surface(P[k], rng);
    for (int attempt = 0; attempt < 64 && detail::buried(P, k, smp.p); ++attempt) smp = sample_surface(P[k], rng);
    const Eigen::Vector3f s(h_global * rng.uniform(4.f, 8.f), 0.3f * h_global, wp.normal_scale * h_global);
    const float opacity = rng.uniform(0.6f, 0.95f);  // drawn before the tangent (see F above)
    const Eigen::Vector3f tangent = detail::random_tangent(smp.n, rng);
    detail::put_gaussian(g, i, smp.p, smp.n, tangent, s, opacity, surface_colour(P[k], smp.local));
    w.object_id[i] = P[k].object_id;
  });

  // Floaters: faint blobs in the air above the table, background.
  parallel_for(static_cast<std::int64_t>(n_float), [&](std::int64_t jj) {
    const std::size_t i = n_surf + n_strad + n_needle + static_cast<std::size_t>(jj);
    Rng rng(wp.seed, 4, i);
    Eigen::Vector3f p, n;  // components drawn z, y, x (see F above)
    p.z() = rng.uniform(0.05f, 0.9f); p.y() = rng.uniform(-1.f, 1.f); p.x() = rng.uniform(-1.f, 1.f);
    n.z() = rng.uniform(-1.f, 1.f); n.y() = rng.uniform(-1.f, 1.f); n.x() = rng.uniform(-1.f, 1.f);
    n = n.squaredNorm() > 1e-6f ? n.normalized() : Eigen::Vector3f::UnitZ();
    const float big = h_global * rng.uniform(2.f, 5.f);
    const float grey = rng.uniform(0.3f, 0.8f);
    const float opacity = rng.uniform(0.03f, 0.25f);  // sequenced: opacity, s2, s1, tangent
    const float s2 = rng.uniform(0.3f, 1.f);
    const float s1 = rng.uniform(0.5f, 1.f);
    const Eigen::Vector3f tangent = detail::random_tangent(n, rng);
    detail::put_gaussian(g, i, p, n, tangent, Eigen::Vector3f(big, big * s1, big * s2), opacity,
                         Eigen::Vector3f::Constant(grey));
    w.object_id[i] = -1;
  });
  return w;
}

// The fixed scene of the README demo: ~100k Gaussians, a target touching a neighbour, floaters.
inline World default_world() {
  WorldParams p;
  p.seed = 7;
  p.n_gaussians = 100000;
  return generate_world(p);
}

// Appends the Gaussians of a trained object at world pose x -> R (scale x) + t, all with true
// id `object_id`. Colour keeps the DC term only (the world is SH degree 0: rotating
// view-dependent terms is out of scope); extra properties are dropped.
inline void insert_gaussians(World& w, const GaussianScene& obj, const Eigen::Matrix3f& R,
                             const Eigen::Vector3f& t, float scale, int object_id) {
  if (!(scale > 0.f)) throw Error("scale must be positive", "insert_gaussians");
  if (object_id < 0) throw Error("object id must be >= 0 (-1 is background)", "insert_gaussians");
  obj.validate("inserted object");
  GaussianScene& g = w.scene;
  const std::size_t n0 = g.size(), n = obj.size();
  GaussianScene merged;
  merged.resize(n0 + n, g.sh_degree);
  const std::size_t B3 = static_cast<std::size_t>(g.sh_coeffs()) * 3, B3o = static_cast<std::size_t>(obj.sh_coeffs()) * 3;
  for (std::size_t i = 0; i < n0; ++i) {
    for (int d = 0; d < 3; ++d) { merged.mean[d][i] = g.mean[d][i]; merged.log_scale[d][i] = g.log_scale[d][i]; }
    for (int c = 0; c < 4; ++c) merged.rotation[c][i] = g.rotation[c][i];
    merged.opacity_logit[i] = g.opacity_logit[i];
    for (std::size_t b = 0; b < B3; ++b) merged.sh[i * B3 + b] = g.sh[i * B3 + b];
  }
  const Eigen::Quaternionf qR(R);
  const float log_scale = std::log(scale);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = n0 + j;
    const Eigen::Vector3f mu = R * (scale * obj.mu(j)) + t;
    const Eigen::Quaternionf qj(obj.rotation[0][j], obj.rotation[1][j], obj.rotation[2][j], obj.rotation[3][j]);
    const Eigen::Quaternionf q = qR * qj.normalized();
    merged.set(i, mu, Eigen::Vector3f(obj.log_scale[0][j] + log_scale, obj.log_scale[1][j] + log_scale,
                                      obj.log_scale[2][j] + log_scale),
               Eigen::Vector4f(q.w(), q.x(), q.y(), q.z()), obj.opacity_logit[j]);
    for (int c = 0; c < 3; ++c) merged.sh[i * B3 + c] = obj.sh[j * B3o + c];
  }
  g = std::move(merged);
  w.object_id.resize(n0 + n, object_id);
  w.inserted.push_back({object_id, n0, n});
}

}  // namespace vcar::synth
