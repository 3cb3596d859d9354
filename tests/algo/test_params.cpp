#include <catch2/catch.hpp>

#include <cmath>
#include <set>

#include "vcar/algo/params.hpp"

using vcar::VcarParams;

namespace {
std::string where_of(VcarParams p) {
  try {
    p.validate();
  } catch (const vcar::Error& e) {
    return e.where();
  }
  return "";
}
}  // namespace

TEST_CASE("presets carry the paper's and the reference code's values") {
  const auto n = VcarParams::nvos();
  CHECK(n.tau_coarse == 0.5f);
  CHECK(n.tau_fine == 0.8f);
  CHECK(n.rho_min == 0.2f);
  CHECK(n.K == 2000);
  CHECK(n.Delta_th_deg == 90.f);
  CHECK(n.eta == 1.2f);
  CHECK(n.S1 * n.S2 == 32);
  CHECK(n.phi_s_deg == -60.f);
  CHECK(n.phi_e_deg == 60.f);
  CHECK(n.sigma_c == 3.f);
  CHECK(n.rho == 0.6f);
  CHECK(n.f_min == 0.1f);
  CHECK(n.boundary_samples == 129);
  CHECK_FALSE(n.occlusion_aware);
  CHECK_FALSE(n.gap_directed);
  const auto l = VcarParams::lerf();
  CHECK(l.tau_coarse == 0.4f);
  CHECK(l.tau_fine >= 0.5f);
  CHECK(l.tau_fine <= 0.7f);
  const auto c = VcarParams::reference_code();
  CHECK(c.rho_min == 0.01f);
  CHECK(c.tau_fine == 0.9f);
  CHECK(c.eta == 1.1f);
  CHECK(c.phi_s_deg == 60.f);
  CHECK(c.phi_e_deg == -10.f);
  CHECK(c.sampled_intrinsics == vcar::SampledIntrinsics::ReferenceCode45Fov);
  CHECK(c.abr_variant == vcar::AbrVariant::ReferenceCode);
  CHECK(c.background == Eigen::Vector3f::Ones());
  CHECK(c.min_mask_fraction == 0.001f);
  CHECK(c.min_frame_content == 0.005f);
  CHECK(n.min_mask_fraction == 0.f);
  for (const auto& p : {n, l, c}) CHECK_NOTHROW(p.validate());
}

TEST_CASE("validate names the parameter at fault") {
  VcarParams p;
  p.tau_coarse = 1.5f;
  CHECK(where_of(p) == "tau_coarse");
  p = {}; p.tau_fine = -0.1f;  CHECK(where_of(p) == "tau_fine");
  p = {}; p.K = 0;             CHECK(where_of(p) == "K");
  p = {}; p.S2 = 0;            CHECK(where_of(p) == "S2");
  p = {}; p.f_min = 0.f;       CHECK(where_of(p) == "f_min");
  p = {}; p.f_min = 1.f;       CHECK(where_of(p) == "");  // (0, 1]
  p = {}; p.f_min = 1.01f;     CHECK(where_of(p) == "f_min");
  p = {}; p.rho_min = 2.f;     CHECK(where_of(p) == "rho_min");
  p = {}; p.eta = 0.f;         CHECK(where_of(p) == "eta");
  p = {}; p.phi_e_deg = 95.f;  CHECK(where_of(p) == "phi_e_deg");
}

TEST_CASE("the robust preset (docs/robust.md) switches on each mechanism beyond the paper; the paper presets none") {
  const auto r = VcarParams::robust();
  CHECK(r.evidence.occlusion);
  CHECK(r.reliability.enabled);      // R13
  CHECK(r.tau_fine == VcarParams::nvos().tau_fine);  // the paper's, where R14 is off
  CHECK(r.undershoot.band > 0.f);
  CHECK(r.valley.enabled);                            // R14
  CHECK(r.strict.tau > r.tau_fine);
  CHECK(r.abr_lowpass);  // as the paper; R8 reads own footprints after a split vote
  CHECK(r.snap.enabled);                  // R11-R12
  CHECK(r.evidence.kappa == 2.f);
  CHECK(r.phi_s_deg == VcarParams::reference_code().phi_e_deg);  // the spiral from the code's lowest elevation
  CHECK(r.phi_e_deg == VcarParams::nvos().phi_e_deg);
  CHECK(r.robust_vote());
  CHECK_NOTHROW(r.validate());
  for (const auto& p : {VcarParams::nvos(), VcarParams::lerf(), VcarParams::reference_code()}) {
    CHECK_FALSE(p.robust_vote());
    CHECK_FALSE(p.reliability.enabled);
    CHECK(p.undershoot.band == 0.f);
    CHECK(p.strict.tau <= p.tau_fine);  // Eq. R7 off
    CHECK_FALSE(p.valley.enabled);      // Eq. R14 off
    CHECK(p.abr_lowpass);
    CHECK_FALSE(p.snap.enabled);            // Eq. R11-R12 off
  }
  CHECK(VcarParams::reference_code().force_fine_round);
  CHECK_FALSE(VcarParams::nvos().force_fine_round);
  // By name, as the command line and the Python module use them.
  CHECK(VcarParams::preset("robust").undershoot.band == r.undershoot.band);
  CHECK(VcarParams::preset("reference_code").tau_fine == 0.9f);
  CHECK_THROWS_WITH(VcarParams::preset("paper"), Catch::Contains("robust, nvos, lerf, reference_code"));
}

TEST_CASE("validate: rho = 1 can never trigger the strict gate, and the robust parameters have ranges") {
  VcarParams p;
  p.rho = 1.f;            CHECK(where_of(p) == "rho");
  p = {}; p.rho = 0.99f;  CHECK(where_of(p) == "");
  p = {}; p.evidence.kappa = -1.f;      CHECK(where_of(p) == "kappa");
  p = {}; p.undershoot.band = -1.f; CHECK(where_of(p) == "undershoot_band");
  p = {}; p.undershoot.band = NAN;  CHECK(where_of(p) == "undershoot_band");
  p = {}; p.undershoot.band = 2.f;  CHECK(where_of(p) == "");
  p = {}; p.strict.tau = 1.2f;      CHECK(where_of(p) == "tau_strict");
  // Each mechanism alone makes the vote RobustVoting's.
  p = {}; p.reliability.enabled = true; CHECK(p.robust_vote());
  p = {}; p.evidence.occlusion = true;   CHECK(p.robust_vote());
  p = {}; p.undershoot.band = 1.f;  CHECK(p.robust_vote());
}
