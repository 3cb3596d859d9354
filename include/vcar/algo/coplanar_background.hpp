#pragma once
// Beyond the paper: hidden candidates on a background surface are background
// (docs/robust.md, Eq. R10).
//
// A surface of another object pressed against the target (the table under a torus's ring, the
// face of a box that a cylinder leans on) is hidden in every training view, and it lies inside
// the target's silhouette from every direction the fine round can see it from: mask votes
// cannot tell it from the target's own underside. Its geometry can: it is flat, and the part of
// the same surface that the cameras do see, next to it, is background. So a fine candidate i
// that no training view sees takes the label of the seen Gaussians of its own plane nearby:
//   n_i = r_a         the axis of its smallest scale s_a (a = argmin_d s_d): the disc's normal
//   phi_i = 1 - s_a / s_b, s_b the smaller of the other two scales (flatness: disc 1, ball 0)
//   t_i = min_d s_d   its thickness
//   Q_i = { q seen, phi_q >= phi_min, |mu_q - mu_i| <= r_c,                 (coplanar neighbours)
//           |n_i . n_q| >= cos alpha, |n_i . (mu_q - mu_i)| <= k_t (t_i + t_q) }
//   E_i = { q seen, selected, phi_q >= phi_min, |mu_q - mu_i| <= r_c,      (the object's own
//           |n_i . n_q| <= cos beta, |n_i . (mu_q - mu_i)| <= sigma_c sqrt(n_i^T Sigma_q n_i) }  edges)
//   B_i = |{q in Q_i : q not selected}|,  S_i = |{q in Q_i : q selected}| + |E_i|
//   i is dropped  iff  i is hidden, phi_i >= phi_min and B_i > S_i                      (R10)
// with r_c = c_r * D, D the selection's extent (the largest distance of an Eq. 4 inlier from
// the robust centre), alpha = 5 degrees, k_t = 1 (CoplanarParams), beta = 60 degrees and
// sigma_c = 3. E_i are seen faces of the selection that meet i's plane edge-on and reach it
// within their 3-sigma extent: the plane is then one of the object's own faces (a box pressed
// against another box), not a surface that passes under it (a table under a ring, whose seen
// discs stay clear of it). "Seen" is the coarse round's occlusion test (Eq. R3 on renders of
// the whole scene): seen unoccluded in at least one training view. A flat object lying on a
// table is seen, so it is never dropped; curved surfaces have no coplanar neighbours beyond a
// few of their own.
// Cost: one pass over the scene for the region around the selection, two dense grids of cell
// r_c / 4 over its seen flat Gaussians (background, selected), and for each hidden flat
// candidate the cells within r_c that its plane's slab meets (the selected grid only when the
// background one holds a coplanar point).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/robust_sphere.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/parallel.hpp"

namespace vcar {

struct CoplanarParams {
  float radius = 0.f;       // c_r: neighbourhood radius as a fraction of the selection's extent D (0 = off)
  float angle_deg = 5.f;    // alpha: largest angle between the two normals
  float slab = 1.f;         // k_t: plane distance allowed, in thicknesses t_i + t_q
  float min_flatness = 0.5f;  // phi_min: flatness below which a Gaussian has no plane
  float edge_cos = 0.5f;      // cos beta: a seen selected disc at least beta from i's plane is edge-on
  float edge_sigma = 3.f;     // sigma_c: the extent along n_i within which an edge-on disc reaches the plane
};

namespace detail {

struct PlanePoint {
  Eigen::Vector3f mu, n;
  float t = 0.f;
  bool flat = false;
  Eigen::Matrix3f A = Eigen::Matrix3f::Zero();  // columns s_d r_d: n^T Sigma n = |A^T n|^2
};

// Normal n_i and flatness phi_i of Gaussian i (Eq. R10's, above).
inline std::pair<Eigen::Vector3f, float> normal_and_flatness(const GaussianScene& scene, Index i) {
  int a = 0;
  for (int d = 1; d < 3; ++d)
    if (scene.log_scale[d][i] < scene.log_scale[a][i]) a = d;
  const float s_b = std::min(scene.log_scale[(a + 1) % 3][i], scene.log_scale[(a + 2) % 3][i]);
  const float phi = std::clamp(1.f - std::exp(scene.log_scale[a][i] - s_b), 0.f, 1.f);
  return {scene.R(i).col(a), std::isfinite(phi) ? phi : 0.f};
}

inline PlanePoint plane_point(const GaussianScene& scene, Index i, float min_flatness) {
  const auto [n, phi] = normal_and_flatness(scene, i);
  const float t = std::exp(std::min({scene.log_scale[0][i], scene.log_scale[1][i], scene.log_scale[2][i]}));
  PlanePoint p{scene.mu(i), n, t, phi >= min_flatness && std::isfinite(t)};
  p.A = scene.R(i);
  for (int d = 0; d < 3; ++d) p.A.col(d) *= std::exp(scene.log_scale[d][i]);
  return p;
}

// The coplanarity test of Eq. R10 for a (candidate) and b (neighbour), within distance r.
inline bool coplanar(const PlanePoint& a, const PlanePoint& b, float r, float cos_alpha, float slab) {
  const Eigen::Vector3f d = b.mu - a.mu;
  return d.squaredNorm() <= r * r && std::abs(a.n.dot(b.n)) >= cos_alpha &&
         std::abs(a.n.dot(d)) <= slab * (a.t + b.t);
}

// E_i of Eq. R10: b, a disc at least beta from a's plane, reaches it within edge_sigma of its
// extent along a's normal (and lies within distance r).
inline bool reaches_edge_on(const PlanePoint& a, const PlanePoint& b, float r, float edge_cos, float edge_sigma) {
  const Eigen::Vector3f d = b.mu - a.mu;
  if (d.squaredNorm() > r * r || std::abs(a.n.dot(b.n)) > edge_cos) return false;
  const float h = a.n.dot(d);
  return h * h <= edge_sigma * edge_sigma * (b.A.transpose() * a.n).squaredNorm();
}

// Directions binned on the cube: 6 faces of k x k cells (a direction's face is its largest
// component's axis and sign, its cell the other two components over that one), and one bin for
// directions that are not finite. A bin's directions lie within radius(b) of its centre (the
// farthest of the cell's corners), so a bin whose centre's line lies farther than alpha +
// radius from a normal's line holds no normal within alpha of it: R10's background points are
// kept by bin in each grid cell, and a candidate skips the bins that cannot be coplanar with it.
struct NormalBins {
  static constexpr int k = 4, count = 6 * k * k + 1, not_finite = count - 1;
  using Set = std::array<std::uint64_t, (count + 63) / 64>;

  static int of(const Eigen::Vector3f& n) {
    if (!n.allFinite()) return not_finite;
    int a = 0;
    for (int d = 1; d < 3; ++d)
      if (std::abs(n[d]) > std::abs(n[a])) a = d;
    const float m = std::abs(n[a]);
    if (!(m > 0.f)) return not_finite;
    auto cell = [&](float t) { return std::clamp(static_cast<int>(std::floor((t / m + 1.f) * 0.5f * k)), 0, k - 1); };
    const int face = 2 * a + (n[a] < 0.f);
    return (face * k + cell(n[(a + 2) % 3])) * k + cell(n[(a + 1) % 3]);
  }
  // cos(alpha + radius(b)) per bin (0 where that reaches past 90 degrees; -1 for the non-finite
  // bin): what near() compares with.
  using Cosines = std::array<float, count>;
  static Cosines cosines(float alpha) {
    Cosines c{};
    const auto& t = table();
    for (int b = 0; b < count; ++b) {
      const double reach = alpha + t.radius[static_cast<std::size_t>(b)];
      c[static_cast<std::size_t>(b)] = b == not_finite ? -1.f : reach >= 1.5707963 ? 0.f : static_cast<float>(std::cos(reach));
    }
    return c;
  }
  // The bins that may hold a direction within alpha of +-n (c = cosines(alpha)): every bin when n
  // is not finite, and always the non-finite one.
  static Set near(const Eigen::Vector3f& n, const Cosines& c) {
    Set out{};
    const auto& t = table();
    const bool finite = n.allFinite();
    const float norm = finite ? n.norm() : 0.f;
    for (int b = 0; b < count; ++b) {
      const std::size_t u = static_cast<std::size_t>(b);
      if (!finite || c[u] <= 0.f || std::abs(n.dot(t.centre[u])) >= c[u] * norm - 1e-4f)
        out[u / 64] |= std::uint64_t{1} << (u % 64);
    }
    return out;
  }
  static Set all() {
    Set out{};
    for (int b = 0; b < count; ++b) out[static_cast<std::size_t>(b) / 64] |= std::uint64_t{1} << (b % 64);
    return out;
  }
  static bool in(const Set& s, int b) { return (s[static_cast<std::size_t>(b) / 64] >> (b % 64)) & 1; }

private:
  struct Table {
    std::array<Eigen::Vector3f, count> centre;
    std::array<double, count> radius;
  };
  static const Table& table() {
    static const Table t = [] {
      Table t{};
      for (int face = 0; face < 6; ++face)
        for (int iv = 0; iv < k; ++iv)
          for (int iu = 0; iu < k; ++iu) {
            const int a = face / 2;
            auto direction = [&](double u, double v) {  // face point (u, v) as a unit vector
              Eigen::Vector3d d;
              d[a] = face % 2 ? -1.0 : 1.0;
              d[(a + 1) % 3] = -1.0 + 2.0 * u / k;
              d[(a + 2) % 3] = -1.0 + 2.0 * v / k;
              return d.normalized();
            };
            const std::size_t b = static_cast<std::size_t>((face * k + iv) * k + iu);
            const Eigen::Vector3d c = direction(iu + 0.5, iv + 0.5);
            double r = 0.0;
            for (int corner = 0; corner < 4; ++corner)
              r = std::max(r, std::acos(std::clamp(c.dot(direction(iu + corner % 2, iv + corner / 2)), -1.0, 1.0)));
            t.centre[b] = c.cast<float>();
            t.radius[b] = r + 1e-3;  // and a margin for rounding
          }
      t.centre[not_finite] = Eigen::Vector3f::Zero();
      t.radius[not_finite] = 4.0;
      return t;
    }();
    return t;
  }
};

}  // namespace detail

// Eq. R10 on `selected` (ascending scene indices): the positions k into `selected` whose
// Gaussian is background by R10, ascending. `seen(i)`: scene Gaussian i was seen unoccluded in
// some training view. Deterministic for any thread count.
template <class Seen>
std::vector<std::size_t> coplanar_background(const GaussianScene& scene, std::span<const Index> selected,
                                             Seen&& seen, const CoplanarParams& p) {
  std::vector<std::size_t> out;
  if (!(p.radius > 0.f) || selected.empty()) return out;
  const RobustCentre rc = robust_centre(scene, selected);
  const float r = p.radius * rc.max_inlier_distance;
  if (!(r > 0.f) || !std::isfinite(r)) return out;
  const float cos_alpha = std::cos(p.angle_deg * 3.14159265358979f / 180.f);
  auto is_selected = [&](Index i) { return std::binary_search(selected.begin(), selected.end(), i); };

  // Seen flat Gaussians within D + r of the centre, in two dense grids (background, selected)
  // of cells of side r / 4 (counting sort, ascending scene index within a cell): a ball of
  // radius r lies in the 9 x 9 rows of 9 cells around its centre's cell. (Side r / 2 took about
  // 1.7 times as long, r / 8 spent more on cells than it saved: docs/notes/default-cost-2026-12-04.md.)
  constexpr int span = 4;
  const float reach = rc.max_inlier_distance + r, cell = r / static_cast<float>(span);
  const int dim = static_cast<int>(std::ceil(2.f * reach / cell)) + 1;
  const Eigen::Vector3f origin = rc.c - Eigen::Vector3f::Constant(reach);
  auto cell_index = [&](const Eigen::Vector3f& m, int axis) {
    return std::clamp(static_cast<int>(std::floor((m[axis] - origin[axis]) / cell)), 0, dim - 1);
  };
  auto flat_index = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * dim + y) * dim + x; };
  struct Grid {
    std::vector<std::uint32_t> start;      // per cell: its first run
    std::vector<std::uint32_t> run_begin;  // per run (of one normal bin in one cell): its first point; then the end
    std::vector<std::uint8_t> run_bin;     // per run: its normal bin (detail::NormalBins)
    std::vector<detail::PlanePoint> points;
    float t_max = 0.f, s_max = 0.f;  // largest thickness, largest scale of its points
  };
  // [0] background, [2] selected; ascending index.
  std::vector<detail::PlanePoint> members[4];
  for (std::size_t i = 0; i < scene.size(); ++i) {
    if ((scene.mu(i) - rc.c).squaredNorm() > reach * reach || !seen(static_cast<Index>(i))) continue;
    detail::PlanePoint q = detail::plane_point(scene, static_cast<Index>(i), p.min_flatness);
    if (q.flat) members[is_selected(static_cast<Index>(i)) ? 2 : 0].push_back(std::move(q));
  }
  // A candidate's slab is as thick as the thickest background point (B) and the largest
  // selected extent (E_i): a few outliers would widen every candidate's slab over the whole
  // neighbourhood. So the thickest (largest) tenth of each set goes into a grid of its own,
  // [1] and [3], searched with its own slab: the same points and tests, fewer cells visited.
  auto extent = [](const detail::PlanePoint& q) { return std::max({q.A.col(0).norm(), q.A.col(1).norm(), q.A.col(2).norm()}); };
  auto split_largest_tenth = [](std::vector<detail::PlanePoint>& all, std::vector<detail::PlanePoint>& large, auto key) {
    if (all.size() < 10) return;
    std::vector<float> v(all.size());
    for (std::size_t j = 0; j < v.size(); ++j) v[j] = key(all[j]);
    const auto cut = v.begin() + static_cast<std::ptrdiff_t>(v.size() * 9 / 10);
    std::nth_element(v.begin(), cut, v.end());
    std::vector<detail::PlanePoint> rest;
    for (detail::PlanePoint& q : all) (key(q) < *cut ? rest : large).push_back(std::move(q));
    all = std::move(rest);
  };
  split_largest_tenth(members[0], members[1], [](const detail::PlanePoint& q) { return q.t; });
  split_largest_tenth(members[2], members[3], extent);
  auto cell_of = [&](const Eigen::Vector3f& m) { return flat_index(cell_index(m, 0), cell_index(m, 1), cell_index(m, 2)); };
  Grid grid[4];
  for (int g = 0; g < 4; ++g) {
    std::vector<std::uint32_t> first(static_cast<std::size_t>(dim) * dim * dim + 1, 0);  // per cell: first point
    for (const detail::PlanePoint& q : members[g]) ++first[cell_of(q.mu) + 1];
    for (std::size_t c = 1; c < first.size(); ++c) first[c] += first[c - 1];
    grid[g].points.resize(members[g].size());
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (const detail::PlanePoint& q : members[g]) {
      grid[g].points[next[cell_of(q.mu)]++] = q;
      grid[g].t_max = std::max(grid[g].t_max, q.t);
      grid[g].s_max = std::max(grid[g].s_max, extent(q));
    }
    // Within each cell, the points by normal bin (ascending index within a bin), one run per bin.
    grid[g].start.assign(first.size(), 0);
    std::vector<std::pair<int, std::uint32_t>> order;
    std::vector<detail::PlanePoint> sorted;
    for (std::size_t c = 0; c + 1 < first.size(); ++c) {
      grid[g].start[c] = static_cast<std::uint32_t>(grid[g].run_bin.size());
      order.clear();
      for (std::uint32_t e = first[c]; e < first[c + 1]; ++e) order.push_back({detail::NormalBins::of(grid[g].points[e].n), e});
      std::sort(order.begin(), order.end());
      sorted.clear();
      for (std::size_t e = 0; e < order.size(); ++e) {
        if (e == 0 || order[e].first != order[e - 1].first) {
          grid[g].run_begin.push_back(first[c] + static_cast<std::uint32_t>(e));
          grid[g].run_bin.push_back(static_cast<std::uint8_t>(order[e].first));
        }
        sorted.push_back(grid[g].points[order[e].second]);
      }
      std::copy(sorted.begin(), sorted.end(), grid[g].points.begin() + first[c]);
    }
    grid[g].start.back() = static_cast<std::uint32_t>(grid[g].run_bin.size());
    grid[g].run_begin.push_back(static_cast<std::uint32_t>(grid[g].points.size()));
  }
  // f(point) for every point of grid g in the cells within r of a (the cell's box nearer than r
  // to mu_a) that meet the slab |n_a . (x - mu_a)| <= w (the cell's box: centre c,
  // |n_a . (x - c)| <= cell / 2 sum_d |n_a,d|; a point of a skipped cell lies farther from mu_a
  // than r or from a's plane than w, by a margin for rounding), until f returns false.
  auto for_each_near = [&](const Grid& g, const detail::PlanePoint& a, float w, const detail::NormalBins::Set& bins,
                           auto&& f) {
    const int cx = cell_index(a.mu, 0), cy = cell_index(a.mu, 1), cz = cell_index(a.mu, 2);
    const float half = 0.5f * cell * (std::abs(a.n.x()) + std::abs(a.n.y()) + std::abs(a.n.z())) * 1.001f + w;
    const float h0 = a.n.dot(origin - a.mu + Eigen::Vector3f::Constant(0.5f * cell));  // cell (0, 0, 0)'s centre
    auto gap2 = [&](int i, int axis) {  // squared distance from mu_a to cell row i along the axis
      const float lo = origin[axis] + cell * static_cast<float>(i), m = a.mu[axis];
      const float g = m < lo ? lo - m : std::max(0.f, m - lo - cell);
      return g * g;
    };
    const float r2 = r * r * 1.001f;
    for (int z = std::max(cz - span, 0); z <= std::min(cz + span, dim - 1); ++z) {
      const float gz = gap2(z, 2);
      if (gz > r2) continue;
      for (int y = std::max(cy - span, 0); y <= std::min(cy + span, dim - 1); ++y) {
        const float gyz = gap2(y, 1) + gz;
        if (gyz > r2) continue;
        for (int x = std::max(cx - span, 0); x <= std::min(cx + span, dim - 1); ++x) {
          if (gap2(x, 0) + gyz > r2) continue;
          const float h = h0 + cell * (a.n.x() * static_cast<float>(x) + a.n.y() * static_cast<float>(y) + a.n.z() * static_cast<float>(z));
          if (std::abs(h) > half) continue;
          const std::size_t c = flat_index(x, y, z);
          for (std::uint32_t run = g.start[c]; run < g.start[c + 1]; ++run) {
            if (!detail::NormalBins::in(bins, g.run_bin[run])) continue;
            for (std::uint32_t e = g.run_begin[run]; e < g.run_begin[run + 1]; ++e)
              if (!f(g.points[e])) return;
          }
        }
      }
    }
  };

  const detail::NormalBins::Cosines bin_cosines = detail::NormalBins::cosines(p.angle_deg * 3.14159265358979f / 180.f);
  const detail::NormalBins::Set every_bin = detail::NormalBins::all();
  std::vector<std::uint8_t> drop(selected.size(), 0);
  parallel_for(static_cast<std::int64_t>(selected.size()), [&](std::int64_t kk) {
    const auto k = static_cast<std::size_t>(kk);
    const Index i = selected[k];
    if (seen(i)) return;  // (so i is in neither grid)
    const detail::PlanePoint a = detail::plane_point(scene, i, p.min_flatness);
    if (!a.flat) return;
    long B = 0, S = 0;
    // Coplanar points lie within slab (t_a + t_max) of a's plane, with a normal in a bin near
    // a's; edge-on ones reach it within edge_sigma times their largest scale.
    const detail::NormalBins::Set near = detail::NormalBins::near(a.n, bin_cosines);
    for (int g = 0; g <= 1; ++g)
      for_each_near(grid[g], a, p.slab * (a.t + grid[g].t_max), near,
                    [&](const detail::PlanePoint& q) { return B += detail::coplanar(a, q, r, cos_alpha, p.slab), true; });
    if (B == 0) return;  // no seen background plane: kept, whatever S
    // S is counted only until it reaches B: i is kept from then on (the same verdict, less work).
    for (int g = 2; g <= 3 && S < B; ++g) {
      const float w = std::max(p.slab * (a.t + grid[g].t_max), p.edge_sigma * grid[g].s_max);
      for_each_near(grid[g], a, w, every_bin, [&](const detail::PlanePoint& q) {
        S += detail::coplanar(a, q, r, cos_alpha, p.slab) || detail::reaches_edge_on(a, q, r, p.edge_cos, p.edge_sigma);
        return S < B;
      });
    }
    drop[k] = B > S;                                                                      // Eq. R10
  });
  for (std::size_t k = 0; k < selected.size(); ++k)
    if (drop[k]) out.push_back(k);
  return out;
}

}  // namespace vcar
