#pragma once
// What the compact splat formats (.splat, compressed PLY, SPZ) have in common: they store
// activated values (opacity after the sigmoid, DC colour as 0.5 + C0 f_dc) in 8 bits, and the
// scene model keeps the raw ones (opacity logit, f_dc; docs/formats.md). Also the whole-file read
// they all start with.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"

namespace vcar::io {

// Zeroth SH basis constant: rgb = 0.5 + sh_C0 * f_dc (degree-0 colour of the 3DGS renderer).
inline constexpr float sh_C0 = 0.28209479177387814f;

// An 8-bit alpha b stands for alpha in [(b - 0.5) / 255, (b + 0.5) / 255]; b = 0 and b = 255
// would have an infinite logit, so alpha is clamped to the edge of those cells, half a step
// from 0 and 1 (logit -6.24 .. 6.24): finite, and within the quantisation of the stored byte.
inline float opacity_logit_from_alpha(float alpha) {
  constexpr float lo = 0.5f / 255.f, hi = 1.f - 0.5f / 255.f;
  const float a = std::clamp(alpha, lo, hi);
  return std::log(a / (1.f - a));
}

inline float sigmoid(float x) { return 1.f / (1.f + std::exp(-x)); }

// Nearest byte to v * 255 (v in [0, 1], clamped).
inline std::uint8_t unit_to_byte(float v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(static_cast<double>(v) * 255.0), 0L, 255L));
}

// f_dc of a degree-0 colour c (inverse of c = 0.5 + sh_C0 f_dc).
inline float dc_from_colour(float c) { return (c - 0.5f) / sh_C0; }
inline float colour_from_dc(float f_dc) { return 0.5f + sh_C0 * f_dc; }

namespace detail {

// The whole file; `what` names the format in the messages ("SPZ file").
inline std::vector<std::uint8_t> read_whole_file(const std::filesystem::path& path, const std::string& what) {
  const std::string where = path.string();
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw Error("cannot open " + what + ": " + ec.message(), where);
  if (size > (std::uintmax_t{1} << 34)) throw Error(what + " is larger than 16 GiB", where);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open " + what, where);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<std::size_t>(in.gcount()) != bytes.size()) throw Error("cannot read " + what, where);
  return bytes;
}

// Little-endian loads from a byte buffer (the caller has checked the bounds).
inline std::uint32_t load_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
inline std::uint64_t load_u64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(load_u32(p)) | static_cast<std::uint64_t>(load_u32(p + 4)) << 32;
}
inline float load_f32(const std::uint8_t* p) {
  const std::uint32_t u = load_u32(p);
  float f;
  static_assert(sizeof f == sizeof u);
  std::memcpy(&f, &u, 4);
  return f;
}
inline void store_u32(std::string& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xffu));
}
inline void store_f32(std::string& out, float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  store_u32(out, u);
}

}  // namespace detail

}  // namespace vcar::io
