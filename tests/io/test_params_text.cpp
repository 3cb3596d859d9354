#include <catch2/catch.hpp>

#include <set>

#include "vcar/io/params_text.hpp"

using vcar::VcarParams;

TEST_CASE("set_parameter(key, value) parses every kind of field and rejects unknown keys") {
  VcarParams p;
  vcar::io::set_parameter(p, "tau_fine", "0.65");
  CHECK(p.tau_fine == Approx(0.65));
  vcar::io::set_parameter(p, "K=500");
  CHECK(p.K == 500);
  vcar::io::set_parameter(p, "enable_sss", "false");
  CHECK_FALSE(p.enable_sss);
  vcar::io::set_parameter(p, "spiral_variant", "ReferenceCode");
  CHECK(p.spiral_variant == vcar::SpiralVariant::ReferenceCode);
  vcar::io::set_parameter(p, "sampled_intrinsics", "ReferenceCode45Fov");
  CHECK(p.sampled_intrinsics == vcar::SampledIntrinsics::ReferenceCode45Fov);
  vcar::io::set_parameter(p, "background", "1,0.5,0");
  CHECK(p.background == Eigen::Vector3f(1, 0.5f, 0));
  CHECK_THROWS_AS(vcar::io::set_parameter(p, "K", "12x"), vcar::Error);
  CHECK_THROWS_AS(vcar::io::set_parameter(p, "tau_fine", ""), vcar::Error);
  CHECK_THROWS_AS(vcar::io::set_parameter(p, "enable_abr", "maybe"), vcar::Error);
  CHECK_THROWS_AS(vcar::io::set_parameter(p, "spiral_variant", "Other"), vcar::Error);
  CHECK_THROWS_AS(vcar::io::set_parameter(p, "background", "1,2"), vcar::Error);
  try {
    vcar::io::set_parameter(p, "tau", "0.5");
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    const std::string msg = e.what();
    CHECK(msg.find("tau_coarse") != std::string::npos);  // lists the valid keys
    CHECK(msg.find("f_min") != std::string::npos);
  }
  // The four fields that became one switch (Eq. R11-R12) name it.
  vcar::io::set_parameter(p, "snap", "false");
  CHECK_FALSE(p.snap.enabled);
  for (const char* merged : {"overshoot_min", "grow_max", "overshoot_margin", "grow_margin"}) {
    try {
      vcar::io::set_parameter(p, merged, "0");
      FAIL("expected an error");
    } catch (const vcar::Error& e) {
      CHECK(std::string(e.what()).find("'snap'") != std::string::npos);
    }
  }
  // R6d's threshold, replaced by Eq. R14, names its successor.
  try {
    vcar::io::set_parameter(p, "undershoot_tau", "0.7");
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(std::string(e.what()).find("'valley'") != std::string::npos);
  }
  // Eq. R10's radius, removed, says so (not "unknown parameter").
  try {
    vcar::io::set_parameter(p, "coplanar_radius", "0.75");
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(std::string(e.what()).find("R10") != std::string::npos);
    CHECK(std::string(e.what()).find("removed") != std::string::npos);
  }
  // Every field is reachable by its own name, and names are unique.
  std::set<std::string> names;
  std::size_t count = 0;
  VcarParams::for_each_field(p, [&](const char* name, auto&) { names.insert(name); ++count; });
  CHECK(names.size() == count);
  CHECK(names.count("boundary_samples") == 1);
  CHECK(names.count("depth_tolerance") == 1);
}

TEST_CASE("params_json writes every field under its name in the form set_parameter reads back") {
  VcarParams p = VcarParams::reference_code();
  p.background = {1, 0.5f, 0};
  const nlohmann::json j = vcar::io::params_json(p);
  CHECK(j.at("tau_fine") == 0.9);  // 0.9, not 0.899999976
  CHECK(j.at("spiral_variant") == "Paper");
  CHECK(j.at("abr_variant") == "ReferenceCode");
  CHECK(j.at("sampled_intrinsics") == "ReferenceCode45Fov");
  CHECK(j.at("force_fine_round") == true);
  VcarParams q = VcarParams::robust();
  for (const auto& [key, value] : j.items()) {
    std::string text;
    if (value.is_array()) text = std::to_string(value[0].get<double>()) + "," + std::to_string(value[1].get<double>()) + "," + std::to_string(value[2].get<double>());
    else if (value.is_string()) text = value.get<std::string>();
    else if (value.is_boolean()) text = value.get<bool>() ? "true" : "false";
    else text = value.dump();
    vcar::io::set_parameter(q, key, text);
  }
  CHECK(vcar::io::params_json(q) == j);
}
