#pragma once
// antimatter15 `.splat` files (the WebGL viewer's format, convert.py): no header, 32 bytes per
// Gaussian, little-endian:
//   float32 x y z | float32 s0 s1 s2 (LINEAR scales, exp of the log-scales) |
//   uint8 r g b a (r = (0.5 + C0 f_dc_0) * 255, a = sigmoid(opacity) * 255) |
//   uint8 q0 q1 q2 q3 (q = (w, x, y, z) / |q| * 128 + 128)
// No SH beyond the DC colour, no axes change (same frame as the Inria PLY). Reading converts to
// the scene model (log-scales, opacity logit, f_dc; docs/formats.md); the file's order is kept
// (convert.py sorts by size x opacity, this writer does not: index i of the scene is record i).
// Writing drops SH degree > 0 and extras, clamps colours to [0, 1], rounds to the nearest byte.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/compact_values.hpp"

namespace vcar::io {

inline constexpr std::size_t splat_record_bytes = 32;

// Decodes .splat bytes (the whole file); `where` names the file in errors.
inline GaussianScene decode_splat(const std::uint8_t* data, std::size_t size, const std::string& where) {
  if (size == 0) throw Error(".splat file is empty", where);
  if (size % splat_record_bytes != 0)
    throw Error(".splat file size " + std::to_string(size) + " is not a multiple of 32 bytes (truncated, or not a .splat file)", where);
  const std::size_t n = size / splat_record_bytes;
  GaussianScene s;
  s.resize(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* r = data + i * splat_record_bytes;
    for (int d = 0; d < 3; ++d) s.mean[d][i] = detail::load_f32(r + 4 * d);
    for (int d = 0; d < 3; ++d) {
      const float scale = detail::load_f32(r + 12 + 4 * d);
      if (!(scale >= 0.f) || !std::isfinite(scale))
        throw Error("Gaussian " + std::to_string(i) + " (byte " + std::to_string(i * splat_record_bytes + 12 + 4 * d) +
                    ") has scale " + std::to_string(scale) + ": linear scales must be finite and >= 0", where);
      // exp(log s) underflows to 0 in float32 below log s = -103.3; keep the smallest positive scale.
      s.log_scale[d][i] = std::log(std::max(scale, std::numeric_limits<float>::denorm_min()));
    }
    for (int c = 0; c < 3; ++c) s.sh[i * 3 + static_cast<std::size_t>(c)] = dc_from_colour(static_cast<float>(r[24 + c]) / 255.f);
    s.opacity_logit[i] = opacity_logit_from_alpha(static_cast<float>(r[27]) / 255.f);
    for (int k = 0; k < 4; ++k) s.rotation[k][i] = (static_cast<float>(r[28 + k]) - 128.f) / 128.f;
  }
  s.validate(where);
  return s;
}

// Reads an antimatter15 .splat file.
inline GaussianScene read_splat(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = detail::read_whole_file(path, ".splat file");
  return decode_splat(bytes.data(), bytes.size(), path.string());
}

// The same from the file's bytes in memory; `name` stands for the file in errors.
inline GaussianScene read_splat(std::span<const std::uint8_t> bytes, const std::string& name) {
  return decode_splat(bytes.data(), bytes.size(), name);
}

// The .splat bytes of `scene` (every Gaussian, in scene order).
inline std::string encode_splat(const GaussianScene& scene) {
  const std::size_t n = scene.size(), B3 = static_cast<std::size_t>(scene.sh_coeffs()) * 3;
  std::string out;
  out.reserve(n * splat_record_bytes);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) detail::store_f32(out, scene.mean[d][i]);
    for (int d = 0; d < 3; ++d) detail::store_f32(out, std::exp(scene.log_scale[d][i]));
    for (std::size_t c = 0; c < 3; ++c) out.push_back(static_cast<char>(unit_to_byte(colour_from_dc(scene.sh[i * B3 + c]))));
    out.push_back(static_cast<char>(unit_to_byte(sigmoid(scene.opacity_logit[i]))));
    float qq = 0.f;
    for (int k = 0; k < 4; ++k) qq += scene.rotation[k][i] * scene.rotation[k][i];
    const float inv = 1.f / std::sqrt(qq);
    for (int k = 0; k < 4; ++k) {
      const long b = std::lround(static_cast<double>(scene.rotation[k][i] * inv) * 128.0 + 128.0);
      out.push_back(static_cast<char>(std::clamp(b, 0L, 255L)));
    }
  }
  return out;
}

// Writes `scene` as .splat (atomic: temp file + rename); see the top of this file for what is lost.
inline void write_splat(const std::filesystem::path& path, const GaussianScene& scene) {
  scene.validate(path.string());
  const std::string bytes = encode_splat(scene);
  atomic_write(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace vcar::io
