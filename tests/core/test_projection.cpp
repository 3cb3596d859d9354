#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "vcar/core/projection.hpp"
#include "vcar/core/rotation.hpp"

namespace {

using Mat23d = Eigen::Matrix<double, 2, 3>;

vcar::Camera test_camera() {
  vcar::Intrinsics k{640, 480, 500.f, 520.f, 330.f, 236.f};
  return vcar::Camera::look_at(Eigen::Vector3f(0.3f, -0.2f, -4.f), Eigen::Vector3f(0, 0, 0),
                               Eigen::Vector3f(0, -1, 0), k, "test");
}

// Reference projection in double precision, written from the conventions (B.6-B.7, Eq. 10).
struct Reference {
  Eigen::Vector3d t;
  Eigen::Vector2d m;
  Mat23d J, M;
  Eigen::Matrix2d Sigma2D, conic;
  int rx, ry;
};

Reference reference(const vcar::Camera& cam, const Eigen::Vector3d& mu, const Eigen::Matrix3d& R,
                    const Eigen::Vector3d& s, double opacity) {
  Reference r;
  const Eigen::Matrix3d Rw = cam.R_w.cast<double>();
  r.t = Rw * mu + cam.t_w.cast<double>();
  const double fx = cam.fx, fy = cam.fy, cx = cam.cx, cy = cam.cy, W = cam.width, H = cam.height;
  r.m = {fx * r.t.x() / r.t.z() + cx, fy * r.t.y() / r.t.z() + cy};
  const double lxp = (W - cx) / fx + 0.3 * 0.5 * W / fx, lxn = cx / fx + 0.3 * 0.5 * W / fx;
  const double lyp = (H - cy) / fy + 0.3 * 0.5 * H / fy, lyn = cy / fy + 0.3 * 0.5 * H / fy;
  const double z = r.t.z();
  const double tx = z * std::clamp(r.t.x() / z, -lxn, lxp), ty = z * std::clamp(r.t.y() / z, -lyn, lyp);
  r.J << fx / z, 0, -fx * tx / (z * z), 0, fy / z, -fy * ty / (z * z);
  r.M = r.J * Rw;
  const Eigen::Matrix3d Sigma = R * s.cwiseAbs2().asDiagonal() * R.transpose();
  r.Sigma2D = r.M * Sigma * r.M.transpose() + 0.3 * Eigen::Matrix2d::Identity();
  r.conic = r.Sigma2D.inverse();
  const double extend = std::min(3.33, std::sqrt(2 * std::log(255 * opacity)));
  r.rx = int(std::ceil(extend * std::sqrt(r.Sigma2D(0, 0))));
  r.ry = int(std::ceil(extend * std::sqrt(r.Sigma2D(1, 1))));
  return r;
}

Eigen::Matrix3f random_rotation(std::mt19937& rng) {
  std::normal_distribution<float> N(0, 1);
  return vcar::rotation_from_quaternion(N(rng), N(rng), N(rng), N(rng));
}

}  // namespace

TEST_CASE("project_gaussian matches a double-precision reference (B.6-B.7, Eq. 10)") {
  const vcar::Camera cam = test_camera();
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(-1.5f, 1.5f), LS(-4.f, -1.f), OP(0.05f, 1.f);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3f mu(U(rng), U(rng), U(rng));
    const Eigen::Matrix3f R = random_rotation(rng);
    const Eigen::Vector3f s(std::exp(LS(rng)), std::exp(LS(rng)), std::exp(LS(rng)));
    const float op = OP(rng);
    const vcar::ProjectedGaussian g = vcar::project_gaussian(cam, mu, R, s, op);
    const Reference ref = reference(cam, mu.cast<double>(), R.cast<double>(), s.cast<double>(), op);
    REQUIRE(g.valid);
    CHECK(g.depth == Approx(ref.t.z()).epsilon(1e-5));
    CHECK(g.mean.x() == Approx(ref.m.x()).epsilon(1e-5));
    CHECK(g.mean.y() == Approx(ref.m.y()).epsilon(1e-5));
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        CHECK(g.Sigma2D(a, b) == Approx(ref.Sigma2D(a, b)).epsilon(1e-4).margin(1e-4 * ref.Sigma2D.norm()));
    CHECK(g.conic[0] == Approx(ref.conic(0, 0)).epsilon(1e-3));
    CHECK(g.conic[1] == Approx(ref.conic(0, 1)).epsilon(1e-3).margin(1e-3 * ref.conic.norm()));
    CHECK(g.conic[2] == Approx(ref.conic(1, 1)).epsilon(1e-3));
    CHECK(std::abs(g.radius_x - ref.rx) <= 1);  // ceil of a float vs a double value
    CHECK(std::abs(g.radius_y - ref.ry) <= 1);
    // q_d = M r_d and Sigma2D = sum_d s_d^2 q_d q_d^T + eps2d I (B.7)
    Eigen::Matrix2d S = 0.3 * Eigen::Matrix2d::Identity();
    for (int d = 0; d < 3; ++d) {
      const Eigen::Vector2d qd = ref.M * R.col(d).cast<double>();
      CHECK(g.q[d].x() == Approx(qd.x()).margin(1e-3 * ref.M.norm()));
      CHECK(g.q[d].y() == Approx(qd.y()).margin(1e-3 * ref.M.norm()));
      S += double(s[d]) * s[d] * g.q[d].cast<double>() * g.q[d].cast<double>().transpose();
    }
    CHECK((S - g.Sigma2D.cast<double>()).norm() <= 1e-4 * S.norm());
  }
}

TEST_CASE("near plane, opacity cull and on-screen test") {
  const vcar::Camera cam = test_camera();
  const Eigen::Matrix3f I = Eigen::Matrix3f::Identity();
  const Eigen::Vector3f s(0.01f, 0.01f, 0.01f);
  const Eigen::Vector3f eye = cam.position(), fwd = cam.forward();
  CHECK_FALSE(vcar::project_gaussian(cam, eye + 0.009f * fwd, I, s, 0.9f).valid);
  CHECK_FALSE(vcar::project_gaussian(cam, eye - 1.f * fwd, I, s, 0.9f).valid);
  CHECK(vcar::project_gaussian(cam, eye + 0.011f * fwd, I, s, 0.9f).valid);
  // opacity below 1/255 is culled; the extent follows opacity (gsplat 1.5)
  CHECK_FALSE(vcar::project_gaussian(cam, eye + 2.f * fwd, I, s, 0.003f).valid);
  const auto g = vcar::project_gaussian(cam, eye + 2.f * fwd, I, s, 0.02f);
  REQUIRE(g.valid);
  CHECK(g.radius_x == int(std::ceil(std::sqrt(2 * std::log(255 * 0.02)) * std::sqrt(g.Sigma2D(0, 0)))));
  // far to the side: valid but off screen
  const auto off = vcar::project_gaussian(cam, eye + 2.f * fwd + 10.f * cam.right(), I, s, 0.9f);
  CHECK(off.valid);
  CHECK_FALSE(off.on_screen);
  CHECK(g.on_screen);
}

TEST_CASE("the Jacobian clamps tx/z and ty/z to the frustum widened by 30%") {
  const vcar::Camera cam = test_camera();
  const float W = float(cam.width), H = float(cam.height);
  const float lxp = (W - cam.cx) / cam.fx + 0.3f * 0.5f * W / cam.fx;
  const float lyn = cam.cy / cam.fy + 0.3f * 0.5f * H / cam.fy;
  const Eigen::Vector3f t(5.f, -4.f, 2.f);  // tx/z = 2.5 > lxp, ty/z = -2 < -lyn
  const auto J = vcar::perspective_jacobian(cam, t);
  CHECK(J(0, 0) == Approx(cam.fx / 2.f));
  CHECK(J(0, 2) == Approx(-cam.fx * lxp / 2.f));
  CHECK(J(1, 2) == Approx(cam.fy * lyn / 2.f));
  // inside the frustum nothing is clamped
  const Eigen::Vector3f t2(0.1f, 0.2f, 2.f);
  const auto J2 = vcar::perspective_jacobian(cam, t2);
  CHECK(J2(0, 2) == Approx(-cam.fx * 0.1f / 4.f));
  CHECK(J2(1, 2) == Approx(-cam.fy * 0.2f / 4.f));
}

TEST_CASE("JacobianLimits: the frustum's tan half-extents, each side widened by margin x tan_half_fov (hand values)") {
  // W 100, H 50, fx fy 100, principal point (40, 25): tan_x = 0.5, tan_y = 0.25.
  const vcar::Camera cam = vcar::Camera::look_at(Eigen::Vector3f(0, 0, -4), Eigen::Vector3f::Zero(),
                                                 Eigen::Vector3f(0, -1, 0), {100, 50, 100.f, 100.f, 40.f, 25.f});
  const vcar::JacobianLimits lim = vcar::JacobianLimits::of(cam, 0.3f);
  CHECK(lim.x_pos == Approx(0.6 + 0.15));  // (W - cx) / fx + 0.3 tan_x
  CHECK(lim.x_neg == Approx(0.4 + 0.15));  // cx / fx + 0.3 tan_x
  CHECK(lim.y_pos == Approx(0.25 + 0.075));
  CHECK(lim.y_neg == Approx(0.25 + 0.075));
  const vcar::JacobianLimits none = vcar::JacobianLimits::of(cam, 0.f);  // the image's own edges
  CHECK(none.x_pos == Approx(0.6));
  CHECK(none.y_neg == Approx(0.25));
}

TEST_CASE("Monte Carlo: Sigma2D - eps2d is the covariance of the linearised projection") {
  const vcar::Camera cam = test_camera();
  std::mt19937 rng(5);
  const Eigen::Vector3f mu(0.2f, -0.1f, 0.3f);
  const Eigen::Matrix3f R = random_rotation(rng);
  const Eigen::Vector3f s(0.004f, 0.01f, 0.002f);
  const auto g = vcar::project_gaussian(cam, mu, R, s, 1.f);
  REQUIRE(g.valid);
  // Samples x = mu + R S n mapped by (a) the affine linearisation at the mean and (b) the true
  // pinhole projection (nearly linear for a Gaussian this small against its depth).
  const Eigen::Matrix3d Rw = cam.R_w.cast<double>();
  const Eigen::Vector3d t0 = Rw * mu.cast<double>() + cam.t_w.cast<double>();
  Mat23d J;
  J << cam.fx / t0.z(), 0, -cam.fx * t0.x() / (t0.z() * t0.z()), 0, cam.fy / t0.z(),
      -cam.fy * t0.y() / (t0.z() * t0.z());
  const Eigen::Matrix3d A = R.cast<double>() * s.cast<double>().asDiagonal();
  std::normal_distribution<double> N(0, 1);
  const int n = 200000;
  Eigen::Vector2d sum_lin = Eigen::Vector2d::Zero(), sum_pin = Eigen::Vector2d::Zero();
  Eigen::Matrix2d sq_lin = Eigen::Matrix2d::Zero(), sq_pin = Eigen::Matrix2d::Zero();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d x = mu.cast<double>() + A * Eigen::Vector3d(N(rng), N(rng), N(rng));
    const Eigen::Vector3d t = Rw * x + cam.t_w.cast<double>();
    const Eigen::Vector2d u_lin = J * (t - t0);
    const Eigen::Vector2d u_pin(cam.fx * t.x() / t.z(), cam.fy * t.y() / t.z());
    sum_lin += u_lin; sq_lin += u_lin * u_lin.transpose();
    sum_pin += u_pin; sq_pin += u_pin * u_pin.transpose();
  }
  const Eigen::Matrix2d cov_lin = sq_lin / n - (sum_lin / n) * (sum_lin / n).transpose();
  const Eigen::Matrix2d cov_pin = sq_pin / n - (sum_pin / n) * (sum_pin / n).transpose();
  const Eigen::Matrix2d S = g.Sigma2D.cast<double>() - 0.3 * Eigen::Matrix2d::Identity();
  CHECK((cov_lin - S).norm() <= 0.02 * S.norm());
  CHECK((cov_pin - S).norm() <= 0.03 * S.norm());
}
