#pragma once
// Labels PLY: the whole scene (every Gaussian, in scene order, unchanged) as an Inria PLY with a
// last vertex property `int label` naming each Gaussian's object (0, 1, ... in the order the
// objects were given; -1 for none). Written by `vcar segment --prompts` (several objects in one
// run); read back by read_ply as an extra column "label". An extra named "label" in the scene is
// replaced.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/ply.hpp"

namespace vcar::io {

inline void write_label_ply(const std::filesystem::path& path, const GaussianScene& scene,
                            const std::vector<std::int32_t>& label, bool binary = true) {
  const std::string where = path.string();
  if (label.size() != scene.size())
    throw Error("labels has " + std::to_string(label.size()) + " entries, the scene " + std::to_string(scene.size()) + " Gaussians", where);
  detail::check_writable(path, scene, nullptr, nullptr);
  atomic_write(path, [&](std::ostream& out) {
    detail::write_ply_stream(out, scene, nullptr, nullptr, binary, nullptr, &label);
  });
}

}  // namespace vcar::io
