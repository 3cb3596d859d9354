#pragma once
// Analytic primitives of the synthetic world: closed-form ray intersection (the exact 2D ground
// truth), signed distance (contacts, buried samples) and area-uniform surface sampling (where
// the Gaussians sit). Each primitive lives in its local frame: world = R * local + t.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Core>

#include "vcar/core/error.hpp"
#include "vcar/synth/random.hpp"

namespace vcar::synth {

// Local shapes and their `params`:
//   sphere   (r, -, -)            centred at the origin
//   box      (hx, hy, hz)         half extents
//   cylinder (r, h, -)            axis local z, z in [-h, h], capped
//   rod      (r, h, -)            a thin cylinder (same geometry, its own name in scene.json)
//   torus    (R, r, -)            ring of radius R around local z, tube radius r
//   plane    (hx, hy, -)          rectangle z = 0, |x| <= hx, |y| <= hy, normal +z (one sided
//                                 for sampling, two sided for rays)
enum class PrimitiveType { sphere, box, cylinder, rod, torus, plane };

inline const char* to_string(PrimitiveType t) {
  switch (t) {
    case PrimitiveType::sphere: return "sphere";
    case PrimitiveType::box: return "box";
    case PrimitiveType::cylinder: return "cylinder";
    case PrimitiveType::rod: return "rod";
    case PrimitiveType::torus: return "torus";
    case PrimitiveType::plane: return "plane";
  }
  return "?";
}

inline PrimitiveType primitive_type_from_string(const std::string& s) {
  for (auto t : {PrimitiveType::sphere, PrimitiveType::box, PrimitiveType::cylinder,
                 PrimitiveType::rod, PrimitiveType::torus, PrimitiveType::plane})
    if (s == to_string(t)) return t;
  throw Error("unknown primitive type '" + s + "'", "primitive.type");
}

// Procedural colour so that renders look like objects (and segmenters would have edges to see).
enum class Pattern { solid, stripes, checker, noise };

struct Texture {
  Pattern pattern = Pattern::solid;
  Eigen::Vector3f colour_a{0.7f, 0.7f, 0.7f};
  Eigen::Vector3f colour_b{0.3f, 0.3f, 0.3f};
  float frequency = 8.f;  // cycles per world unit (local coordinates)
};

struct Primitive {
  PrimitiveType type = PrimitiveType::sphere;
  Eigen::Matrix3f R = Eigen::Matrix3f::Identity();  // local-to-world rotation
  Eigen::Vector3f t = Eigen::Vector3f::Zero();      // local origin in world
  Eigen::Vector3f params = Eigen::Vector3f::Ones();
  int object_id = 0;
  Texture texture;

  Eigen::Vector3f to_local(const Eigen::Vector3f& p) const { return R.transpose() * (p - t); }
};

namespace detail {
inline float sdf_local(const Primitive& q, const Eigen::Vector3f& p) {
  const Eigen::Vector3f& a = q.params;
  switch (q.type) {
    case PrimitiveType::sphere: return p.norm() - a[0];
    case PrimitiveType::box: {
      const Eigen::Vector3f d = p.cwiseAbs() - a;
      return d.cwiseMax(0.f).norm() + std::min(d.maxCoeff(), 0.f);
    }
    case PrimitiveType::cylinder:
    case PrimitiveType::rod: {
      const float dx = std::hypot(p.x(), p.y()) - a[0], dz = std::abs(p.z()) - a[1];
      return std::min(std::max(dx, dz), 0.f) + std::hypot(std::max(dx, 0.f), std::max(dz, 0.f));
    }
    case PrimitiveType::torus: return std::hypot(std::hypot(p.x(), p.y()) - a[0], p.z()) - a[1];
    case PrimitiveType::plane: {
      const float dx = std::max(std::abs(p.x()) - a[0], 0.f), dy = std::max(std::abs(p.y()) - a[1], 0.f);
      return std::sqrt(dx * dx + dy * dy + p.z() * p.z());
    }
  }
  return 0.f;
}

// Nearest root of a t^2 + 2 b t + c = 0 above t_min (the half-b form), or false.
inline bool first_quadratic_root(float a, float b, float c, float t_min, float& t0, float& t1) {
  const float disc = b * b - a * c;
  if (!(disc >= 0.f) || a == 0.f) return false;
  const float s = std::sqrt(disc);
  t0 = (-b - s) / a;
  t1 = (-b + s) / a;
  return t1 > t_min;
}
}  // namespace detail

// Signed distance from a world point to the surface (negative inside; the plane has no inside).
inline float sdf(const Primitive& q, const Eigen::Vector3f& p_world) {
  return detail::sdf_local(q, q.to_local(p_world));
}

// Radius of a sphere around `t` that contains the primitive (ray culling).
inline float bounding_radius(const Primitive& q) {
  const Eigen::Vector3f& a = q.params;
  switch (q.type) {
    case PrimitiveType::sphere: return a[0];
    case PrimitiveType::box: return a.norm();
    case PrimitiveType::cylinder:
    case PrimitiveType::rod: return std::hypot(a[0], a[1]);
    case PrimitiveType::torus: return a[0] + a[1];
    case PrimitiveType::plane: return std::hypot(a[0], a[1]);
  }
  return 0.f;
}

// Surface area (the generator's Gaussian budget is proportional to it).
inline float area(const Primitive& q) {
  constexpr float pi = std::numbers::pi_v<float>;
  const Eigen::Vector3f& a = q.params;
  switch (q.type) {
    case PrimitiveType::sphere: return 4.f * pi * a[0] * a[0];
    case PrimitiveType::box: return 8.f * (a[0] * a[1] + a[1] * a[2] + a[0] * a[2]);
    case PrimitiveType::cylinder:
    case PrimitiveType::rod: return 4.f * pi * a[0] * a[1] + 2.f * pi * a[0] * a[0];
    case PrimitiveType::torus: return 4.f * pi * pi * a[0] * a[1];
    case PrimitiveType::plane: return 4.f * a[0] * a[1];
  }
  return 0.f;
}

// Nearest intersection of the ray o + s d (d unit, world) with the surface for s in
// (s_min, s_max); writes it to s_hit. Closed form for all shapes except the torus, which is
// sphere-traced along its exact distance function (never steps past the first hit).
inline bool intersect(const Primitive& q, const Eigen::Vector3f& o_world, const Eigen::Vector3f& d_world,
                      float s_min, float s_max, float& s_hit) {
  // Cheap reject by the bounding sphere before the local transform.
  const Eigen::Vector3f oc = o_world - q.t;
  const float rb = bounding_radius(q) * 1.0001f + 1e-6f;
  const float bb = oc.dot(d_world), cc = oc.squaredNorm() - rb * rb;
  if (cc > 0.f && (bb > 0.f || bb * bb < cc)) return false;

  const Eigen::Vector3f o = q.R.transpose() * oc, d = q.R.transpose() * d_world;
  const Eigen::Vector3f& a = q.params;
  float best = s_max;
  bool hit = false;
  auto take = [&](float s) { if (s > s_min && s < best) { best = s; hit = true; } };
  switch (q.type) {
    case PrimitiveType::sphere: {
      float t0, t1;
      if (detail::first_quadratic_root(1.f, o.dot(d), o.squaredNorm() - a[0] * a[0], s_min, t0, t1)) {
        take(t0); if (!hit) take(t1);
      }
      break;
    }
    case PrimitiveType::box: {  // slabs
      float tn = -INFINITY, tf = INFINITY;
      for (int k = 0; k < 3; ++k) {
        if (d[k] == 0.f) {
          if (std::abs(o[k]) > a[k]) return false;
          continue;
        }
        float t0 = (-a[k] - o[k]) / d[k], t1 = (a[k] - o[k]) / d[k];
        if (t0 > t1) std::swap(t0, t1);
        tn = std::max(tn, t0);
        tf = std::min(tf, t1);
      }
      if (tn <= tf) { take(tn); if (!hit) take(tf); }
      break;
    }
    case PrimitiveType::cylinder:
    case PrimitiveType::rod: {
      float t0, t1;
      const float A = d.x() * d.x() + d.y() * d.y();
      if (detail::first_quadratic_root(A, o.x() * d.x() + o.y() * d.y(),
                                       o.x() * o.x() + o.y() * o.y() - a[0] * a[0], s_min, t0, t1)) {
        for (float s : {t0, t1})
          if (std::abs(o.z() + s * d.z()) <= a[1]) take(s);
      }
      if (d.z() != 0.f) {
        for (float zc : {-a[1], a[1]}) {  // caps
          const float s = (zc - o.z()) / d.z();
          const float x = o.x() + s * d.x(), y = o.y() + s * d.y();
          if (x * x + y * y <= a[0] * a[0]) take(s);
        }
      }
      break;
    }
    case PrimitiveType::plane: {
      if (d.z() != 0.f) {
        const float s = -o.z() / d.z();
        if (std::abs(o.x() + s * d.x()) <= a[0] && std::abs(o.y() + s * d.y()) <= a[1]) take(s);
      }
      break;
    }
    case PrimitiveType::torus: {
      // Sphere tracing in double along |sdf| (exact distance: no step crosses the surface).
      const double R = a[0], r = a[1];
      const double b = static_cast<double>(o.dot(d)), c = static_cast<double>(o.squaredNorm()) - (R + r) * (R + r);
      const double disc = b * b - c;
      if (disc < 0.0) break;
      double s = std::max(static_cast<double>(s_min), -b - std::sqrt(disc));
      const double s_end = std::min(static_cast<double>(s_max), -b + std::sqrt(disc));
      const double eps = 1e-6 * (R + r);
      for (int it = 0; it < 1000 && s < s_end; ++it) {
        const double x = o.x() + s * d.x(), y = o.y() + s * d.y(), z = o.z() + s * d.z();
        const double dist = std::abs(std::hypot(std::hypot(x, y) - R, z) - r);
        if (dist < eps) {
          if (s > s_min) take(static_cast<float>(s));
          break;
        }
        s += dist;
      }
      break;
    }
  }
  if (hit) s_hit = best;
  return hit;
}

struct SurfaceSample {
  Eigen::Vector3f p;        // world position
  Eigen::Vector3f n;        // world outward normal (unit)
  Eigen::Vector3f local;    // local position (texture coordinates)
};

// A point uniform by area on the surface.
inline SurfaceSample sample_surface(const Primitive& q, Rng& rng) {
  constexpr float pi = std::numbers::pi_v<float>;
  const Eigen::Vector3f& a = q.params;
  Eigen::Vector3f p = Eigen::Vector3f::Zero(), n = Eigen::Vector3f::UnitZ();  // every case sets both
  switch (q.type) {
    case PrimitiveType::sphere: {
      const float z = rng.uniform(-1.f, 1.f), phi = 2.f * pi * rng.uniform();
      const float rho = std::sqrt(std::max(0.f, 1.f - z * z));
      n = {rho * std::cos(phi), rho * std::sin(phi), z};
      p = a[0] * n;
      break;
    }
    case PrimitiveType::box: {
      const float w[3] = {a[1] * a[2], a[0] * a[2], a[0] * a[1]};  // face area per axis
      const float pick = rng.uniform() * (w[0] + w[1] + w[2]);
      const int k = pick < w[0] ? 0 : (pick < w[0] + w[1] ? 1 : 2);
      const float sign = rng.uniform() < 0.5f ? -1.f : 1.f;
      for (int j = 0; j < 3; ++j) p[j] = rng.uniform(-a[j], a[j]);
      p[k] = sign * a[k];
      n = Eigen::Vector3f::Zero();
      n[k] = sign;
      break;
    }
    case PrimitiveType::cylinder:
    case PrimitiveType::rod: {
      const float side = 2.f * a[1], cap = a[0];  // side : both caps = 2 pi r 2h : 2 pi r^2
      const float phi = 2.f * pi * rng.uniform();
      if (rng.uniform() * (side + cap) < side) {
        n = {std::cos(phi), std::sin(phi), 0.f};
        p = {a[0] * n.x(), a[0] * n.y(), rng.uniform(-a[1], a[1])};
      } else {
        const float rho = a[0] * std::sqrt(rng.uniform());
        const float sign = rng.uniform() < 0.5f ? -1.f : 1.f;
        n = {0.f, 0.f, sign};
        p = {rho * std::cos(phi), rho * std::sin(phi), sign * a[1]};
      }
      break;
    }
    case PrimitiveType::torus: {
      const float phi = 2.f * pi * rng.uniform();
      float theta = 0.f;
      for (int it = 0; it < 64; ++it) {  // area element (R + r cos theta): rejection
        theta = 2.f * pi * rng.uniform();
        if (rng.uniform() * (a[0] + a[1]) <= a[0] + a[1] * std::cos(theta)) break;
      }
      n = {std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), std::sin(theta)};
      const float rho = a[0] + a[1] * std::cos(theta);
      p = {rho * std::cos(phi), rho * std::sin(phi), a[1] * std::sin(theta)};
      break;
    }
    case PrimitiveType::plane: {
      p = {rng.uniform(-a[0], a[0]), rng.uniform(-a[1], a[1]), 0.f};
      n = {0.f, 0.f, 1.f};
      break;
    }
  }
  return {q.R * p + q.t, q.R * n, p};
}

namespace detail {
inline float lattice(int x, int y, int z, std::uint64_t key) {
  const std::uint64_t h = hash_combine(hash_combine(hash_combine(key, static_cast<std::uint32_t>(x)),
                                                    static_cast<std::uint32_t>(y)), static_cast<std::uint32_t>(z));
  return static_cast<float>(h >> 40) * (1.f / 16777216.f);
}
// Trilinear value noise in [0, 1].
inline float value_noise(const Eigen::Vector3f& p, std::uint64_t key) {
  const Eigen::Vector3f f = p.array().floor();
  const int x = static_cast<int>(f.x()), y = static_cast<int>(f.y()), z = static_cast<int>(f.z());
  const Eigen::Vector3f w = p - f;
  float acc = 0.f;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const float wt = (dx ? w.x() : 1.f - w.x()) * (dy ? w.y() : 1.f - w.y()) * (dz ? w.z() : 1.f - w.z());
    acc += wt * lattice(x + dx, y + dy, z + dz, key);
  }
  return acc;
}
}  // namespace detail

// Colour of the surface at a local point.
inline Eigen::Vector3f surface_colour(const Primitive& q, const Eigen::Vector3f& local) {
  const Texture& tx = q.texture;
  const Eigen::Vector3f u = local * tx.frequency;
  switch (tx.pattern) {
    case Pattern::solid: return tx.colour_a;
    case Pattern::stripes: return (u.x() + 0.5f * u.z() - std::floor(u.x() + 0.5f * u.z())) < 0.5f ? tx.colour_a : tx.colour_b;
    case Pattern::checker: {
      const int s = static_cast<int>(std::floor(u.x()) + std::floor(u.y()) + std::floor(u.z()));
      return (s & 1) ? tx.colour_b : tx.colour_a;
    }
    case Pattern::noise: {
      const float w = detail::value_noise(u, static_cast<std::uint64_t>(q.object_id) + 77u);
      return (1.f - w) * tx.colour_a + w * tx.colour_b;
    }
  }
  return tx.colour_a;
}

}  // namespace vcar::synth
