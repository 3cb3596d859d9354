#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "vcar/core/spherical_harmonics.hpp"

namespace {

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

// Independent real SH: Y_lm from associated Legendre polynomials (std::assoc_legendre has no
// Condon-Shortley phase, so it is applied here), m = -l..l at index l^2 + l + m.
double real_sh(int l, int m, double x, double y, double z) {
  const double theta = std::acos(std::clamp(z, -1.0, 1.0)), phi = std::atan2(y, x);
  const int am = std::abs(m);
  const double K = std::sqrt((2 * l + 1) / (4 * M_PI) * factorial(l - am) / factorial(l + am));
  const double P = std::assoc_legendre(l, am, std::cos(theta)) * ((am % 2) ? -1.0 : 1.0);
  if (m == 0) return K * P;
  if (m > 0) return std::sqrt(2.0) * K * std::cos(am * phi) * P;
  return std::sqrt(2.0) * K * std::sin(am * phi) * P;
}

}  // namespace

TEST_CASE("degree 0 colour is 0.5 + C0 f_dc, clamped at 0") {
  const float dc[3] = {1.f, -0.5f, -3.f};
  const Eigen::Vector3f rgb = vcar::sh_to_rgb(0, dc, Eigen::Vector3f(0.3f, -2.f, 1.f));
  CHECK(rgb[0] == 0.5f + 0.28209479177387814f * 1.f);
  CHECK(rgb[1] == 0.5f + 0.28209479177387814f * -0.5f);
  CHECK(rgb[2] == 0.f);  // 0.5 - 0.846 < 0
}

TEST_CASE("the basis of degrees 1-3 is the real SH with Condon-Shortley phase") {
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0, 1);
  for (int trial = 0; trial < 50; ++trial) {
    double x = N(rng), y = N(rng), z = N(rng);
    const double n = std::sqrt(x * x + y * y + z * z);
    x /= n; y /= n; z /= n;
    float Y[16];
    vcar::sh_basis(3, float(x), float(y), float(z), Y);
    for (int l = 0; l <= 3; ++l)
      for (int m = -l; m <= l; ++m)
        CHECK(Y[l * l + l + m] == Approx(real_sh(l, m, x, y, z)).margin(1e-5));
  }
}

TEST_CASE("known directions: +x, +y, +z pick out single degree-1 coefficients") {
  const float C1 = 0.4886025119029199f;
  float sh[4 * 3] = {};
  sh[1 * 3 + 0] = 0.5f;  // sh1 red: -C1 y
  sh[2 * 3 + 1] = 0.5f;  // sh2 green: +C1 z
  sh[3 * 3 + 2] = 0.5f;  // sh3 blue: -C1 x
  const Eigen::Vector3f py = vcar::sh_to_rgb(1, sh, Eigen::Vector3f(0, -4, 0));
  CHECK(py[0] == Approx(0.5f + C1 * 0.5f));  // y = -1
  CHECK(py[1] == Approx(0.5f));
  const Eigen::Vector3f pz = vcar::sh_to_rgb(1, sh, Eigen::Vector3f(0, 0, 2));
  CHECK(pz[1] == Approx(0.5f + C1 * 0.5f));
  const Eigen::Vector3f px = vcar::sh_to_rgb(1, sh, Eigen::Vector3f(3, 0, 0));
  CHECK(px[2] == Approx(0.5f - C1 * 0.5f));
  CHECK(px[0] == Approx(0.5f));
}

TEST_CASE("sh_to_rgb sums basis times coefficients per channel, view from the camera centre") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(-0.4f, 0.4f);
  vcar::GaussianScene scene;
  scene.resize(2, 3);
  for (auto& v : scene.sh) v = U(rng);
  scene.set(1, Eigen::Vector3f(1, 2, 3), Eigen::Vector3f::Zero(), Eigen::Vector4f(1, 0, 0, 0), 0.f);
  const Eigen::Vector3f eye(-1, 0.5f, 2);
  const Eigen::Vector3f rgb = vcar::gaussian_rgb(scene, 1, eye);
  const Eigen::Vector3d d = (Eigen::Vector3d(1, 2, 3) - eye.cast<double>()).normalized();
  for (int c = 0; c < 3; ++c) {
    double s = 0.5;
    for (int l = 0; l <= 3; ++l)
      for (int m = -l; m <= l; ++m)
        s += real_sh(l, m, d.x(), d.y(), d.z()) * scene.sh[(16 + l * l + l + m) * 3 + c];
    CHECK(rgb[c] == Approx(std::max(0.0, s)).margin(1e-5));
  }
}
