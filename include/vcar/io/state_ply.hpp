#pragma once
// SuperSplat's per-splat flags in a PLY: the whole scene (Inria layout, every Gaussian unchanged,
// in scene order) plus a last vertex property `uchar state`, bit 0 selected, bit 1 locked, bit 2
// deleted. Opened in SuperSplat, a segmentation written this way shows as the current selection.
// Read back with read_ply (or read_scene): `state` is kept as an extra column, state_of() returns it.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/ply.hpp"

namespace vcar::io {

namespace splat_state {
inline constexpr std::uint8_t selected = 1, locked = 2, deleted = 4;
}

// Writes `scene` with one state byte per Gaussian (atomic). An extra column named "state" in the
// scene is replaced by `state`.
inline void write_state_ply(const std::filesystem::path& path, const GaussianScene& scene,
                            const std::vector<std::uint8_t>& state, bool binary = true) {
  const std::string where = path.string();
  if (state.size() != scene.size())
    throw Error("state has " + std::to_string(state.size()) + " bytes, the scene " + std::to_string(scene.size()) + " Gaussians", where);
  detail::check_writable(path, scene, nullptr, nullptr);
  atomic_write(path, [&](std::ostream& out) { detail::write_ply_stream(out, scene, nullptr, nullptr, binary, &state); });
}

// The state bytes `selected` on the Gaussians `indices`, 0 elsewhere.
inline std::vector<std::uint8_t> selection_state(std::size_t n, const std::vector<Index>& indices) {
  std::vector<std::uint8_t> s(n, 0);
  for (Index i : indices) {
    if (i >= n) throw Error("index " + std::to_string(i) + " out of range for a scene of " + std::to_string(n), "selection");
    s[i] = splat_state::selected;
  }
  return s;
}

// The state column of a scene read from a state PLY (empty when it has none). Values must be
// integers 0..255 (the property is a uchar; any other type that holds such values is accepted).
inline std::vector<std::uint8_t> state_of(const GaussianScene& scene, const std::string& where = "scene") {
  const std::size_t E = scene.extra_names.size();
  for (std::size_t e = 0; e < E; ++e) {
    if (scene.extra_names[e] != "state") continue;
    std::vector<std::uint8_t> s(scene.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
      const float v = scene.extra[i * E + e];
      if (!(v >= 0.f && v <= 255.f) || std::floor(v) != v)
        throw Error("Gaussian " + std::to_string(i) + " has state " + std::to_string(v) + " (expected an integer 0..255)", where);
      s[i] = static_cast<std::uint8_t>(v);
    }
    return s;
  }
  return {};
}

}  // namespace vcar::io
