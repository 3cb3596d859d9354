#include <catch2/catch.hpp>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <random>
#include <vector>

#include "vcar/core/simd.hpp"  // first: it keeps GCC 12 quiet about its own AVX-512 headers (bug 105593)
#include <Eigen/Eigenvalues>

#include "vcar/algo/abr_geometry.hpp"
#include "vcar/core/rotation.hpp"

namespace {

struct RandomGaussian {
  Eigen::Vector3f mu, s;
  Eigen::Matrix3f R;
};

// Means in [-2, 2]^3 (some behind or beside the camera: the tests put it inside the cube), scales 0.005-0.5, random rotations; every
// 16th is a needle (one scale 100x the others).
std::vector<RandomGaussian> random_gaussians(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.f, 1.f), L(std::log(0.005f), std::log(0.5f));
  std::vector<RandomGaussian> g(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    auto& x = g[static_cast<std::size_t>(i)];
    x.mu = 2.f * Eigen::Vector3f(U(rng), U(rng), U(rng));
    x.s = Eigen::Vector3f(std::exp(L(rng)), std::exp(L(rng)), std::exp(L(rng)));
    if (i % 16 == 0) x.s[0] = 100.f * x.s[1];
    x.R = vcar::rotation_from_quaternion(U(rng), U(rng), U(rng), U(rng) + 0.01f);
  }
  return g;
}

// Columns of simd::width Gaussians starting at g[i] (SoA, as BoundaryRefinement keeps them).
struct Columns {
  static constexpr std::size_t L = vcar::simd::width;
  alignas(64) float c[15][L];  // x, y, z, R column-major, s
  Columns(const std::vector<RandomGaussian>& g, std::size_t i) {
    for (std::size_t l = 0; l < L; ++l) {
      const RandomGaussian& x = g[std::min(g.size() - 1, i + l)];
      for (int d = 0; d < 3; ++d) c[d][l] = x.mu[d], c[12 + d][l] = x.s[d];
      for (int e = 0; e < 9; ++e) c[3 + e][l] = x.R(e % 3, e / 3);
    }
  }
  void geometry(const vcar::AbrCamera& C, vcar::AbrBatch& out) const {
    const float* const rot[9] = {c[3], c[4], c[5], c[6], c[7], c[8], c[9], c[10], c[11]};
    const float* const s[3] = {c[12], c[13], c[14]};
    vcar::abr_geometry(C, c[0], c[1], c[2], rot, s, 3.f, out);
  }
};

// A 320 x 240 view with fx != fy and an off-centre principal point, looking at the cube of
// random_gaussians from inside it (some Gaussians behind it, many beside the image).
vcar::Camera oblique_camera() {
  const vcar::Intrinsics k{320, 240, 260.f, 250.f, 161.3f, 118.7f};
  return vcar::Camera::look_at({0.4f, 0.3f, -0.8f}, {0, 0, 0}, {0, 1, 0}, k, "v");
}

// f(b, l, g) for every Gaussian g of gs: lane l of the batch b that abr_geometry computed for it.
template <class F>
void for_each_lane(const std::vector<RandomGaussian>& gs, const vcar::AbrCamera& C, F&& f) {
  for (std::size_t i = 0; i < gs.size(); i += vcar::simd::width) {
    const Columns cols(gs, i);
    vcar::AbrBatch b;
    cols.geometry(C, b);
    for (std::size_t l = 0; l < vcar::simd::width && i + l < gs.size(); ++l) f(b, l, gs[i + l]);
  }
}

}  // namespace

TEST_CASE("symmetric_eigen2 matches a brute-force eigen solver") {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> U(-5.f, 5.f);
  for (int t = 0; t < 500; ++t) {
    Eigen::Matrix2f A;
    A << U(rng), U(rng), U(rng), U(rng);
    Eigen::Matrix2f S = A * A.transpose();
    if (t % 50 == 0) S = Eigen::Matrix2f::Identity() * 2.f;            // isotropic
    if (t % 50 == 1) { S(0, 1) = S(1, 0) = 0.f; }                      // diagonal
    const vcar::SymmetricEigen2 E = vcar::symmetric_eigen2(S);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> ref(S.cast<double>());
    const double scale = std::max(1.0, ref.eigenvalues()(1));
    CHECK(E.lambda1 == Approx(ref.eigenvalues()(1)).margin(1e-5 * scale));
    CHECK(E.lambda2 == Approx(ref.eigenvalues()(0)).margin(1e-5 * scale));
    CHECK(E.lambda1 >= E.lambda2);
    CHECK(E.e1.norm() == Approx(1).epsilon(1e-5));
    CHECK(E.e1.dot(E.e2) == Approx(0).margin(1e-6));
    CHECK((S * E.e1 - E.lambda1 * E.e1).norm() <= 1e-4 * scale);
    CHECK((S * E.e2 - E.lambda2 * E.e2).norm() <= 1e-4 * scale);
  }
}

TEST_CASE("abr_geometry: every lane as project_gaussian computes it (Eq. 10, B.7), Eq. 9's eigenpairs and endpoints") {
  const auto gs = random_gaussians(800, 7);
  const vcar::Camera cam = oblique_camera();
  const vcar::ProjectionParams pp;
  const vcar::AbrCamera C = vcar::AbrCamera::from(cam, pp);
  int front = 0, behind = 0;
  for_each_lane(gs, C, [&](const vcar::AbrBatch& b, std::size_t l, const RandomGaussian& x) {
    const vcar::ProjectedGaussian g = vcar::project_gaussian(cam, x.mu, x.R, x.s, 1.f, pp);
    const bool in_front = g.depth >= pp.near_plane && g.depth <= pp.far_plane;
    CHECK((b.front[l] > 0.f) == in_front);  // rule (e)
    if (!in_front) { ++behind; return; }
    ++front;
    CHECK(b.mx[l] == Approx(g.mean.x()).epsilon(1e-5).margin(1e-3));
    CHECK(b.my[l] == Approx(g.mean.y()).epsilon(1e-5).margin(1e-3));
    const Eigen::Matrix2d S = g.Sigma2D.cast<double>();
    const double scale = S.norm();
    for (int d = 0; d < 3; ++d) {
      CHECK((b.q(d, l) - g.q[d]).norm() <= 1e-4 * (1.0 + g.q[d].norm()));
    }
    CHECK(b.det[l] == Approx(S.determinant()).margin(1e-4 * scale * scale));
    CHECK(b.lambda1[l] + b.lambda2[l] == Approx(S.trace()).margin(1e-5 * scale));
    const Eigen::Vector2d e1(b.e1x[l], b.e1y[l]);
    CHECK(e1.norm() == Approx(1).epsilon(1e-5));
    CHECK((S * e1 - b.lambda1[l] * e1).norm() <= 1e-4 * scale);  // Eq. 9: e1 is the major axis
    // Eq. 9's endpoints: m + a e1, m - a e1, m + b e2, m - b e2 with a = 3 sqrt(lambda1),
    // b = 3 sqrt(lambda2), e2 = (-e1.y, e1.x) (up to the rounding of m + len u in float).
    const Eigen::Vector2d e2(-e1.y(), e1.x());
    const double tol = 1e-3 + 1e-6 * (std::abs(b.mx[l]) + std::abs(b.my[l]));
    for (int k = 0; k < 4; ++k) {
      const double len = 3.0 * std::sqrt(std::max(0.0, static_cast<double>(k < 2 ? b.lambda1[l] : b.lambda2[l])));
      CHECK(b.axis[k / 2][l] == Approx(len).epsilon(1e-5));
      const Eigen::Vector2d expect = (k % 2 ? -len : len) * (k < 2 ? e1 : e2);
      const Eigen::Vector2d d(b.ex[k][l] - static_cast<double>(b.mx[l]), b.ey[k][l] - static_cast<double>(b.my[l]));
      CHECK((d - expect).norm() <= tol * (1.0 + len));
    }
  });
  CHECK(front > 300);  // both outcomes are exercised
  CHECK(behind > 100);
}

TEST_CASE("abr_geometry: a lane's bits do not depend on the other lanes") {
  // observe_gaussian computes one Gaussian broadcast to every lane, BoundaryRefinement a run of
  // candidates: both must see the same bits for BoundaryRefinement to equal observe_gaussian.
  const auto gs = random_gaussians(200, 11);
  const vcar::Intrinsics k{200, 150, 170.f, 170.f, 100.f, 75.f};
  const vcar::AbrCamera C = vcar::AbrCamera::from(vcar::Camera::look_at({3.f, 1.f, -3.f}, {0, 0, 0}, {0, 1, 0}, k, "v"), {});
  int differing = 0;
  for (std::size_t i = 0; i < gs.size(); i += vcar::simd::width) {
    vcar::AbrBatch run;
    Columns(gs, i).geometry(C, run);
    for (std::size_t l = 0; l < vcar::simd::width && i + l < gs.size(); ++l) {
      const std::vector<RandomGaussian> one(1, gs[i + l]);
      vcar::AbrBatch alone;
      Columns(one, 0).geometry(C, alone);
      auto same = [&](const float* a, const float* b) { return std::bit_cast<std::uint32_t>(a[l]) == std::bit_cast<std::uint32_t>(b[0]); };
      bool ok = same(run.front, alone.front) && same(run.mx, alone.mx) && same(run.my, alone.my) && same(run.det, alone.det) &&
                same(run.lambda1, alone.lambda1) && same(run.lambda2, alone.lambda2) && same(run.e1x, alone.e1x) &&
                same(run.e1y, alone.e1y) && same(run.axis[0], alone.axis[0]) && same(run.axis[1], alone.axis[1]);
      for (int d = 0; d < 3; ++d) ok = ok && same(run.qx[d], alone.qx[d]) && same(run.qy[d], alone.qy[d]);
      for (int k = 0; k < 4; ++k) ok = ok && same(run.ex[k], alone.ex[k]) && same(run.ey[k], alone.ey[k]);
      differing += !ok;
    }
  }
  CHECK(differing == 0);
}

TEST_CASE("lambda1_bound: bounds Eq. 10's lambda_1 over a rectangle of centres, and is exact at the principal point") {
  const auto gs = random_gaussians(2000, 11);
  const vcar::Camera cam = oblique_camera();
  const vcar::ProjectionParams pp;
  const vcar::AbrCamera C = vcar::AbrCamera::from(cam, pp);
  int tested = 0, beside = 0;
  double tightest = 0;  // largest lambda_1 / bound seen
  for_each_lane(gs, C, [&](const vcar::AbrBatch& b, std::size_t l, const RandomGaussian& x) {
    if (!(b.front[l] > 0.f)) return;
    const Eigen::Vector3f t = cam.R_w * x.mu + cam.t_w;
    const float s2 = x.s.cwiseAbs2().maxCoeff();
    // The Gaussian's own centre as the rectangle, and a wider rectangle around it.
    const float bound = vcar::lambda1_bound(C, b.mx[l], b.my[l], b.mx[l], b.my[l], t.z(), s2);
    const float wider = vcar::lambda1_bound(C, b.mx[l] - 40.f, b.my[l] - 3.f, b.mx[l] + 5.f, b.my[l] + 30.f, 0.9f * t.z(), s2);
    CHECK(b.lambda1[l] <= bound * (1.f + 1e-5f));
    CHECK(bound <= wider);
    tightest = std::max(tightest, static_cast<double>(b.lambda1[l]) / bound);
    beside += b.mx[l] < 0.f || b.mx[l] > 320.f || b.my[l] < 0.f || b.my[l] > 240.f;  // clamped Jacobian
    ++tested;
  });
  CHECK(tested > 500);
  CHECK(beside > 20);
  CHECK(tightest > 0.9);  // not a loose bound: some Gaussians come close to it
  // At the principal point (a = b = 0) with fx = fy and an isotropic Gaussian, J J^T = (f/z)^2 I:
  // lambda_1 = (f/z)^2 s^2 + eps2d, the bound exactly. By hand: f = 250, z = 2, s = 0.1.
  const vcar::Intrinsics k2{320, 240, 250.f, 250.f, 160.f, 120.f};
  const vcar::AbrCamera C2 = vcar::AbrCamera::from(vcar::Camera::look_at({0, 0, -2}, {0, 0, 0}, {0, 1, 0}, k2, "c"), pp);
  CHECK(vcar::lambda1_bound(C2, 160.f, 120.f, 160.f, 120.f, 2.f, 0.01f) == Approx(125.f * 125.f * 0.01f + 0.3f));
  // Off axis, by hand: u = 160 + 125 (a = 0.5), v = 120 (b = 0): (f/z)^2 (1 + 0.25) s^2 + eps2d.
  CHECK(vcar::lambda1_bound(C2, 285.f, 120.f, 285.f, 120.f, 2.f, 0.01f) == Approx(156.25f * 1.25f + 0.3f));
}
