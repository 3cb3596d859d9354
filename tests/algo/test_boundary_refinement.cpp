#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <string>

#include <Eigen/Eigenvalues>

#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/incremental_refinement.hpp"
#include "vcar/core/rle_mask.hpp"

namespace {

// Fronto-parallel camera at the origin looking down +z: fx = fy = 100, 200 x 100 px, principal
// point off the pixel grid. A Gaussian at (0, 0, 10) projects to m = (cx, cy) with J = diag(10, 10)
// on the first two axes and a zero third column (tx = ty = 0), so q_d = 10 (x_d, y_d) of r_d.
constexpr double kFx = 100, kZ = 10, kCx = 100.3, kCy = 50.3, kEps2d = 0.3;

vcar::Camera camera(int w = 200, int h = 100, std::string name = "front") {
  vcar::Camera c;
  c.name = std::move(name);
  c.width = w; c.height = h;
  c.fx = c.fy = static_cast<float>(kFx);
  c.cx = static_cast<float>(kCx); c.cy = static_cast<float>(kCy);
  return c;
}

// Foreground where col < edge_col: a straight vertical mask edge at u = edge_col.
vcar::Mask left_part(int edge_col, int w = 200, int h = 100) {
  vcar::Mask m(w, h, 1, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < std::min(edge_col, w); ++x) m(x, y) = 255;
  return m;
}

// One Gaussian at (0, 0, z) with scales s and quaternion q (w, x, y, z).
vcar::GaussianScene one_gaussian(Eigen::Vector3f s, Eigen::Vector4f q = {1, 0, 0, 0}) {
  vcar::GaussianScene g;
  g.resize(1);
  g.set(0, {0.f, 0.f, static_cast<float>(kZ)}, s.array().log(), q, 5.f);
  return g;
}

// Hand computation for the straddling Gaussian: long axis s1 along image u, edge at u = edge.
// w_1 = s1^2 (fx / z)^2 (Eq. 11), lambda1 = w_1 + eps2d, a = 3 sqrt(lambda1) (Eq. 9),
// samples t_k = a k / 128, first exit k* = ceil((edge - cx) 128 / a), l = (k* - 1/2) a / 128,
// f = sqrt(((l/3)^2 - lambda1 + w_1) / w_1) (Eq. 13).
struct Hand {
  double w1, lambda, a, l, f;
};
Hand hand(double s1, double edge) {
  Hand h;
  h.w1 = s1 * s1 * (kFx / kZ) * (kFx / kZ);
  h.lambda = h.w1 + kEps2d;
  h.a = 3.0 * std::sqrt(h.lambda);
  const double k = std::ceil((edge - kCx) * 128.0 / h.a);
  h.l = (k - 0.5) * h.a / 128.0;
  const double num = (h.l / 3.0) * (h.l / 3.0) - h.lambda + h.w1;
  h.f = num > 0 ? std::sqrt(num / h.w1) : -1.0;  // -1: negative numerator
  return h;
}

vcar::AbrResult run(const vcar::GaussianScene& g, const std::vector<vcar::Mask>& masks,
                    vcar::AbrParams p = {}, const vcar::Camera& cam = camera()) {
  vcar::BoundaryRefinement abr(g, {0}, p);
  for (const auto& m : masks) abr.add_view(cam, m);
  return abr.finish();
}

double factor(const vcar::AbrResult& r, const vcar::GaussianScene& g, int d) {
  return std::exp(static_cast<double>(r.log_scale[d][0]) - g.log_scale[d][0]);
}

// 6000 random small Gaussians in a cube seen by 6 ring views with disc masks of growing radius.
struct RingFixture {
  vcar::GaussianScene scene;
  std::vector<vcar::Camera> cams;
  std::vector<vcar::Mask> masks;
};
// n Gaussians with means uniform in [-1, 1]^3, log-scales uniform in [log_lo, log_hi], random rotations.
vcar::GaussianScene random_gaussians(int n, unsigned seed, float log_lo, float log_hi) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.f, 1.f), L(log_lo, log_hi);
  vcar::GaussianScene g;
  g.resize(n);
  for (int i = 0; i < n; ++i)
    g.set(i, {U(rng), U(rng), U(rng)}, {L(rng), L(rng), L(rng)}, {U(rng), U(rng), U(rng), U(rng) + 0.01f}, 0.f);
  return g;
}

RingFixture ring_fixture() {
  RingFixture f;
  f.scene = random_gaussians(6000, 3, -4.f, -2.f);
  const vcar::Intrinsics k{160, 120, 150.f, 150.f, 80.f, 60.f};
  for (int v = 0; v < 6; ++v) {
    const float a = 1.047f * v;
    f.cams.push_back(vcar::Camera::look_at({3.5f * std::cos(a), 0.5f, 3.5f * std::sin(a)}, {0, 0, 0}, {0, 1, 0}, k,
                                           "v" + std::to_string(v)));
    vcar::Mask m(160, 120, 1, 0);
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) m(x, y) = (x - 80) * (x - 80) + (y - 60) * (y - 60) < 40 * 40 + 10 * v ? 255 : 0;
    f.masks.push_back(m);
  }
  return f;
}

}  // namespace

TEST_CASE("Eq. 11: lambda == sum_d w_d + eps2d for random Gaussians and cameras") {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> U(-1.f, 1.f), L(-4.f, -0.5f);
  const vcar::Intrinsics k{640, 480, 500.f, 520.f, 321.f, 239.f};
  int checked = 0;
  for (int t = 0; t < 300; ++t) {
    const Eigen::Vector3f eye(3 * U(rng), 3 * U(rng), 3 * U(rng) + 5.f);
    const vcar::Camera cam = vcar::Camera::look_at(eye, {0, 0, 0}, {0, 1, 0}, k);
    const Eigen::Vector3f mu(U(rng), U(rng), U(rng));
    const Eigen::Matrix3f R = vcar::rotation_from_quaternion(U(rng), U(rng), U(rng), U(rng) + 0.01f);
    const Eigen::Vector3f s(std::exp(L(rng)), std::exp(L(rng)), std::exp(L(rng)));
    const auto g = vcar::project_gaussian(cam, mu, R, s, 1.f);
    REQUIRE(g.valid);
    const auto E = vcar::symmetric_eigen2(g.Sigma2D);
    for (const Eigen::Vector2f& u : {E.e1, E.e2, Eigen::Vector2f(-E.e2)}) {
      const double lambda = static_cast<double>(u.transpose() * g.Sigma2D * u);
      const auto w = vcar::axis_contributions(g.q, s, u);
      // Brute force w_d: project the 3D covariance of axis d alone, s_d^2 r_d r_d^T, onto u.
      const Eigen::Matrix<float, 2, 3> M = vcar::perspective_jacobian(cam, cam.to_camera(mu)) * cam.R_w;
      double sum = 0;
      for (int d = 0; d < 3; ++d) {
        const Eigen::Matrix3d Sd = (s[d] * s[d] * R.col(d) * R.col(d).transpose()).cast<double>();
        const double wd = u.cast<double>().dot(M.cast<double>() * Sd * M.cast<double>().transpose() * u.cast<double>());
        CHECK(w[d] == Approx(wd).margin(1e-5 * lambda + 1e-6));
        sum += w[d];
      }
      CHECK(lambda == Approx(sum + kEps2d).epsilon(1e-4));
      ++checked;
    }
  }
  CHECK(checked == 900);
}

TEST_CASE("a Gaussian straddling a vertical mask edge: Eq. 13 by hand, long axis compressed") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const Hand h = hand(0.5, 110);
  REQUIRE(h.a == Approx(15.0897).epsilon(1e-4));
  REQUIRE(h.f > 0.1);
  REQUIRE(h.f < 1.0);
  vcar::BoundaryRefinement abr(g, {0});
  abr.add_view(camera(), left_part(110));
  CHECK(abr.n_vis(0) == 1);
  CHECK(abr.n_ovf(0) == 1);
  const auto r = abr.finish();
  CHECK(r.flagged == 1);
  CHECK(r.compressed == 1);
  CHECK(r.axis_compressed[0] == 0b001);  // axis 0 is long and along the edge normal
  CHECK(factor(r, g, 0) == Approx(h.f).epsilon(1e-5));
  CHECK(r.log_scale[1][0] == g.log_scale[1][0]);  // other axes untouched (Eq. 14)
  CHECK(r.log_scale[2][0] == g.log_scale[2][0]);
  // After compression the 3-sigma extent along u equals l (the goal of Eq. 13).
  const double s1 = 0.5 * factor(r, g, 0);
  CHECK(3.0 * std::sqrt(s1 * s1 * 100.0 + kEps2d) == Approx(h.l).epsilon(1e-5));
}

TEST_CASE("the dominant axis follows the projection, not the axis index") {
  // Rotated 90 degrees about z: r_1 = (0, 1, 0) projects on v, r_2 = (-1, 0, 0) on u.
  const float c = std::sqrt(0.5f);
  const auto g = one_gaussian({0.1f, 0.5f, 1.f}, {c, 0.f, 0.f, c});
  const Hand h = hand(0.5, 110);
  const auto r = run(g, {left_part(110)});
  CHECK(r.axis_compressed[0] == 0b010);
  CHECK(factor(r, g, 1) == Approx(h.f).epsilon(1e-5));
  CHECK(r.log_scale[0][0] == g.log_scale[0][0]);
  CHECK(r.log_scale[2][0] == g.log_scale[2][0]);
}

TEST_CASE("two views with different factors: the minimum is taken") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const Hand h110 = hand(0.5, 110), h108 = hand(0.5, 108);
  REQUIRE(h108.f < h110.f);
  REQUIRE(h108.f > 0.1);
  CHECK(factor(run(g, {left_part(110), left_part(108)}), g, 0) == Approx(h108.f).epsilon(1e-5));
  CHECK(factor(run(g, {left_part(108), left_part(110)}), g, 0) == Approx(h108.f).epsilon(1e-5));
}

TEST_CASE("the rho gate is strict: gamma = n_ovf / n_vis > rho") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const vcar::Mask ovf = left_part(110), inside = left_part(200);
  auto views = [&](int n_ovf, int n_in) {
    std::vector<vcar::Mask> v(static_cast<std::size_t>(n_ovf), ovf);
    v.insert(v.end(), static_cast<std::size_t>(n_in), inside);
    return v;
  };
  vcar::AbrParams p;  // rho = 0.6
  CHECK(run(g, views(3, 2), p).flagged == 0);  // 3/5 = 0.6 is not > 0.6
  CHECK(run(g, views(4, 1), p).flagged == 1);  // 4/5
  p.rho = 0.4f;
  CHECK(run(g, views(2, 3), p).flagged == 0);  // 2/5 = 0.4
  const auto r = run(g, views(3, 2), p);       // 3/5 > 0.4
  CHECK(r.flagged == 1);
  CHECK(factor(r, g, 0) == Approx(hand(0.5, 110).f).epsilon(1e-5));
  CHECK(run(g, views(3, 2), p).log_scale[0][0] != g.log_scale[0][0]);
  p.rho = 0.6f;
  CHECK(run(g, views(3, 2), p).log_scale[0][0] == g.log_scale[0][0]);
}

TEST_CASE("f_min clamps a small positive factor") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const Hand h = hand(0.5, 106);
  REQUIRE(h.f > 0.0);
  REQUIRE(h.f < 0.5);  // below the f_min chosen here
  vcar::AbrParams p;
  p.f_min = 0.5f;
  CHECK(factor(run(g, {left_part(106)}, p), g, 0) == Approx(0.5).epsilon(1e-6));
  p.f_min = 0.1f;  // default: the raw factor passes
  CHECK(factor(run(g, {left_part(106)}, p), g, 0) == Approx(h.f).epsilon(1e-5));
}

TEST_CASE("a negative Eq. 13 numerator gives f_min (B.3)") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const Hand h = hand(0.5, 101);  // l ~ 0.7 px: (l/3)^2 < eps2d = lambda - w_1
  REQUIRE(h.f < 0.0);
  const auto r = run(g, {left_part(101)});
  CHECK(factor(r, g, 0) == Approx(0.1).epsilon(1e-6));
  CHECK(r.axis_compressed[0] == 0b001);
}

TEST_CASE("a centre on background is not eligible (B.1)") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  vcar::BoundaryRefinement abr(g, {0});
  abr.add_view(camera(), left_part(95));  // centre at u = 100.3 is background
  abr.add_view(camera(), left_part(95));
  CHECK(abr.n_vis(0) == 0);
  CHECK(abr.n_ovf(0) == 0);
  const auto r = abr.finish();
  CHECK(r.flagged == 0);
  CHECK(r.log_scale[0][0] == g.log_scale[0][0]);
  // A centre behind the camera is not eligible either.
  vcar::GaussianScene behind = g;
  behind.mean[2][0] = -10.f;
  vcar::BoundaryRefinement abr2(behind, {0});
  abr2.add_view(camera(), left_part(200));
  CHECK(abr2.n_vis(0) == 0);
}

TEST_CASE("an endpoint outside the image counts as overflow, traced to the image edge") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const vcar::Camera cam = camera(112, 100);  // all foreground; the image ends at u = 112
  const Hand h = hand(0.5, 112);
  vcar::BoundaryRefinement abr(g, {0});
  abr.add_view(cam, vcar::Mask(112, 100, 1, 255));
  CHECK(abr.n_ovf(0) == 1);
  CHECK(factor(abr.finish(), g, 0) == Approx(h.f).epsilon(1e-5));
}

TEST_CASE("an elongated Gaussian inside the mask is not penalised (directional test)") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});  // a = 15.1 px, the mask reaches u = 116
  vcar::BoundaryRefinement abr(g, {0});
  abr.add_view(camera(), left_part(116));
  CHECK(abr.n_vis(0) == 1);
  CHECK(abr.n_ovf(0) == 0);
  CHECK(abr.finish().flagged == 0);
}

TEST_CASE("compression_factor: degenerate w_{d*} and the reference-code rules") {
  vcar::AbrParams p;
  const std::array<float, 3> zero{0.f, 0.f, 0.f};
  CHECK(std::isinf(vcar::compression_factor(1.f, 0.3f, zero, 0, p)));  // rule (c): no candidate
  // Paper: f^2 = ((l/3)^2 - lambda + w*) / w*, lambda = 10 + 5 + 0.3.
  const std::array<float, 3> w{10.f, 5.f, 0.f};
  const float lambda = 15.3f, l = 9.f;  // (l/3)^2 = 9
  CHECK(vcar::compression_factor(l, lambda, w, 0, p) == Approx(std::sqrt((9.0 - 15.3 + 10.0) / 10.0)));
  // Reference code: w* -> lambda w* / sum w = 15.3 * 10 / 15 = 10.2.
  p.reference_code_rules = true;
  CHECK(vcar::compression_factor(l, lambda, w, 0, p) == Approx(std::sqrt((9.0 - 15.3 + 10.2) / 10.2)));
  CHECK(std::isinf(vcar::compression_factor(12.f, lambda, w, 0, p)));  // (12/3)^2 = 16 >= lambda
  CHECK(vcar::compression_factor(3.f, lambda, w, 0, p) == Approx(0.1f));  // negative numerator
}

TEST_CASE("Eq. 13 solved for l_u: the last march sample whose exit can lower a minimum") {
  vcar::AbrParams p;  // sigma_c 3, f_min 0.1
  // By hand: lambda 4, w = (1, 0.5, 0.2), d* = 0, minimum 0.5: f < 0.5 <=> (l/3)^2 < 4 - 1 + 0.25,
  // l* = 3 sqrt(3.25) = 5.408; step 0.1: exit distance (k - 1/2) 0.1 < l* for k <= 54; + 2 margin.
  CHECK(vcar::last_sample_that_can_beat(0.5f, 4.f, {1.f, 0.5f, 0.2f}, 0, 0.1f, 129, p) == 56);
  CHECK(vcar::last_sample_that_can_beat(0.5f, 4.f, {1.f, 0.5f, 0.2f}, 0, 0.01f, 129, p) == 128);  // beyond L
  CHECK(vcar::last_sample_that_can_beat(0.05f, 0.2f, {1.f, 0.f, 0.f}, 0, 0.1f, 129, p) == -1);    // l2 < 0
  // Brute force, both rule sets: every exit sample whose clamped factor is below the minimum
  // lies within the returned reach.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  int checked = 0, below = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    p.reference_code_rules = trial % 2 == 1;
    const std::array<float, 3> w{4.f * U(rng), 4.f * U(rng), 4.f * U(rng)};
    const int d = static_cast<int>(std::max_element(w.begin(), w.end()) - w.begin());
    const float lambda = w[0] + w[1] + w[2] + 0.3f * U(rng);
    const float L = 3.f * std::sqrt(lambda), step = L / 128.f;
    const float beat = p.f_min + 1.2f * U(rng);
    const int last = vcar::last_sample_that_can_beat(beat, lambda, w, d, step, 129, p);
    for (int k = 0; k <= 128; ++k) {
      const float f = std::max(p.f_min, vcar::compression_factor(vcar::exit_distance(k, step), lambda, w, d, p));
      if (f < beat) { ++below; checked += k <= last; }
    }
  }
  CHECK(below > 10000);
  CHECK(checked == below);
}

TEST_CASE("reference-code rules on the straddling Gaussian") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  const Hand h = hand(0.5, 110);
  vcar::AbrParams p;
  p.reference_code_rules = true;
  // Along u = e1 only axis 0 contributes, so its share is all of lambda: f = (l/3) / sqrt(lambda).
  CHECK(factor(run(g, {left_part(110)}, p), g, 0) == Approx(h.l / 3.0 / std::sqrt(h.lambda)).epsilon(1e-5));
}

TEST_CASE("results are bit-identical for any thread count") {
  const RingFixture f = ring_fixture();
  const vcar::GaussianScene& g = f.scene;
  const std::vector<vcar::Camera>& cams = f.cams;
  const std::vector<vcar::Mask>& masks = f.masks;
  std::vector<vcar::Index> cand(f.scene.size());
  for (std::size_t i = 0; i < cand.size(); ++i) cand[i] = static_cast<vcar::Index>(cand.size() - 1 - i);
  auto go = [&](int threads) {
    vcar::set_num_threads(threads);
    vcar::BoundaryRefinement abr(g, cand);
    for (int v = 0; v < 6; ++v) abr.add_view(cams[v], masks[v]);
    return abr.finish();
  };
  const int saved = vcar::max_threads();
  const auto r1 = go(1), r2 = go(2), r3 = go(3);
  vcar::set_num_threads(saved);
  CHECK(r1.compressed > 100);  // the test exercises compression
  CHECK(r1.log_scale == r2.log_scale);
  CHECK(r1.log_scale == r3.log_scale);
  CHECK(r1.axis_compressed == r2.axis_compressed);
  CHECK(r1.flagged == r3.flagged);
}

TEST_CASE("outputs stay aligned with the candidates as given") {
  // Gaussian 0 straddles the edge; Gaussian 1 is small and well inside; Gaussian 2 is not a candidate.
  vcar::GaussianScene g;
  g.resize(3);
  const Eigen::Vector3f big = Eigen::Vector3f(0.5f, 0.1f, 1.f).array().log();
  const Eigen::Vector3f small = Eigen::Vector3f(0.05f, 0.05f, 0.05f).array().log();
  g.set(0, {0.f, 0.f, 10.f}, big, {1, 0, 0, 0}, 5.f);
  g.set(1, {-0.3f, 0.1f, 10.f}, small, {1, 0, 0, 0}, 5.f);
  g.set(2, {0.f, 0.f, 10.f}, big, {1, 0, 0, 0}, 5.f);
  vcar::BoundaryRefinement abr(g, {1, 0});
  abr.add_view(camera(), left_part(110));
  CHECK(abr.candidates() == std::vector<vcar::Index>{1, 0});
  CHECK(abr.n_ovf(0) == 0);
  CHECK(abr.n_ovf(1) == 1);
  const auto r = abr.finish();
  REQUIRE(r.log_scale[0].size() == 2);
  CHECK(r.axis_compressed == std::vector<std::uint8_t>{0, 0b001});
  for (int d = 0; d < 3; ++d) CHECK(r.log_scale[d][0] == g.log_scale[d][1]);
  CHECK(std::exp(static_cast<double>(r.log_scale[0][1]) - g.log_scale[0][0]) == Approx(hand(0.5, 110).f).epsilon(1e-5));
}

TEST_CASE("bad input names what is at fault") {
  const auto g = one_gaussian({0.5f, 0.1f, 1.f});
  CHECK_THROWS_AS(vcar::BoundaryRefinement(g, {1}), vcar::Error);
  vcar::AbrParams p;
  p.f_min = 0.f;
  try {
    vcar::BoundaryRefinement(g, {0}, p);
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(e.where().find("f_min") != std::string::npos);
  }
  vcar::BoundaryRefinement abr(g, {0});
  try {
    abr.add_view(camera(200, 100, "IMG_3"), vcar::Mask(100, 100, 1, 255));
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(std::string(e.what()).find("IMG_3") != std::string::npos);
  }
}

TEST_CASE("views decided per chunk or per Gaussian from mask tiles equal observe_gaussian one by one") {
  // Small Gaussians filling a ball seen inside a large disc mask: most chunks and Gaussians are
  // decided from the tiles (no centre on foreground, or every endpoint on foreground); the
  // counts and minima must be those of observe_gaussian called for every Gaussian and view.
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> U(-1.f, 1.f), L(-5.5f, -3.f);
  vcar::GaussianScene g;
  const int n = 8000;
  g.resize(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3f p(U(rng), U(rng), U(rng));
    if (i % 7 == 0) p *= 2.f;  // some outside the disc's reach
    g.set(i, p, {L(rng), L(rng), i % 50 == 0 ? -1.f : L(rng)}, {U(rng), U(rng), U(rng), U(rng) + 0.01f}, 0.f);
  }
  std::vector<vcar::Index> cand(n);
  for (int i = 0; i < n; ++i) cand[i] = static_cast<vcar::Index>(i);
  const vcar::Intrinsics k{200, 150, 170.f, 170.f, 100.f, 75.f};
  std::vector<vcar::Camera> cams;
  std::vector<vcar::Mask> masks;
  for (int v = 0; v < 5; ++v) {
    const float a = 1.2566f * v;
    cams.push_back(vcar::Camera::look_at({4.f * std::cos(a), 0.7f, 4.f * std::sin(a)}, {0, 0, 0}, {0, 1, 0}, k,
                                         "v" + std::to_string(v)));
    vcar::Mask m(200, 150, 1, 0);
    for (int y = 0; y < 150; ++y)
      for (int x = 0; x < 200; ++x) m(x, y) = (x - 100) * (x - 100) + (y - 75) * (y - 75) < (48 + 3 * v) * (48 + 3 * v);
    masks.push_back(m);
  }
  vcar::BoundaryRefinement abr(g, cand);
  for (int v = 0; v < 5; ++v) abr.add_view(cams[v], masks[v]);
  const vcar::AbrParams p;
  int mismatches = 0, eligible = 0, overflowing = 0, below_f_min = 0;
  for (int i = 0; i < n; ++i) {
    int n_vis = 0, n_ovf = 0;
    std::array<float, 3> f{INFINITY, INFINITY, INFINITY};
    for (int v = 0; v < 5; ++v) {
      const vcar::AbrObservation o = vcar::observe_gaussian(cams[v], masks[v], g.mu(i), g.R(i), g.scale(i), p);
      n_vis += o.eligible;
      n_ovf += o.eligible && o.overflow;
      if (o.eligible && o.overflow)
        for (int d = 0; d < 3; ++d) f[d] = std::min(f[d], o.f[d]);
    }
    eligible += n_vis;
    overflowing += n_ovf;
    mismatches += (abr.n_vis(i) != n_vis) + (abr.n_ovf(i) != n_ovf);
    // The refinement keeps the minimum of the factors clamped below at f_min (and traces only
    // endpoints that can lower it): max(f_min, min over views) of the full observations.
    for (int d = 0; d < 3; ++d) {
      mismatches += !(abr.min_factor(i, d) == std::max(p.f_min, f[d]));
      below_f_min += f[d] < p.f_min;
    }
  }
  CHECK(eligible > 10000);   // the test exercises both outcomes
  CHECK(overflowing > 500);
  CHECK(below_f_min > 0);    // ... and factors that the clamp changes
  CHECK(mismatches == 0);
}

TEST_CASE("IncrementalRefinement (carried state, change_view, complete_view) equals a refinement from scratch") {
  // A ball of Gaussians seen by 8 views with disc masks. The previous refinement held candidates
  // [0, 6000) under masks A; the next holds [1000, 7000) under masks where view 1 changed, view
  // 3 was cleared, view 5 is new and the others are unchanged.
  const vcar::GaussianScene g = random_gaussians(8000, 21, -5.f, -2.5f);
  const vcar::Intrinsics k{160, 120, 140.f, 140.f, 80.f, 60.f};
  std::vector<vcar::Camera> cams;
  auto disc = [](int r, int dx) {
    vcar::Mask m(160, 120, 1, 0);
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) m(x, y) = (x - 80 - dx) * (x - 80 - dx) + (y - 60) * (y - 60) < r * r ? 255 : 0;
    return m;
  };
  std::vector<std::optional<vcar::Mask>> before(8), after(8);
  for (int v = 0; v < 8; ++v) {
    const float a = 0.785f * v;
    cams.push_back(vcar::Camera::look_at({3.5f * std::cos(a), 0.6f, 3.5f * std::sin(a)}, {0, 0, 0}, {0, 1, 0}, k,
                                         "v" + std::to_string(v)));
    if (v != 5) before[v] = disc(34 + 2 * v, 0);
    after[v] = before[v];
  }
  after[1] = disc(26, 9);  // a smaller, shifted mask: minima of view 1 move
  after[3].reset();
  after[5] = disc(40, -4);
  std::vector<vcar::Index> prev_cand, next_cand;
  for (int i = 0; i < 6000; ++i) prev_cand.push_back(static_cast<vcar::Index>(i));
  for (int i = 1000; i < 7000; ++i) next_cand.push_back(static_cast<vcar::Index>(i));
  std::reverse(next_cand.begin(), next_cand.end());  // any candidate order

  vcar::BoundaryRefinement prev(g, prev_cand);
  for (int v = 0; v < 8; ++v)
    if (before[v]) prev.add_view(cams[v], *before[v], static_cast<std::uint16_t>(v));
  vcar::BoundaryRefinement scratch(g, next_cand);
  for (int v = 0; v < 8; ++v)
    if (after[v]) scratch.add_view(cams[v], *after[v], static_cast<std::uint16_t>(v));

  vcar::IncrementalRefinement inc(g, next_cand, {}, prev);
  for (int v : {1, 3, 5})
    inc.change_view(cams[v], before[v] ? &*before[v] : nullptr, after[v] ? &*after[v] : nullptr, static_cast<std::uint16_t>(v));
  const auto cfs = inc.carried_fresh_stale();
  CHECK(cfs[0] + cfs[2] == 5000);
  CHECK(cfs[1] == 1000);
  CHECK(cfs[2] > 20);  // some minima came from view 1 or 3: the recomputation is exercised
  CHECK(inc.incomplete());
  for (int v = 0; v < 8; ++v)
    if (after[v]) inc.complete_view(cams[v], *after[v], static_cast<std::uint16_t>(v));
  CHECK_THROWS_AS(inc.change_view(cams[0], nullptr, &*after[0], 0), vcar::Error);  // too late

  CHECK(inc.views() == scratch.views());
  int mismatches = 0;
  for (std::size_t c = 0; c < next_cand.size(); ++c) {
    mismatches += (inc.n_vis(c) != scratch.n_vis(c)) + (inc.n_ovf(c) != scratch.n_ovf(c));
    for (int d = 0; d < 3; ++d) mismatches += !(inc.min_factor(c, d) == scratch.min_factor(c, d));
  }
  CHECK(mismatches == 0);
  const auto a = inc.finish(), b = scratch.finish();
  CHECK(b.compressed > 50);  // the comparison covers compressed Gaussians
  CHECK(a.log_scale == b.log_scale);
  CHECK(a.axis_compressed == b.axis_compressed);
  CHECK(a.flagged == b.flagged);
  CHECK(a.compressed == b.compressed);

  // A carried state carries again (Reselection chains them), here under the same masks: nothing
  // to complete, the same result; only as an AbrState (what Reselection keeps) too.
  const vcar::AbrState kept(std::move(inc));
  vcar::IncrementalRefinement again(g, next_cand, {}, kept);
  CHECK(!again.incomplete());
  CHECK(again.carried_fresh_stale() == std::array<std::size_t, 3>{next_cand.size(), 0, 0});
  CHECK(again.finish().log_scale == b.log_scale);
}

TEST_CASE("expect_views skips candidates whose gate cannot open, with the same result") {
  const RingFixture f = ring_fixture();
  const vcar::GaussianScene& g = f.scene;
  const std::vector<vcar::Camera>& cams = f.cams;
  const std::vector<vcar::Mask>& masks = f.masks;
  const int n = static_cast<int>(g.size());
  std::vector<vcar::Index> cand(g.size());
  for (std::size_t i = 0; i < cand.size(); ++i) cand[i] = static_cast<vcar::Index>(i);
  vcar::AbrParams p;
  for (float rho : {0.6f, 0.2f, 0.f}) {
    p.rho = rho;
    vcar::BoundaryRefinement all(g, cand, p), skipping(g, cand, p);
    skipping.expect_views(6);
    const std::size_t boxes = all.boxes_observed();
    CHECK(boxes == (cand.size() + 63) / 64);
    CHECK(skipping.boxes_observed() == boxes);
    for (int v = 0; v < 6; ++v) {
      all.add_view(cams[v], masks[v]);
      skipping.add_view(cams[v], masks[v]);
      CHECK(all.boxes_observed() == boxes);
    }
    std::size_t observed_all = 0, observed_skipping = 0;
    for (int i = 0; i < n; ++i) {
      observed_all += all.n_vis(i);
      observed_skipping += skipping.n_vis(i);
    }
    if (rho > 0.f) CHECK(observed_skipping < observed_all);  // some candidates were skipped
    const auto a = all.finish(), b = skipping.finish();
    CHECK(a.flagged > 0);
    CHECK(a.log_scale == b.log_scale);
    CHECK(a.axis_compressed == b.axis_compressed);
    CHECK(a.flagged == b.flagged);
    CHECK(a.compressed == b.compressed);
  }
  {
    // Boxes whose candidates all stopped being observed are left out of the later views. Tiny
    // Gaussians near the middle under full-foreground masks are eligible without overflow in
    // every view, so with rho 0.6 and six views none can open its gate after three (at most
    // (0 + 3) / (3 + 3) = 0.5): from the fourth view on no box is observed.
    vcar::GaussianScene tiny = random_gaussians(3000, 5, -7.f, -6.f);
    for (int d = 0; d < 3; ++d)
      for (float& m : tiny.mean[d]) m *= 0.5f;
    std::vector<vcar::Index> every(tiny.size());
    for (std::size_t i = 0; i < every.size(); ++i) every[i] = static_cast<vcar::Index>(i);
    const vcar::Mask full(160, 120, 1, 255);
    p.rho = 0.6f;
    vcar::BoundaryRefinement all(tiny, every, p), skipping(tiny, every, p);
    skipping.expect_views(6);
    const std::size_t boxes = skipping.boxes_observed();
    CHECK(boxes == (every.size() + 63) / 64);
    for (int v = 0; v < 6; ++v) {
      all.add_view(cams[v], full);
      skipping.add_view(cams[v], full);
      CHECK(skipping.boxes_observed() == (v < 3 ? boxes : 0));
    }
    std::size_t eligible = 0;
    for (std::size_t i = 0; i < every.size(); ++i) eligible += all.n_vis(i) == 6 && all.n_ovf(i) == 0;
    CHECK(eligible == every.size());  // the premise: every candidate eligible, none overflowing
    const auto a = all.finish(), b = skipping.finish();
    CHECK(a.log_scale == b.log_scale);
    CHECK(a.flagged == b.flagged);
  }
  vcar::BoundaryRefinement more(g, cand);
  more.expect_views(1);
  more.add_view(cams[0], masks[0]);
  CHECK_THROWS_AS(more.add_view(cams[1], masks[1]), vcar::Error);  // more views than announced
  CHECK_THROWS_AS(vcar::IncrementalRefinement(g, cand, {}, more), vcar::Error);  // partial state cannot be carried
}

TEST_CASE("expect_views' gate table: least_opening_overflow is the least count that passes gate_can_open") {
  using BR = vcar::BoundaryRefinement;
  // By hand: rho 0.5, 4 views to come, 6 seen: (o + 4) / 10 >= 0.5 - 1e-6 first at o = 1.
  CHECK(BR::least_opening_overflow(6, 4, 0.5f) == 1);
  CHECK(BR::least_opening_overflow(2, 4, 0.5f) == 0);    // (0 + 4) / 6 passes already
  CHECK(BR::least_opening_overflow(10, 0, 0.3f) == 3);   // 3 / 10 >= 0.3 - 1e-6 (finish() then needs 4)
  CHECK(BR::least_opening_overflow(100, 1, 0.99f) == 99);
  // Brute force over counts, views to come and thresholds, exact multiples of rho included.
  std::size_t checked = 0;
  for (float rho : {0.f, 0.1f, 0.25f, 0.3f, 0.5f, 1.f / 3.f, 0.7f, 0.9f, 0.999f})
    for (std::size_t remaining : {0, 1, 2, 3, 7, 50, 1000})
      for (std::size_t v = 0; v <= 300; ++v) {
        const std::size_t least = BR::least_opening_overflow(v, remaining, rho);
        REQUIRE(least <= v);
        for (std::size_t o = 0; o <= v; ++o) {
          if (BR::gate_can_open(o, v, remaining, rho) != (o >= least)) {
            FAIL_CHECK("rho " << rho << " remaining " << remaining << " n_vis " << v << " n_ovf " << o);
          }
          ++checked;
        }
      }
  CHECK(checked > 1000000);
  CHECK(BR::least_opening_overflow(65535, 65535, 0.5f) == 0);  // large counts: no overflow of the guess
  CHECK(BR::least_opening_overflow(65535, 0, 0.5f) == 32768);  // 32768 / 65535 >= 0.5 - 1e-6; 32767 is not
}

TEST_CASE("defer_tracing and refine_deferred: the flagged candidates left untraced, refined alone, complete a full refinement") {
  const RingFixture f = ring_fixture();
  std::vector<vcar::Index> cand(f.scene.size());
  for (std::size_t i = 0; i < cand.size(); ++i) cand[i] = static_cast<vcar::Index>(i);
  vcar::AbrParams p;
  std::size_t retraced_total = 0;
  for (float rho : {0.6f, 0.3f, 0.f}) {
    p.rho = rho;
    INFO("rho " << rho);
    vcar::BoundaryRefinement full(f.scene, cand, p), deferred(f.scene, cand, p);
    deferred.defer_tracing();
    for (int v = 0; v < 6; ++v) {
      full.add_view(f.cams[v], f.masks[v]);
      deferred.add_view(f.cams[v], f.masks[v]);
    }
    // The counts are exact (the gate reads them); only the minima can miss views.
    std::size_t missing = 0;
    for (std::size_t k = 0; k < cand.size(); ++k) {
      REQUIRE(deferred.n_vis(k) == full.n_vis(k));
      REQUIRE(deferred.n_ovf(k) == full.n_ovf(k));
      for (int d = 0; d < 3; ++d) missing += deferred.min_factor(k, d) != full.min_factor(k, d);
    }
    const std::vector<std::size_t> again = deferred.flagged_untraced();
    retraced_total += again.size();
    const vcar::AbrResult partial = deferred.finish(), ref = full.finish();
    CHECK(partial.flagged == ref.flagged);
    if (rho > 0.f) CHECK(missing > 0);  // some minima were left out (not traced)
    // refine_deferred: those candidates once more, alone, complete it bit for bit.
    int passes = 0;
    const vcar::AbrResult a = vcar::refine_deferred(f.scene, cand, p, 6, [&](auto&& add) {
      ++passes;
      for (int v = 0; v < 6; ++v) add(f.cams[v], f.masks[v]);
    });
    CHECK(passes == (again.empty() ? 1 : 2));
    CHECK(a.retraced == again.size());
    CHECK(a.flagged == ref.flagged);
    CHECK(a.compressed == ref.compressed);
    CHECK(a.log_scale == ref.log_scale);
    CHECK(a.axis_compressed == ref.axis_compressed);
    // Every other flagged candidate was traced in each view it overflowed: its minima are exact.
    for (std::size_t k = 0; k < cand.size(); ++k)
      if (!std::binary_search(again.begin(), again.end(), k) && full.n_vis(k) > 0 &&
          static_cast<float>(full.n_ovf(k)) / static_cast<float>(full.n_vis(k)) > rho)
        for (int d = 0; d < 3; ++d) REQUIRE(deferred.min_factor(k, d) == full.min_factor(k, d));
  }
  CHECK(retraced_total > 0);  // the second refinement had work to do
  vcar::BoundaryRefinement started(f.scene, cand, p);
  started.add_view(f.cams[0], f.masks[0]);
  CHECK_THROWS_AS(started.defer_tracing(), vcar::Error);  // before the first view only
  vcar::BoundaryRefinement deferring(f.scene, cand, p);
  deferring.defer_tracing();
  CHECK_THROWS_AS(vcar::IncrementalRefinement(f.scene, cand, p, deferring), vcar::Error);  // partial minima
}

TEST_CASE("add_view with a run-length encoded mask equals add_view with its pixels, with tiles and without") {
  const RingFixture f = ring_fixture();
  std::vector<vcar::RleMask> runs;
  for (const vcar::Mask& m : f.masks) runs.push_back(vcar::RleMask::encode(m));
  vcar::AbrParams p;
  p.rho = 0.3f;
  // All 6000 candidates: the tiles pay and are built from the runs. 40 candidates: they do not,
  // and the runs are decoded to pixels.
  for (std::size_t count : {f.scene.size(), std::size_t{40}}) {
    INFO(count << " candidates");
    std::vector<vcar::Index> cand(count);
    for (std::size_t i = 0; i < count; ++i) cand[i] = static_cast<vcar::Index>(i * 7 % f.scene.size());
    vcar::BoundaryRefinement from_pixels(f.scene, cand, p), from_runs(f.scene, cand, p);
    for (int v = 0; v < 6; ++v) {
      from_pixels.add_view(f.cams[v], f.masks[v]);
      from_runs.add_view(f.cams[v], runs[v]);
    }
    std::size_t overflowing = 0;
    for (std::size_t k = 0; k < count; ++k) {
      REQUIRE(from_runs.n_vis(k) == from_pixels.n_vis(k));
      REQUIRE(from_runs.n_ovf(k) == from_pixels.n_ovf(k));
      for (int d = 0; d < 3; ++d) REQUIRE(from_runs.min_factor(k, d) == from_pixels.min_factor(k, d));
      overflowing += from_pixels.n_ovf(k) > 0;
    }
    CHECK(overflowing > 0);
    const vcar::AbrResult a = from_pixels.finish(), b = from_runs.finish();
    CHECK(a.flagged == b.flagged);
    CHECK(a.log_scale == b.log_scale);
    CHECK(a.axis_compressed == b.axis_compressed);
    // refine_deferred takes either kind of mask.
    const vcar::AbrResult c = vcar::refine_deferred(f.scene, cand, p, 6, [&](auto&& add) {
      for (int v = 0; v < 6; ++v) add(f.cams[v], runs[v]);
    });
    CHECK(c.log_scale == a.log_scale);
    CHECK(c.axis_compressed == a.axis_compressed);
  }
  // Runs of another size than the view, or that do not cover the image, name the view.
  vcar::BoundaryRefinement abr(f.scene, {0, 1, 2});
  vcar::RleMask wrong = runs[0];
  wrong.width = 150;
  CHECK_THROWS_WITH(abr.add_view(f.cams[0], wrong), Catch::Contains("v0"));
  vcar::RleMask short_runs = runs[1];
  short_runs.runs.back() -= 1;
  CHECK_THROWS_WITH(abr.add_view(f.cams[1], short_runs), Catch::Contains("covers 19199 pixels"));
  CHECK(abr.views() == 0);
}

TEST_CASE("bound_minimum: a bound from some of the views leaves every minimum as a refinement over all views finds it") {
  const RingFixture f = ring_fixture();
  std::vector<vcar::Index> cand(f.scene.size());
  for (std::size_t i = 0; i < cand.size(); ++i) cand[i] = static_cast<vcar::Index>(i);
  vcar::AbrParams p;
  p.rho = 0.f;
  // The bound: minima over views 0, 2, 4 only (an upper bound of the minima over all six).
  vcar::BoundaryRefinement some(f.scene, cand, p), full(f.scene, cand, p), bounded(f.scene, cand, p);
  for (int v = 0; v < 6; v += 2) some.add_view(f.cams[v], f.masks[v]);
  std::size_t finite = 0, tighter = 0;
  for (std::size_t k = 0; k < cand.size(); ++k) {
    const std::array<float, 3> b{some.min_factor(k, 0), some.min_factor(k, 1), some.min_factor(k, 2)};
    bounded.bound_minimum(k, b);
    for (int d = 0; d < 3; ++d) {
      REQUIRE(bounded.min_factor(k, d) == b[d]);  // stored values are already clamped at f_min
      finite += std::isfinite(b[d]);
    }
  }
  CHECK(finite > 0);  // the bound says something
  for (int v = 0; v < 6; ++v) {
    full.add_view(f.cams[v], f.masks[v]);
    bounded.add_view(f.cams[v], f.masks[v]);
  }
  for (std::size_t k = 0; k < cand.size(); ++k) {
    REQUIRE(bounded.n_vis(k) == full.n_vis(k));
    REQUIRE(bounded.n_ovf(k) == full.n_ovf(k));
    for (int d = 0; d < 3; ++d) {
      REQUIRE(bounded.min_factor(k, d) == full.min_factor(k, d));  // min over views, bit for bit
      tighter += full.min_factor(k, d) < some.min_factor(k, d);
    }
  }
  CHECK(tighter > 0);  // the other three views lowered some minima below the bound
  const vcar::AbrResult a = bounded.finish(), ref = full.finish();
  CHECK(a.log_scale == ref.log_scale);
  CHECK(a.axis_compressed == ref.axis_compressed);
  CHECK(a.compressed == ref.compressed);

  // A bound below the true minimum is taken as given (the caller's promise): the result changes.
  vcar::BoundaryRefinement wrong(f.scene, cand, p);
  for (std::size_t k = 0; k < cand.size(); ++k) wrong.bound_minimum(k, {p.f_min, p.f_min, p.f_min});
  for (int v = 0; v < 6; ++v) wrong.add_view(f.cams[v], f.masks[v]);
  CHECK(wrong.finish().log_scale != ref.log_scale);
  // Bounded minima do not remember the view that set them: such a state cannot be carried.
  CHECK_THROWS_AS(vcar::IncrementalRefinement(f.scene, cand, p, wrong), vcar::Error);

  vcar::BoundaryRefinement started(f.scene, cand, p);
  started.add_view(f.cams[0], f.masks[0]);
  CHECK_THROWS_AS(started.bound_minimum(0, {1.f, 1.f, 1.f}), vcar::Error);  // before the first view only
  vcar::BoundaryRefinement fresh(f.scene, cand, p);
  CHECK_THROWS_AS(fresh.bound_minimum(cand.size(), {1.f, 1.f, 1.f}), vcar::Error);  // out of range
}

TEST_CASE("trace_overflow: the lanes traced together equal B.3 written endpoint by endpoint") {
  // Batches of different Gaussians near a disc's edge, each lane with its own running minima
  // (+inf: traced in full, f_min: nothing to trace, or in between: marches cut short). The
  // reference takes each lane alone: u of Eq. 9, w_d of Eq. 11, d* the first largest w_d, the
  // reach of the march (last_sample_that_can_beat), the march (first_exit_sample on the mask) and
  // Eq. 13 (compression_factor), for both rule sets and both mask types of the march.
  constexpr std::size_t W = vcar::simd::width;
  const vcar::Intrinsics k{160, 120, 150.f, 150.f, 80.f, 60.f};
  const vcar::Camera cam = vcar::Camera::look_at({0.3f, 0.4f, 3.5f}, {0, 0, 0}, {0, 1, 0}, k);
  vcar::Mask mask(160, 120, 1, 0);
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) mask(x, y) = (x - 80) * (x - 80) + (y - 60) * (y - 60) < 45 * 45 ? 255 : 0;
  vcar::MaskTiles tiles;
  tiles.build(mask);
  const vcar::GaussianScene g = random_gaussians(static_cast<int>(40 * W), 8, -3.5f, -1.5f);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> U(0.f, 1.f);
  int compared = 0, traced = 0, cut = 0, mismatches = 0;
  for (bool reference_rules : {false, true}) {
    vcar::AbrParams p;
    p.reference_code_rules = reference_rules;
    const vcar::AbrCamera C = vcar::AbrCamera::from(cam, p.projection);
    for (std::size_t b = 0; b + W <= g.size(); b += W) {
      // The batch's columns as BoundaryRefinement holds them.
      alignas(64) float col[15][W];
      for (std::size_t l = 0; l < W; ++l) {
        const Eigen::Vector3f mu = g.mu(b + l), s = g.scale(b + l);
        const Eigen::Matrix3f R = g.R(b + l);
        for (int d = 0; d < 3; ++d) col[d][l] = mu[d], col[12 + d][l] = s[d];
        for (int e = 0; e < 9; ++e) col[3 + e][l] = R(e % 3, e / 3);
      }
      const float* const rot[9] = {col[3], col[4], col[5], col[6], col[7], col[8], col[9], col[10], col[11]};
      const float* const sc[3] = {col[12], col[13], col[14]};
      vcar::AbrBatch geo;
      vcar::abr_geometry(C, col[0], col[1], col[2], rot, sc, p.sigma_c, geo);
      vcar::AbrLanes a;
      unsigned lanes = 0;
      for (std::size_t l = 0; l < W; ++l) {
        const float pick = U(rng);
        for (int d = 0; d < 3; ++d) {
          a.s[d][l] = col[12 + d][l];
          a.beat[d][l] = pick < 0.3f ? INFINITY : pick < 0.4f ? p.f_min : p.f_min + 1.1f * U(rng);
        }
        a.outside[l] = vcar::outside_endpoints(mask, geo, l);
        if (geo.front[l] > 0.f && geo.det[l] > 0.f && vcar::mask_at(mask, geo.mx[l], geo.my[l]) && a.outside[l] &&
            rng() % 5 != 0)  // some overflowing lanes left out: they must stay +inf
          lanes |= 1u << l;
      }
      for (int m = 0; m < 2; ++m) {
        if (m == 0) vcar::trace_overflow(mask, geo, lanes, p, a);
        else vcar::trace_overflow(tiles, geo, lanes, p, a);
        for (std::size_t l = 0; l < W; ++l) {
          std::array<float, 3> want{INFINITY, INFINITY, INFINITY};
          if ((lanes >> l) & 1u) {
            const Eigen::Vector2f e1(geo.e1x[l], geo.e1y[l]), e2(-geo.e1y[l], geo.e1x[l]);
            const std::array<Eigen::Vector2f, 3> q{geo.q(0, l), geo.q(1, l), geo.q(2, l)};
            const Eigen::Vector3f s(a.s[0][l], a.s[1][l], a.s[2][l]);
            for (int e = 0; e < 4; ++e) {
              if (!((a.outside[l] >> e) & 1)) continue;
              const Eigen::Vector2f u = (e < 2 ? e1 : e2) * (e % 2 ? -1.f : 1.f);
              const float lambda = std::max(e < 2 ? geo.lambda1[l] : geo.lambda2[l], 0.f), L = geo.axis[e / 2][l];
              const auto w = vcar::axis_contributions(q, s, u);
              const int d = static_cast<int>(std::max_element(w.begin(), w.end()) - w.begin());
              const float beat = a.beat[d][l];
              if (!(beat > p.f_min)) continue;
              const float step = L / 128.f;
              const int last = vcar::last_sample_that_can_beat(beat, lambda, w, d, step, 129, p);
              if (last < 0) continue;
              const int x = vcar::first_exit_sample(mask, geo.m(l), u, step, last);
              if (x > last && last < 128) continue;
              cut += last < 128;
              ++traced;
              want[d] = std::min(want[d], vcar::compression_factor(x <= last ? vcar::exit_distance(x, step) : L, lambda, w, d, p));
            }
          }
          for (int d = 0; d < 3; ++d) {
            const float got = a.f[d][l];
            const bool same = std::isinf(want[d]) ? got == want[d] : std::abs(got - want[d]) <= 1e-5f * want[d];
            mismatches += !same;
            ++compared;
          }
        }
      }
    }
  }
  CHECK(compared == 2 * 2 * 3 * 40 * static_cast<int>(W));
  CHECK(traced > 100);  // the test exercises full and cut marches
  CHECK(cut > 20);
  CHECK(mismatches == 0);
}

namespace {

// 40 views on a ring (more than two groups of add_views), each mask a disc whose radius and
// centre move from view to view, so that candidates overflow in some views and not in others.
struct ManyViews {
  std::vector<vcar::Camera> cams;
  std::vector<vcar::Mask> masks;
};
ManyViews many_views(int count, int w, int h) {
  ManyViews m;
  const vcar::Intrinsics k{w, h, 150.f * w / 160.f, 150.f * w / 160.f, w / 2.f, h / 2.f};
  for (int v = 0; v < count; ++v) {
    const float a = 6.2832f * static_cast<float>(v) / static_cast<float>(count);
    m.cams.push_back(vcar::Camera::look_at({3.5f * std::cos(a), 0.4f + 0.02f * v, 3.5f * std::sin(a)}, {0, 0, 0},
                                           {0, 1, 0}, k, "v" + std::to_string(v)));
    vcar::Mask mask(w, h, 1, 0);
    const float cx = w / 2.f + static_cast<float>(v % 5 - 2) * w / 40.f, r = w * (0.2f + 0.006f * static_cast<float>(v % 9));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) mask(x, y) = (x - cx) * (x - cx) + (y - h / 2.f) * (y - h / 2.f) < r * r ? 255 : 0;
    m.masks.push_back(mask);
  }
  return m;
}

// Every candidate's counts and minima, and finish(), of two refinements are the same.
void require_same_state(const vcar::BoundaryRefinement& a, const vcar::BoundaryRefinement& b) {
  REQUIRE(a.views() == b.views());
  for (std::size_t k = 0; k < a.size(); ++k) {
    REQUIRE(a.n_vis(k) == b.n_vis(k));
    REQUIRE(a.n_ovf(k) == b.n_ovf(k));
    for (int d = 0; d < 3; ++d) REQUIRE(a.min_factor(k, d) == b.min_factor(k, d));
  }
  const vcar::AbrResult x = a.finish(), y = b.finish();
  CHECK(x.flagged == y.flagged);
  CHECK(x.log_scale == y.log_scale);
  CHECK(x.axis_compressed == y.axis_compressed);
}

}  // namespace

TEST_CASE("add_views, candidates outside and views inside, equals add_view view by view") {
  const ManyViews mv = many_views(40, 160, 120);
  static_assert(vcar::BoundaryRefinement::kViewGroup < 40);
  const vcar::GaussianScene g = random_gaussians(6000, 11, -4.f, -2.f);
  std::vector<vcar::Index> cand(g.size());
  for (std::size_t i = 0; i < cand.size(); ++i) cand[i] = static_cast<vcar::Index>(i);
  std::vector<vcar::RleMask> runs;
  for (const vcar::Mask& m : mv.masks) runs.push_back(vcar::RleMask::encode(m));
  vcar::AbrParams p;
  p.rho = 0.3f;
  const int saved = vcar::max_threads();
  // Plain, skipping (expect_views), and skipping with deferred tracing (refine_deferred's first pass).
  for (int mode = 0; mode < 3; ++mode) {
    for (int threads : {1, std::max(2, saved)}) {
      INFO("mode " << mode << ", " << threads << " threads");
      vcar::set_num_threads(threads);
      auto make = [&] {
        vcar::BoundaryRefinement r(g, cand, p);
        if (mode >= 1) r.expect_views(mv.cams.size());
        if (mode == 2) r.defer_tracing();
        return r;
      };
      vcar::BoundaryRefinement one_by_one = make(), grouped = make(), grouped_runs = make();
      for (std::size_t v = 0; v < mv.cams.size(); ++v) one_by_one.add_view(mv.cams[v], mv.masks[v]);
      grouped.add_views([&](auto&& add) {
        for (std::size_t v = 0; v < mv.cams.size(); ++v) add(mv.cams[v], mv.masks[v]);
      });
      grouped_runs.add_views([&](auto&& add) {
        for (std::size_t v = 0; v < mv.cams.size(); ++v) add(mv.cams[v], runs[v]);
      });
      vcar::BoundaryRefinement plain(g, cand, p);
      for (std::size_t v = 0; v < mv.cams.size(); ++v) plain.add_view(mv.cams[v], mv.masks[v]);
      std::size_t overflowing = 0, skipped = 0;
      for (std::size_t k = 0; k < cand.size(); ++k) {
        overflowing += plain.n_ovf(k) > 0 && plain.n_ovf(k) < plain.n_vis(k);
        skipped += one_by_one.n_vis(k) < plain.n_vis(k);
      }
      // The premises: candidates overflow in some views, not all; skipping leaves views out.
      CHECK(overflowing > 100);
      if (mode >= 1) CHECK(skipped > 100);
      require_same_state(one_by_one, grouped);
      require_same_state(one_by_one, grouped_runs);
      if (mode >= 1) CHECK(grouped.boxes_observed() == one_by_one.boxes_observed());
      if (mode == 2) CHECK(grouped.flagged_untraced() == one_by_one.flagged_untraced());
    }
  }
  vcar::set_num_threads(saved);
}

TEST_CASE("add_views: views whose tiles do not pay are observed in turn; a bad view keeps the ones before") {
  // 40 candidates: a 64 x 48 view (3072 px) is observed from tiles, a 160 x 120 one (19200 px)
  // from its pixels (tiles_pay: 256 pixels per candidate). Alternating sizes makes add_views
  // observe the queued tiled views before each decoded one.
  const ManyViews small = many_views(20, 64, 48), large = many_views(20, 160, 120);
  std::vector<vcar::Camera> cams;
  std::vector<vcar::RleMask> masks;
  for (int v = 0; v < 20; ++v) {
    const ManyViews& from = v % 3 == 2 ? large : small;
    cams.push_back(from.cams[v]);
    masks.push_back(vcar::RleMask::encode(from.masks[v]));
  }
  const vcar::GaussianScene g = random_gaussians(6000, 13, -4.f, -2.f);
  std::vector<vcar::Index> cand(40);
  for (std::size_t i = 0; i < cand.size(); ++i) cand[i] = static_cast<vcar::Index>(i * 37 % g.size());
  vcar::AbrParams p;
  p.rho = 0.3f;
  vcar::BoundaryRefinement one_by_one(g, cand, p), grouped(g, cand, p);
  for (std::size_t v = 0; v < cams.size(); ++v) one_by_one.add_view(cams[v], masks[v]);
  grouped.add_views([&](auto&& add) {
    for (std::size_t v = 0; v < cams.size(); ++v) add(cams[v], masks[v]);
  });
  std::size_t seen = 0;
  for (std::size_t k = 0; k < cand.size(); ++k) seen += one_by_one.n_vis(k);
  CHECK(seen > 100);
  require_same_state(one_by_one, grouped);

  // View 7's runs do not cover its image: add_views throws naming it, and views 0-6 are added.
  std::vector<vcar::RleMask> bad = masks;
  bad[7].runs.back() -= 1;
  vcar::BoundaryRefinement first_seven(g, cand, p), broken(g, cand, p);
  for (std::size_t v = 0; v < 7; ++v) first_seven.add_view(cams[v], masks[v]);
  CHECK_THROWS_WITH(broken.add_views([&](auto&& add) {
    for (std::size_t v = 0; v < cams.size(); ++v) add(cams[v], bad[v]);
  }), Catch::Contains("v7"));
  CHECK(broken.views() == 7);
  require_same_state(first_seven, broken);
}
