#pragma once
// One entry point for the scene files splat users exchange, chosen by CONTENT (the name only
// decides for .splat, which has no signature): Inria PLY and PlayCanvas compressed PLY (first
// line "ply"; compressed when the header has a `chunk` element and packed_* vertex properties),
// Niantic SPZ (gzip magic 1f 8b, or the NGSP magic of v4) and antimatter15 .splat. Conversions
// of each format to the scene model: docs/formats.md.
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <span>
#include <string>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/byte_stream.hpp"
#include "vcar/io/compressed_ply.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/splat_file.hpp"
#include "vcar/io/spz.hpp"

namespace vcar::io {

enum class SceneFormat { ply, compressed_ply, spz, splat };

inline const char* scene_format_name(SceneFormat f) {
  switch (f) {
    case SceneFormat::ply: return "PLY";
    case SceneFormat::compressed_ply: return "compressed PLY";
    case SceneFormat::spz: return "SPZ";
    case SceneFormat::splat: return ".splat";
  }
  return "?";
}

namespace detail {
inline std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}
}  // namespace detail

namespace detail {
// Whether the first bytes `head` (got of them) open a PLY file: "ply" and a line end.
inline bool ply_signature(const unsigned char* head, std::size_t got) {
  return got >= 4 && head[0] == 'p' && head[1] == 'l' && head[2] == 'y' && (head[3] == '\n' || head[3] == '\r');
}

// The format from the first bytes `head` (got of them) of a stream holding the whole file;
// `in` is read again (from its start) for a PLY header. `name` decides only for .splat.
inline SceneFormat scene_format_of(const unsigned char* head, std::size_t got, std::istream& in,
                                   const std::filesystem::path& name, const std::string& where) {
  if (ply_signature(head, got)) {
    in.clear();
    in.seekg(0);
    const PlyHeader h = parse_ply_header(in, where);
    return is_compressed_ply_header(h) ? SceneFormat::compressed_ply : SceneFormat::ply;
  }
  if (got >= 2 && head[0] == 0x1f && head[1] == 0x8b) return SceneFormat::spz;
  if (got >= 4 && load_u32(head) == spz_magic) return SceneFormat::spz;
  if (lower_extension(name) == ".splat") return SceneFormat::splat;
  throw Error("unrecognised scene file: not a PLY (first line 'ply'), not SPZ (gzip or NGSP magic); antimatter15 "
              "files have no signature and must be named *.splat", where);
}
}  // namespace detail

// The format of a scene file, from its first bytes (and the .splat extension when they match no
// signature). Throws vcar::Error naming the file when it is none of the four.
inline SceneFormat detect_scene_format(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  if (!in || !std::filesystem::is_regular_file(path, ec)) throw Error("cannot open scene file", where);
  unsigned char head[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(head), 4);
  return detail::scene_format_of(head, static_cast<std::size_t>(in.gcount()), in, path, where);
}

// The same for a file's bytes in memory; `name` is the file's name (its extension decides for
// .splat) and stands for it in errors.
inline SceneFormat detect_scene_format(std::span<const std::uint8_t> bytes, const std::string& name) {
  detail::ByteStream in(bytes);
  return detail::scene_format_of(bytes.data(), std::min<std::size_t>(bytes.size(), 4), in, name, name);
}

// Reads any of the four formats (docs/formats.md); `format`, when given, receives what was read,
// and `infinite` how many opacity logits were +-inf and read as opacity 1 / 0 (only float
// formats can hold them: Inria PLY; the 8-bit formats never do, and report zero).
inline GaussianScene read_scene(const std::filesystem::path& path, SceneFormat* format = nullptr,
                                InfiniteOpacities* infinite = nullptr) {
  const SceneFormat f = detect_scene_format(path);
  if (format) *format = f;
  if (infinite) *infinite = {};
  switch (f) {
    case SceneFormat::ply: return read_ply(path, infinite);
    case SceneFormat::compressed_ply: return read_compressed_ply(path);
    case SceneFormat::spz: return read_spz(path);
    case SceneFormat::splat: return read_splat(path);
  }
  throw Error("unknown scene format", path.string());
}

// The same from a file's bytes in memory (a browser's upload, a network buffer); `name` is the
// file's name (its extension decides for .splat) and stands for it in errors. SPZ v2/v3 may
// also come already inflated (the header and arrays without their gzip stream).
inline GaussianScene read_scene(std::span<const std::uint8_t> bytes, const std::string& name,
                                SceneFormat* format = nullptr, InfiniteOpacities* infinite = nullptr) {
  const SceneFormat f = detect_scene_format(bytes, name);
  if (format) *format = f;
  if (infinite) *infinite = {};
  switch (f) {
    case SceneFormat::ply: return read_ply(bytes, name, infinite);
    case SceneFormat::compressed_ply: return read_compressed_ply(bytes, name);
    case SceneFormat::spz: return read_spz(bytes, name);
    case SceneFormat::splat: return read_splat(bytes, name);
  }
  throw Error("unknown scene format", name);
}

// Writes by extension: .splat, .spz, otherwise Inria PLY (binary). Compressed PLY is not written.
inline void write_scene(const std::filesystem::path& path, const GaussianScene& scene) {
  const std::string e = detail::lower_extension(path);
  if (e == ".splat") write_splat(path, scene);
  else if (e == ".spz") write_spz(path, scene);
  else write_ply(path, scene);
}

}  // namespace vcar::io
