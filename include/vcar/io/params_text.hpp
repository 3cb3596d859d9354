#pragma once
// VcarParams as text: `--set key=value` parsing and the JSON object written to report.json.
// One table of names (VcarParams::for_each_field) serves both, so the two cannot drift apart.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>

#include "vcar/algo/params.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/json_file.hpp"

namespace vcar::io {

namespace detail {

template <class E>
struct EnumNames;
template <>
struct EnumNames<SpiralVariant> {
  static constexpr std::pair<const char*, SpiralVariant> names[] = {{"Paper", SpiralVariant::Paper},
                                                                    {"ReferenceCode", SpiralVariant::ReferenceCode}};
};
template <>
struct EnumNames<SampledIntrinsics> {
  static constexpr std::pair<const char*, SampledIntrinsics> names[] = {
      {"ReferenceView", SampledIntrinsics::ReferenceView}, {"ReferenceCode45Fov", SampledIntrinsics::ReferenceCode45Fov}};
};
template <>
struct EnumNames<AbrVariant> {
  static constexpr std::pair<const char*, AbrVariant> names[] = {{"Paper", AbrVariant::Paper},
                                                                 {"ReferenceCode", AbrVariant::ReferenceCode}};
};

inline void parse_value(const std::string& key, const std::string& s, float& out) {
  errno = 0;
  char* end = nullptr;
  const float v = std::strtof(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno != 0 || !std::isfinite(v))
    throw Error("expected a number, got '" + s + "'", key);
  out = v;
}
inline void parse_value(const std::string& key, const std::string& s, int& out) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || end != s.c_str() + s.size() || errno != 0 || v < -2147483647L || v > 2147483647L)
    throw Error("expected an integer, got '" + s + "'", key);
  out = static_cast<int>(v);
}
inline void parse_value(const std::string& key, const std::string& s, bool& out) {
  if (s == "true" || s == "1" || s == "on") out = true;
  else if (s == "false" || s == "0" || s == "off") out = false;
  else throw Error("expected true/false, got '" + s + "'", key);
}
inline void parse_value(const std::string& key, const std::string& s, Eigen::Vector3f& out) {
  Eigen::Vector3f v;
  std::size_t start = 0;
  for (int c = 0; c < 3; ++c) {
    const std::size_t comma = s.find(',', start);
    if ((c < 2) == (comma == std::string::npos)) throw Error("expected r,g,b, got '" + s + "'", key);
    parse_value(key, s.substr(start, c < 2 ? comma - start : std::string::npos), v[c]);
    start = comma + 1;
  }
  out = v;
}
template <class E>
  requires std::is_enum_v<E>
void parse_value(const std::string& key, const std::string& s, E& out) {
  std::string valid;
  for (const auto& [n, e] : EnumNames<E>::names) {
    if (s == n) { out = e; return; }
    valid += (valid.empty() ? "" : ", ") + std::string(n);
  }
  throw Error("unknown value '" + s + "'; valid: " + valid, key);
}

template <class T>
nlohmann::json value_json(const T& v) {
  if constexpr (std::is_same_v<T, float>) {
    return json_float(v);  // 0.7, not 0.699999988
  } else if constexpr (std::is_same_v<T, Eigen::Vector3f>) {
    return {json_float(v[0]), json_float(v[1]), json_float(v[2])};
  } else if constexpr (std::is_enum_v<T>) {
    for (const auto& [n, e] : EnumNames<T>::names)
      if (e == v) return n;  // the names --set accepts
    return static_cast<int>(v);
  } else {
    return v;
  }
}

}  // namespace detail

// Comma-separated list of the parameter names (for error messages and --help).
inline std::string parameter_keys() {
  std::string out;
  VcarParams p;
  VcarParams::for_each_field(p, [&](const char* name, auto&) { out += (out.empty() ? "" : ", ") + std::string(name); });
  return out;
}

// `--set key=value`: key is a field name of VcarParams; value as the field's type (numbers,
// true/false/1/0/on/off, enum names Paper/ReferenceCode/ReferenceView/ReferenceCode45Fov,
// colours "r,g,b"). vcar::Error naming the key on a bad value or an unknown key.
inline void set_parameter(VcarParams& p, std::string_view key, std::string_view value) {
  bool found = false;
  VcarParams::for_each_field(p, [&](const char* name, auto& field) {
    if (key != name) return;
    found = true;
    detail::parse_value(std::string(name), std::string(value), field);
  });
  if (!found) {
    for (const char* merged : {"overshoot_min", "overshoot_margin", "grow_max", "grow_margin"})  // until 2026-12-03
      if (key == merged)
        throw Error("'" + std::string(key) + "' is now part of 'snap' (true/false: Eq. R11-R12 together, "
                    "docs/robust.md)", "--set");
    if (key == "undershoot_tau")  // until 2026-12-06
      throw Error("'undershoot_tau' (Eq. R6d) was replaced by 'valley' (true/false: the fine threshold at the fine "
                  "vote's valley, Eq. R14, docs/robust.md)", "--set");
    if (key == "coplanar_radius")  // until 2026-12-06
      throw Error("'coplanar_radius' (Eq. R10) was removed: on the field's held-out seeds it cost as much as it "
                  "paid (docs/robust.md, appendix)", "--set");
    throw Error("unknown parameter '" + std::string(key) + "'; valid keys: " + parameter_keys(), "--set");
  }
}
// "key=value" form of set_parameter.
inline void set_parameter(VcarParams& p, std::string_view assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos) throw Error("expected key=value, got '" + std::string(assignment) + "'", "--set");
  set_parameter(p, assignment.substr(0, eq), assignment.substr(eq + 1));
}

// Every parameter by name, values as set_parameter reads them back.
inline nlohmann::json params_json(const VcarParams& p) {
  nlohmann::json j = nlohmann::json::object();
  VcarParams::for_each_field(p, [&](const char* name, const auto& field) { j[name] = detail::value_json(field); });
  return j;
}

}  // namespace vcar::io
