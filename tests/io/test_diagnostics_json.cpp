#include <catch2/catch.hpp>

#include <string>

#include "vcar/io/diagnostics_json.hpp"

TEST_CASE("diagnostics_json: every field at its report.json key, by hand") {
  vcar::Diagnostics d;
  d.n_scene = 100; d.n_coarse = 40; d.n_fine = 30; d.n_final = 30;
  d.valid_cameras = 7; d.max_gap_deg = 120.5; d.gap_direction = {0.f, 0.f, 1.f};
  d.sss_triggered = true; d.tau_fine_applied = 0.8f; d.undershoot_applied = false; d.fine_split = true;
  const vcar::Intrinsics k{64, 48, 50.f, 50.f, 32.f, 24.f};
  d.sampled_cameras = {vcar::Camera::look_at({1, 2, 3}, {0, 0, 0}, {0, 0, 1}, k, "s0")};
  d.sphere.c = {1.f, 2.f, 3.f}; d.sphere.r = 0.5f; d.sphere.inliers = 38;
  d.abr_flagged = 9; d.abr_compressed = 8; d.abr_retraced = 2; d.abr_masks_widened = 1;
  d.overshoot_eroded = 4; d.masks_grown = 5; d.masks_missing = 6;
  d.mask_store_bytes = 1234; d.note = "n";
  d.timings_s = {{"coarse_voting", 0.25}, {"abr", 0.5}};
  const nlohmann::json j = vcar::io::diagnostics_json(d);
  CHECK(j["counts"] == nlohmann::json({{"scene", 100}, {"coarse", 40}, {"fine", 30}, {"final", 30}}));
  CHECK(j["valid_cameras"] == 7);
  CHECK(j["max_gap_deg"] == 120.5);
  CHECK(j["gap_direction"] == nlohmann::json({0.0, 0.0, 1.0}));
  CHECK(j["sss_triggered"] == true);
  CHECK(j["tau_fine_applied"].get<float>() == 0.8f);
  CHECK(j["undershoot_applied"] == false);
  CHECK(j["fine_split"] == true);
  CHECK(j["sampled_views"] == 1);
  REQUIRE(j["sampled_positions"].size() == 1);
  CHECK(j["sampled_positions"][0][2].get<float>() == Approx(3.f));
  CHECK(j["sphere"]["center"] == nlohmann::json({1.0, 2.0, 3.0}));
  CHECK(j["sphere"]["radius"] == 0.5);
  CHECK(j["sphere"]["inliers"] == 38);
  CHECK(j["abr"] == nlohmann::json({{"flagged", 9}, {"compressed", 8}, {"retraced", 2}, {"masks_widened", 1}}));
  CHECK(j["overshoot_eroded"] == 4);
  CHECK(j["masks_grown"] == 5);
  CHECK(j["masks_missing"] == 6);
  CHECK(j["mask_store_bytes"] == 1234);
  CHECK(j["note"] == "n");
  CHECK(j["timings_s"] == nlohmann::json({{"coarse_voting", 0.25}, {"abr", 0.5}}));
  // Nothing else: 23 fields (4 under counts, 4 under abr) and sampled_views.
  CHECK(j.size() == 23 - 4 - 4 + 2 + 1);
  int fields = 0;
  vcar::Diagnostics::for_each_field(d, [&](const char*, const char*, const auto&) { ++fields; });
  CHECK(fields == 23);
}
