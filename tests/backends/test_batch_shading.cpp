#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "vcar/backends/cpu/batch_shading.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/spherical_harmonics.hpp"

// shade_batch is sh_to_rgb (conventions §3) for a batch: the same basis and the same sums in the
// same order, so the only differences are fused multiply-adds (a few ulp).
TEST_CASE("batch shading equals sh_to_rgb lane by lane, every degree, any lane set") {
  constexpr int L = static_cast<int>(vcar::cpu::Lane::size);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  const float eye[3] = {0.3f, -0.2f, -2.f};
  for (int degree = 0; degree <= 3; ++degree) {
    const int n = 5 * L + 3;
    vcar::GaussianScene sc;
    sc.resize(n, degree);
    for (float& v : sc.sh) v = 0.8f * U(rng);
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3f mu(2.f * U(rng), 2.f * U(rng), 2.f * U(rng));
      if (i % 7 == 2) mu = Eigen::Vector3f(eye[0], eye[1], eye[2]);  // at the eye: DC term only
      sc.set(i, mu, Eigen::Vector3f::Zero(), Eigen::Vector4f(1, 0, 0, 0), 0.f);
    }
    int compared = 0, clamped = 0;
    for (int trial = 0; trial < 640 / L; ++trial) {  // 640 lanes on every target
      // Scattered scene indices (as with a subset), some lanes off.
      std::size_t idx[L];
      alignas(64) float mu[3][L];
      std::uint32_t lanes = 0;
      for (int l = 0; l < L; ++l) {
        idx[l] = static_cast<std::size_t>(rng() % n);
        for (int d = 0; d < 3; ++d) mu[d][l] = sc.mean[d][idx[l]];
        if (rng() % 4 != 0) lanes |= std::uint32_t{1} << l;
      }
      const vcar::cpu::Lane m[3] = {vcar::cpu::Lane::load_aligned(mu[0]), vcar::cpu::Lane::load_aligned(mu[1]),
                                    vcar::cpu::Lane::load_aligned(mu[2])};
      alignas(64) float rgb[3][L];
      for (auto& row : rgb)
        for (float& v : row) v = -7.f;  // lanes off must keep this
      vcar::cpu::shade_batch(sc, idx, lanes, m, eye, rgb);
      for (int l = 0; l < L; ++l) {
        if (!((lanes >> l) & 1u)) {
          CHECK((rgb[0][l] == -7.f && rgb[1][l] == -7.f && rgb[2][l] == -7.f));
          continue;
        }
        const Eigen::Vector3f ref = vcar::gaussian_rgb(sc, idx[l], Eigen::Vector3f(eye[0], eye[1], eye[2]));
        for (int c = 0; c < 3; ++c) {
          CHECK(std::abs(rgb[c][l] - ref[c]) <= 1e-6f);
          clamped += ref[c] == 0.f;
          ++compared;
        }
      }
    }
    CHECK(compared > 1000);
    if (degree > 0) CHECK(clamped > 0);  // the max(0, .) clamp is exercised
  }
}
