#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <set>

#include <Eigen/Geometry>

#include "vcar/algo/coplanar_background.hpp"
#include "vcar/algo/params.hpp"

using vcar::Index;

namespace {
// A flat disc at `mu`: scales (a, a, t) in its own frame, its normal the local z rotated by
// `tilt_deg` about the world x axis.
void put_disc(vcar::GaussianScene& s, std::size_t i, const Eigen::Vector3f& mu, float a, float t, float tilt_deg = 0.f) {
  const float h = 0.5f * tilt_deg * 3.14159265f / 180.f;
  s.set(i, mu, Eigen::Vector3f(std::log(a), std::log(a), std::log(t)), {std::cos(h), std::sin(h), 0, 0}, 0.f);
}
}  // namespace

TEST_CASE("Eq. R10 normal and flatness by hand: the smallest axis, 1 - s_a / s_b") {
  vcar::GaussianScene s;
  s.resize(4);
  put_disc(s, 0, {0, 0, 0}, 1.f, 0.01f);  // disc: n = z, phi = 1 - 0.01 / 1 = 0.99
  const auto [n0, phi0] = vcar::detail::normal_and_flatness(s, 0);
  CHECK(n0.isApprox(Eigen::Vector3f::UnitZ()));
  CHECK(phi0 == Approx(0.99f));
  put_disc(s, 1, {0, 0, 0}, 1.f, 0.01f, 90.f);  // the same disc turned 90 degrees about x: n = +-y
  CHECK(vcar::detail::normal_and_flatness(s, 1).first.cwiseAbs().isApprox(Eigen::Vector3f::UnitY(), 1e-5f));
  // Scales (1, 0.5, 0.25): smallest axis z, s_b = 0.5, phi = 1 - 0.25 / 0.5 = 0.5.
  s.set(2, Eigen::Vector3f::Zero(), Eigen::Vector3f(0.f, std::log(0.5f), std::log(0.25f)), {1, 0, 0, 0}, 0.f);
  CHECK(vcar::detail::normal_and_flatness(s, 2).second == Approx(0.5f));
  // A ball and a needle have no plane: phi = 0 (the needle's two small axes are equal).
  s.set(3, Eigen::Vector3f::Zero(), Eigen::Vector3f(0.f, std::log(0.01f), std::log(0.01f)), {1, 0, 0, 0}, 0.f);
  CHECK(vcar::detail::normal_and_flatness(s, 3).second == Approx(0.f).margin(1e-6));
  put_disc(s, 3, {0, 0, 0}, 0.2f, 0.2f);
  CHECK(vcar::detail::normal_and_flatness(s, 3).second == Approx(0.f).margin(1e-6));
}

TEST_CASE("Eq. R10 coplanarity by hand: distance, angle and slab") {
  vcar::detail::PlanePoint a{{0, 0, 0}, {0, 0, 1}, 0.01f, true};
  const float cos5 = std::cos(5.f * 3.14159265f / 180.f);
  vcar::detail::PlanePoint b{{0.5f, 0, 0.015f}, {0, 0, 1}, 0.01f, true};
  CHECK(vcar::detail::coplanar(a, b, 0.6f, cos5, 1.f));         // |n.d| = 0.015 <= 1 (0.01 + 0.01)
  CHECK_FALSE(vcar::detail::coplanar(a, b, 0.6f, cos5, 0.5f));  // 0.015 > 0.5 (0.02)
  CHECK_FALSE(vcar::detail::coplanar(a, b, 0.45f, cos5, 1.f));  // |d| = 0.5002 > 0.45
  b.mu.z() = 0.f;
  b.n = Eigen::Vector3f(0, std::sin(0.1f), std::cos(0.1f));      // 5.7 degrees apart
  CHECK_FALSE(vcar::detail::coplanar(a, b, 0.6f, cos5, 1.f));
  b.n = -Eigen::Vector3f(0, std::sin(0.08f), std::cos(0.08f));   // 4.6 degrees, flipped: a normal has no sign
  CHECK(vcar::detail::coplanar(a, b, 0.6f, cos5, 1.f));
}

TEST_CASE("Eq. R10 by hand: a hidden flat candidate takes the majority of its seen coplanar neighbours") {
  // Candidate 0 (hidden, flat, at the origin, normal z), seen neighbours in its plane: selected
  // ones (1..S) and background ones (S+1..S+B), one seen background disc tilted 30 degrees and
  // one 0.05 above the plane (neither counts), and one selected seen disc far out that sets D.
  auto run = [](int S, int B) {
    vcar::GaussianScene s;
    const std::size_t n = 1 + S + B + 3;
    s.resize(n);
    put_disc(s, 0, {0, 0, 0}, 0.05f, 0.001f);
    std::vector<Index> selected{0};
    std::size_t i = 1;
    for (int k = 0; k < S; ++k, ++i) { put_disc(s, i, {0.1f * (k + 1), 0.1f, 0}, 0.05f, 0.001f); selected.push_back(static_cast<Index>(i)); }
    for (int k = 0; k < B; ++k, ++i) put_disc(s, i, {-0.1f * (k + 1), -0.1f, 0}, 0.05f, 0.001f);
    put_disc(s, i++, {0, 0.2f, 0}, 0.05f, 0.001f, 30.f);  // tilted
    put_disc(s, i++, {0, -0.2f, 0.05f}, 0.05f, 0.001f);   // off the plane
    put_disc(s, i, {0, 0, 1.f}, 0.05f, 0.001f);           // far, selected
    selected.push_back(static_cast<Index>(i));
    vcar::CoplanarParams p;
    p.radius = 10.f;  // the whole scene is near
    auto seen = [](Index j) { return j != 0; };
    return vcar::coplanar_background(s, selected, seen, p);
  };
  CHECK(run(0, 1) == std::vector<std::size_t>{0});  // B 1 > S 0
  CHECK(run(2, 3) == std::vector<std::size_t>{0});
  CHECK(run(3, 3).empty());                         // a tie keeps it
  CHECK(run(3, 2).empty());
  CHECK(run(0, 0).empty());                         // no seen plane: kept (only the tilted / lifted discs)
}

TEST_CASE("Eq. R10 keeps seen, curved and non-flat candidates, and is off at radius 0") {
  vcar::GaussianScene s;
  s.resize(6);
  put_disc(s, 0, {0, 0, 0}, 0.05f, 0.001f);          // hidden flat: dropped (neighbours 3, 4)
  put_disc(s, 1, {0.02f, 0, 0}, 0.05f, 0.04f);        // hidden, flatness 0.2 < 0.5: no plane
  put_disc(s, 2, {0, 0.02f, 0}, 0.05f, 0.001f);       // seen: never dropped
  put_disc(s, 3, {0.1f, 0, 0}, 0.05f, 0.001f);        // seen background
  put_disc(s, 4, {-0.1f, 0, 0}, 0.05f, 0.001f);       // seen background
  put_disc(s, 5, {0, 0, 0.5f}, 0.05f, 0.001f, 90.f);  // selected, sets D
  const std::vector<Index> selected{0, 1, 2, 5};
  auto seen = [](Index j) { return j >= 2; };
  vcar::CoplanarParams p;
  p.radius = 1.f;
  CHECK(vcar::coplanar_background(s, selected, seen, p) == std::vector<std::size_t>{0});
  p.radius = 0.f;
  CHECK(vcar::coplanar_background(s, selected, seen, p).empty());
}

TEST_CASE("Eq. R10 drops the hidden table patch under an object and nothing of the object") {
  // A table of discs (z = 0, spacing 0.05) seen everywhere except the patch |x|, |y| <= 0.2 under
  // an object; the object: a ring of vertical discs (seen) and, hidden, discs at its foot tilted
  // 40 degrees. Selected: the object and the hidden patch (as the fine vote would).
  vcar::GaussianScene s;
  std::vector<Eigen::Vector3f> table;
  for (int x = -20; x <= 20; ++x)
    for (int y = -20; y <= 20; ++y) table.push_back({0.05f * x, 0.05f * y, 0});
  const std::size_t nt = table.size(), nobj = 40, nfoot = 20;
  s.resize(nt + nobj + nfoot);
  std::vector<Index> selected;
  std::set<Index> hidden, patch;
  for (std::size_t k = 0; k < nt; ++k) {
    put_disc(s, k, table[k], 0.04f, 0.001f);
    if (std::abs(table[k].x()) <= 0.2f + 1e-4f && std::abs(table[k].y()) <= 0.2f + 1e-4f) {
      selected.push_back(static_cast<Index>(k));
      hidden.insert(static_cast<Index>(k));
      patch.insert(static_cast<Index>(k));
    }
  }
  for (std::size_t k = 0; k < nobj; ++k) {
    const float a = 6.2831853f * static_cast<float>(k) / nobj;
    const std::size_t i = nt + k;
    // A vertical disc on a ring of radius 0.25 at height 0.2: normal radial (rotation about z, then x).
    const Eigen::Vector3f mu(0.25f * std::cos(a), 0.25f * std::sin(a), 0.2f);
    Eigen::Matrix3f R;
    R.col(2) = Eigen::Vector3f(std::cos(a), std::sin(a), 0);
    R.col(0) = Eigen::Vector3f(0, 0, 1);
    R.col(1) = R.col(2).cross(R.col(0));
    const Eigen::Quaternionf q(R);
    s.set(i, mu, Eigen::Vector3f(std::log(0.04f), std::log(0.04f), std::log(0.001f)), {q.w(), q.x(), q.y(), q.z()}, 0.f);
    selected.push_back(static_cast<Index>(i));
  }
  for (std::size_t k = 0; k < nfoot; ++k) {
    const std::size_t i = nt + nobj + k;
    put_disc(s, i, {0.05f * (static_cast<float>(k) - 10.f) / 10.f, 0.25f, 0.01f}, 0.04f, 0.001f, 40.f);
    selected.push_back(static_cast<Index>(i));
    hidden.insert(static_cast<Index>(i));
  }
  std::sort(selected.begin(), selected.end());
  auto seen = [&](Index j) { return !hidden.count(j); };
  // The selection's extent D is about 0.32 (the ring's discs from its centre): radius 1.5 D
  // reaches the seen table from the patch's middle (0.25 away); radius 0.5 D does not.
  auto dropped_at = [&](float radius) {
    vcar::CoplanarParams p;
    p.radius = radius;
    std::set<Index> out;
    for (std::size_t k : vcar::coplanar_background(s, selected, seen, p)) out.insert(selected[k]);
    return out;
  };
  CHECK(dropped_at(1.5f) == patch);
  const std::set<Index> inner = dropped_at(0.5f);
  CHECK(inner.size() < patch.size());
  CHECK_FALSE(inner.count(static_cast<Index>(nt / 2)));  // (0, 0): the nearest seen table is 0.25 away
  CHECK(inner.count(static_cast<Index>(nt / 2 + 4)));    // (0, 0.2): next to the seen table
}

TEST_CASE("VcarParams: R10 needs the coarse occlusion test, and its ranges") {
  vcar::VcarParams p = vcar::VcarParams::robust();
  CHECK(p.coplanar.radius > 0.f);
  CHECK_NOTHROW(p.validate());
  p.evidence.occlusion = false;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("occlusion=true"));
  p = vcar::VcarParams::robust();
  p.coplanar.radius = -1.f;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("coplanar_radius"));
  for (const char* name : {"nvos", "lerf", "reference_code"}) CHECK(vcar::VcarParams::preset(name).coplanar.radius == 0.f);
}

TEST_CASE("Eq. R10 by hand: a seen face of the selection that meets the plane edge-on counts as selected") {
  // Candidate 0 hidden at the origin (normal z), one seen background disc in its plane (B = 1),
  // and a seen vertical disc (normal x, in-plane sigma 0.05: 3-sigma reach 0.15 along z) at
  // height h; a far selected disc sets D.
  auto run = [](float h, bool edge_selected) {
    vcar::GaussianScene s;
    s.resize(4);
    put_disc(s, 0, {0, 0, 0}, 0.05f, 0.001f);
    put_disc(s, 1, {-0.1f, 0, 0}, 0.05f, 0.001f);
    Eigen::Matrix3f R;  // local z -> world x
    R << 0, 0, 1, 0, 1, 0, -1, 0, 0;
    const Eigen::Quaternionf q(R);
    s.set(2, {0.1f, 0, h}, Eigen::Vector3f(std::log(0.05f), std::log(0.05f), std::log(0.001f)), {q.w(), q.x(), q.y(), q.z()}, 0.f);
    put_disc(s, 3, {0, 0, 1.f}, 0.05f, 0.001f, 90.f);
    std::vector<Index> selected{0, 3};
    if (edge_selected) selected = {0, 2, 3};
    vcar::CoplanarParams p;
    p.radius = 10.f;
    return vcar::coplanar_background(s, selected, [](Index j) { return j != 0; }, p);
  };
  CHECK(run(0.1f, true).empty());                          // reaches the plane: S = 1 = B, kept
  CHECK(run(0.2f, true) == std::vector<std::size_t>{0});   // 0.2 > 0.15: B 1 > S 0
  CHECK(run(0.1f, false) == std::vector<std::size_t>{0});  // background edges do not count
  const vcar::detail::PlanePoint a{{0, 0, 0}, {0, 0, 1}, 0.001f, true};
  vcar::detail::PlanePoint b{{0.1f, 0, 0.149f}, {1, 0, 0}, 0.001f, true};
  b.A = Eigen::Vector3f(0.001f, 0.05f, 0.05f).asDiagonal();  // sqrt(n^T Sigma n) = 0.05 along z
  CHECK(vcar::detail::reaches_edge_on(a, b, 1.f, 0.5f, 3.f));
  b.mu.z() = 0.151f;
  CHECK_FALSE(vcar::detail::reaches_edge_on(a, b, 1.f, 0.5f, 3.f));
  b.mu.z() = 0.f;
  b.n = Eigen::Vector3f(0, std::sin(0.9f), std::cos(0.9f));  // 51.6 degrees from a's normal: not edge-on
  CHECK_FALSE(vcar::detail::reaches_edge_on(a, b, 1.f, 0.5f, 3.f));
}

TEST_CASE("Eq. R10 equals its brute force on random discs (the grids and the slab pruning skip nothing)") {
  // 600 discs: three planes of coplanar discs (z = 0, x = 0.3, a tilted one) and random ones;
  // random seen flags and a random selection. The reference checks every pair with the same
  // predicates.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> U(-0.5f, 0.5f);
  const std::size_t n = 600;
  vcar::GaussianScene s;
  s.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3f mu(U(rng), U(rng), U(rng));
    Eigen::Vector3f nrm = Eigen::Vector3f(U(rng), U(rng), U(rng)).normalized();
    const int kind = static_cast<int>(i % 4);
    if (kind == 0) { mu.z() = 0.001f * U(rng); nrm = Eigen::Vector3f(0.02f * U(rng), 0.02f * U(rng), 1).normalized(); }
    if (kind == 1) { mu.x() = 0.3f + 0.001f * U(rng); nrm = Eigen::Vector3f(1, 0.02f * U(rng), 0.02f * U(rng)).normalized(); }
    if (kind == 2) { const Eigen::Vector3f m(1, 1, 1); nrm = (m + 0.02f * Eigen::Vector3f(U(rng), U(rng), U(rng))).normalized(); mu -= m.normalized() * m.normalized().dot(mu); }
    Eigen::Matrix3f R;
    R.col(2) = nrm;
    R.col(0) = nrm.unitOrthogonal();
    R.col(1) = nrm.cross(R.col(0));
    const Eigen::Quaternionf q(R);
    const float thick = (i % 7 == 0) ? 0.03f : 0.002f;  // some are not flat
    s.set(i, mu, Eigen::Vector3f(std::log(0.04f), std::log(0.03f), std::log(thick)), {q.w(), q.x(), q.y(), q.z()}, 0.f);
  }
  std::vector<std::uint8_t> seen_flag(n), sel_flag(n);
  std::vector<Index> selected;
  for (std::size_t i = 0; i < n; ++i) {
    seen_flag[i] = rng() % 2;
    sel_flag[i] = rng() % 3 == 0;
    if (sel_flag[i]) selected.push_back(static_cast<Index>(i));
  }
  auto seen = [&](Index i) { return seen_flag[i] != 0; };
  for (float radius : {0.3f, 0.75f, 1.5f}) {
    vcar::CoplanarParams p;
    p.radius = radius;
    p.angle_deg = 5.f;
    const std::vector<std::size_t> got = vcar::coplanar_background(s, selected, seen, p);
    // Brute force.
    const vcar::RobustCentre rc = vcar::robust_centre(s, selected);
    const float r = radius * rc.max_inlier_distance, reach = rc.max_inlier_distance + r;
    const float cos_alpha = std::cos(p.angle_deg * 3.14159265358979f / 180.f);
    std::vector<std::size_t> want;
    for (std::size_t k = 0; k < selected.size(); ++k) {
      const Index i = selected[k];
      if (seen(i)) continue;
      const auto a = vcar::detail::plane_point(s, i, p.min_flatness);
      if (!a.flat) continue;
      long B = 0, S = 0;
      for (std::size_t j = 0; j < n; ++j) {
        if (!seen_flag[j] || (s.mu(j) - rc.c).squaredNorm() > reach * reach) continue;
        const auto b = vcar::detail::plane_point(s, static_cast<Index>(j), p.min_flatness);
        if (!b.flat) continue;
        if (sel_flag[j]) S += vcar::detail::coplanar(a, b, r, cos_alpha, p.slab) || vcar::detail::reaches_edge_on(a, b, r, p.edge_cos, p.edge_sigma);
        else B += vcar::detail::coplanar(a, b, r, cos_alpha, p.slab);
      }
      if (B > S) want.push_back(k);
    }
    CHECK(got == want);
    CHECK_FALSE(want.empty());  // the case tests something
  }
}

TEST_CASE("Eq. R10's normal bins: a normal within alpha of a candidate's (either sign) is in a bin near it") {
  // The bins only skip: every pair within alpha must be kept, whatever the faces and cells.
  std::mt19937 rng(19);
  std::normal_distribution<float> N(0.f, 1.f);
  using Bins = vcar::detail::NormalBins;
  for (const float alpha_deg : {1.f, 5.f, 20.f}) {
    const float alpha = alpha_deg * 3.14159265f / 180.f;
    const Bins::Cosines cosines = Bins::cosines(alpha);
    std::size_t kept = 0, pairs = 0;
    for (int t = 0; t < 20000; ++t) {
      const Eigen::Vector3f n = Eigen::Vector3f(N(rng), N(rng), N(rng)).normalized();
      // d: n turned by up to alpha about a random axis, and flipped half the time.
      const Eigen::Vector3f axis = n.cross(Eigen::Vector3f(N(rng), N(rng), N(rng))).normalized();
      const float angle = alpha * std::uniform_real_distribution<float>(0.f, 0.999f)(rng);
      Eigen::Vector3f d = Eigen::AngleAxisf(angle, axis) * n;
      if (t % 2) d = -d;
      const Bins::Set near = Bins::near(n, cosines);
      CAPTURE(alpha_deg, n.transpose(), d.transpose());
      REQUIRE(Bins::in(near, Bins::of(d)));
      for (int b = 0; b < Bins::count; ++b) kept += Bins::in(near, b);
      pairs += Bins::count;
    }
    if (alpha_deg <= 5.f) CHECK(kept < pairs / 4);  // and they do skip most bins
  }
  // Directions on the cube's edges and corners, and ones that are not finite.
  for (const Eigen::Vector3f& d : {Eigen::Vector3f(1, 1, 0), Eigen::Vector3f(1, 1, 1), Eigen::Vector3f(0, 0, -1), Eigen::Vector3f(-1, 0, 0)}) {
    const Eigen::Vector3f u = d.normalized();
    CHECK(Bins::in(Bins::near(u, Bins::cosines(0.01f)), Bins::of(u)));
    CHECK(Bins::in(Bins::near(u, Bins::cosines(0.01f)), Bins::of(-u)));
  }
  CHECK(Bins::of(Eigen::Vector3f(NAN, 0, 1)) == Bins::not_finite);
  CHECK(Bins::of(Eigen::Vector3f::Zero()) == Bins::not_finite);
  CHECK(Bins::in(Bins::near(Eigen::Vector3f(0, 0, 1), Bins::cosines(0.01f)), Bins::not_finite));
  const Bins::Set any = Bins::near(Eigen::Vector3f(NAN, 0, 0), Bins::cosines(0.01f));
  for (int b = 0; b < Bins::count; ++b) CHECK(Bins::in(any, b));
}
