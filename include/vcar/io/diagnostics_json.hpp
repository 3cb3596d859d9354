#pragma once
// Diagnostics as JSON, the way report.json holds them (docs/cli.md): one entry per field of
// Diagnostics::for_each_field at its report key ("counts.coarse" -> {"counts": {"coarse": n}}),
// vectors as [x, y, z], the sampled cameras as their positions (and their number as
// "sampled_views"), the sphere as {"center", "radius", "inliers"}, the timings as
// {stage: seconds}.
#include <cstddef>
#include <string>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "vcar/algo/diagnostics.hpp"

namespace vcar::io {

inline nlohmann::json diagnostics_json(const Diagnostics& d) {
  nlohmann::json j = nlohmann::json::object();
  auto put = [&](const std::string& key, nlohmann::json v) {
    nlohmann::json* at = &j;
    for (std::size_t b = 0, e; (e = key.find('.', b)) != std::string::npos; b = e + 1) at = &(*at)[key.substr(b, e - b)];
    (*at)[key.substr(key.rfind('.') + 1)] = std::move(v);
  };
  Diagnostics::for_each_field(d, [&](const char*, const char* key, const auto& v) {
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, Eigen::Vector3f>) {
      put(key, {v.x(), v.y(), v.z()});
    } else if constexpr (std::is_same_v<T, std::vector<Camera>>) {
      nlohmann::json a = nlohmann::json::array();
      for (const Camera& c : v) {
        const Eigen::Vector3f p = c.position();
        a.push_back({p.x(), p.y(), p.z()});
      }
      put("sampled_views", v.size());
      put(key, std::move(a));
    } else if constexpr (std::is_same_v<T, ObjectSphere>) {
      put(key, {{"center", {v.c.x(), v.c.y(), v.c.z()}}, {"radius", v.r}, {"inliers", v.inliers}});
    } else if constexpr (std::is_same_v<T, std::vector<std::pair<std::string, double>>>) {
      nlohmann::json t = nlohmann::json::object();
      for (const auto& [stage, s] : v) t[stage] = s;
      put(key, std::move(t));
    } else {
      put(key, v);
    }
  });
  return j;
}

}  // namespace vcar::io
