#include <catch2/catch.hpp>

#include <cmath>

#include "vcar/algo/foreshortening.hpp"

using vcar::Foreshortening;
using vcar::GaussianScene;

namespace {
// One Gaussian at the origin with the given scales and rotation (w, x, y, z).
GaussianScene one(float sx, float sy, float sz, Eigen::Vector4f q = {1, 0, 0, 0}) {
  GaussianScene s;
  s.resize(1);
  s.set(0, Eigen::Vector3f::Zero(), Eigen::Vector3f(std::log(sx), std::log(sy), std::log(sz)), q, 0.f);
  return s;
}
}  // namespace

TEST_CASE("Eq. R5 by hand: a disc weighs |cos| of the angle between its normal and the ray, a ball 1") {
  // Disc: scales (1, 1, 0.01): n = r_3 = z, phi = 1 - 0.01 / 1 = 0.99.
  const GaussianScene disc = one(1.f, 1.f, 0.01f);
  const auto [n, phi] = Foreshortening::normal_and_flatness(disc, 0);
  CHECK(n.isApprox(Eigen::Vector3f::UnitZ()));
  CHECK(phi == Approx(0.99f));
  const Foreshortening f = Foreshortening::of(disc, {});
  // Face-on (camera on the normal): omega = 0.01 + 0.99 * 1 = 1.
  CHECK(f.weight(0, 0, 0, 0, {0, 0, -5}) == Approx(1.f));
  CHECK(f.weight(0, 0, 0, 0, {0, 0, 5}) == Approx(1.f));  // either side
  // 60 degrees off the normal: |cos| = 0.5, omega = 0.01 + 0.99 * 0.5 = 0.505.
  CHECK(f.weight(0, 0, 0, 0, {5 * std::sin(1.0471976f), 0, 5 * std::cos(1.0471976f)}) == Approx(0.505f));
  // Edge-on: omega = 1 - phi = 0.01.
  CHECK(f.weight(0, 0, 0, 0, {0, 3, 0}) == Approx(0.01f));
  // The mean elsewhere: only the direction counts. Ray (3, 0, 4) / 5: cos = 0.8.
  CHECK(f.weight(0, 3, 0, 4, {0, 0, 0}) == Approx(0.01f + 0.99f * 0.8f));
  // A camera at the mean itself has no ray: weight 1.
  CHECK(f.weight(0, 0, 0, 0, {0, 0, 0}) == 1.f);
}

TEST_CASE("Eq. R5: balls and needles weigh 1 in every view; the normal follows the rotation") {
  for (const GaussianScene& s : {one(0.2f, 0.2f, 0.2f), one(1.f, 0.01f, 0.01f)}) {
    const Foreshortening f = Foreshortening::of(s, {});
    CHECK(f.weight(0, 0, 0, 0, {0, 0, -5}) == Approx(1.f));
    CHECK(f.weight(0, 0, 0, 0, {0, 5, 0}) == Approx(1.f));
  }
  // Half-flat: scales (1, 0.5, 0.25): smallest axis z, s_b = 0.5, phi = 1 - 0.25 / 0.5 = 0.5.
  // Edge-on: omega = 0.5.
  const Foreshortening half = Foreshortening::of(one(1.f, 0.5f, 0.25f), {});
  CHECK(half.weight(0, 0, 0, 0, {4, 0, 0}) == Approx(0.5f));
  // A disc rotated 90 degrees about y: its normal z becomes x (R = rot(q), column 3).
  const float h = std::sqrt(0.5f);
  const GaussianScene rotated = one(1.f, 1.f, 0.01f, {h, 0, h, 0});
  CHECK(Foreshortening::normal_and_flatness(rotated, 0).first.cwiseAbs().isApprox(Eigen::Vector3f::UnitX(), 1e-5f));
  const Foreshortening fr = Foreshortening::of(rotated, {});
  CHECK(fr.weight(0, 0, 0, 0, {-5, 0, 0}) == Approx(1.f));
  CHECK(fr.weight(0, 0, 0, 0, {0, 0, -5}) == Approx(0.01f).margin(1e-5));
  // Candidates: the k-th entry is the k-th listed Gaussian.
  GaussianScene two;
  two.resize(2);
  two.set(0, Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), {1, 0, 0, 0}, 0.f);
  two.set(1, Eigen::Vector3f::Zero(), Eigen::Vector3f(0, 0, std::log(0.01f)), {1, 0, 0, 0}, 0.f);
  const Foreshortening sub = Foreshortening::of(two, {1});
  CHECK(sub.one_minus_phi.size() == 1);
  CHECK(sub.weight(0, 0, 0, 0, {0, 5, 0}) == Approx(0.01f));
}
