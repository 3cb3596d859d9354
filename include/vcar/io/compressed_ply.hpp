#pragma once
// PlayCanvas compressed PLY (SuperSplat / splat-transform `.compressed.ply`): a binary PLY with
//   element chunk  ceil(n / 256)  float min_x min_y min_z max_x max_y max_z
//                                 min_scale_x .. max_scale_z  [min_r min_g min_b max_r max_g max_b]
//   element vertex n              uint packed_position packed_rotation packed_scale packed_color
//   [element sh n                 uchar f_rest_0 .. f_rest_{9|24|45 - 1}]
// Gaussian i belongs to chunk i / 256. Decoding (docs/formats.md):
//   position, log-scale: 11-10-11 bit unorms (x bits 21-31, y 11-20, z 0-10) lerped between the
//     chunk's min and max (scales are LOG scales);
//   colour: 8-8-8-8 unorms r g b a (bits 24.. / 16.. / 8.. / 0..); r g b lerped between the chunk's
//     min_r .. max_r when the chunk has them (else used as they are) give 0.5 + C0 f_dc; a is the
//     opacity AFTER the sigmoid;
//   rotation: 2-10-10-10, "smallest three": bits 30-31 say which of (rot_0 .. rot_3) = (w x y z)
//     is the largest (stored positive, sqrt(1 - the others^2)); the other three, in order, are
//     (unorm10 - 0.5) * sqrt(2);
//   SH: byte v -> ((v + 0.5) / 256 - 0.5) * 8 (v = 0 -> -4, v = 255 -> 4), channel-major f_rest
//     like the Inria PLY.
// Same axes as the Inria PLY. Writers sort Gaussians (Morton order), so index i of a compressed
// file is not index i of the PLY it came from. Bad input throws vcar::Error naming the file.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <span>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/byte_stream.hpp"
#include "vcar/io/compact_values.hpp"
#include "vcar/io/ply.hpp"

namespace vcar::io {

inline constexpr std::size_t compressed_ply_chunk = 256;  // Gaussians per chunk

namespace detail {

inline const char* const compressed_chunk_names[18] = {
    "min_x", "min_y", "min_z", "max_x", "max_y", "max_z",
    "min_scale_x", "min_scale_y", "min_scale_z", "max_scale_x", "max_scale_y", "max_scale_z",
    "min_r", "min_g", "min_b", "max_r", "max_g", "max_b"};
inline const char* const compressed_vertex_names[4] = {"packed_position", "packed_rotation", "packed_scale", "packed_color"};

// True when a parsed PLY header has the compressed layout (an element `chunk` and a `vertex`
// element with packed_position): how read_scene tells it from an Inria PLY.
inline bool is_compressed_ply_header(const PlyHeader& h) {
  bool chunk = false, packed = false;
  for (const auto& e : h.elements) {
    if (e.name == "chunk") chunk = true;
    if (e.name == "vertex")
      for (const auto& p : e.props) packed = packed || p.name == "packed_position";
  }
  return chunk && packed;
}

inline float unorm(std::uint32_t v, int bits) {
  const std::uint32_t m = (1u << bits) - 1u;
  return static_cast<float>(v & m) / static_cast<float>(m);
}
inline float lerp(float a, float b, float t) { return a * (1.f - t) + b * t; }

// The raw content of a compressed PLY: chunk table (18 floats per chunk, colour bounds 0..1 when
// absent), packed words (4 per Gaussian) and SH bytes. Exposed for tests (quantisation bounds).
struct CompressedPly {
  std::size_t n = 0;
  bool chunk_colours = false;
  std::vector<float> chunks;             // 18 per chunk, in compressed_chunk_names order
  std::vector<std::uint32_t> packed;     // 4 per Gaussian, in compressed_vertex_names order
  int sh_rest = 0;                       // f_rest values per Gaussian (0, 9, 24, 45)
  std::vector<std::uint8_t> sh;          // sh_rest per Gaussian, f_rest order
};

// The packed columns of a compressed PLY on a stream of `file_size` bytes; `where` names it.
inline CompressedPly read_compressed_ply_raw(std::istream& in, std::uint64_t file_size, const std::string& where) {
  const PlyHeader h = parse_ply_header(in, where);
  if (!h.binary) throw Error("compressed PLY must be binary_little_endian", where);

  const PlyElement *chunk = nullptr, *vertex = nullptr, *sh = nullptr;
  std::uint64_t offset = h.data_offset, chunk_at = 0, vertex_at = 0, sh_at = 0;
  for (const auto& e : h.elements) {
    if (e.has_list) throw Error("element '" + e.name + "' has list properties (not a compressed PLY)", where);
    if (e.stride && e.count > (file_size - std::min(file_size, offset)) / e.stride)
      throw Error("element '" + e.name + "' declares " + std::to_string(e.count) + " rows (" + std::to_string(e.stride) +
                  " bytes each) but only " + std::to_string(file_size - std::min(file_size, offset)) +
                  " bytes follow at byte " + std::to_string(offset) + " (truncated?)", where);
    if (e.name == "chunk") { chunk = &e; chunk_at = offset; }
    else if (e.name == "vertex") { vertex = &e; vertex_at = offset; }
    else if (e.name == "sh") { sh = &e; sh_at = offset; }
    else throw Error("unexpected element '" + e.name + "' in a compressed PLY", where);
    offset += e.count * e.stride;
  }
  if (!chunk || !vertex) throw Error("compressed PLY needs elements 'chunk' and 'vertex'", where);

  auto find = [&](const PlyElement& e, const std::string& name, PlyType type, const char* type_name) -> const PlyProperty* {
    for (const auto& p : e.props)
      if (p.name == name) {
        if (p.type != type) throw Error("property '" + name + "' of element '" + e.name + "' must be " + type_name, where);
        return &p;
      }
    return nullptr;
  };
  CompressedPly c;
  c.n = static_cast<std::size_t>(vertex->count);
  const std::uint64_t chunks_needed = (vertex->count + compressed_ply_chunk - 1) / compressed_ply_chunk;
  if (chunk->count != chunks_needed)
    throw Error("element chunk has " + std::to_string(chunk->count) + " rows, " + std::to_string(vertex->count) +
                " vertices need " + std::to_string(chunks_needed) + " (one per 256)", where);
  const PlyProperty* cp[18] = {};
  std::string missing;
  for (int k = 0; k < 18; ++k) {
    cp[k] = find(*chunk, compressed_chunk_names[k], PlyType::f32, "float");
    if (!cp[k] && k < 12) missing += std::string(missing.empty() ? "" : ", ") + compressed_chunk_names[k];
  }
  int colour_props = 0;
  for (int k = 12; k < 18; ++k) colour_props += cp[k] != nullptr;
  if (colour_props != 0 && colour_props != 6) missing += std::string(missing.empty() ? "" : ", ") + "min_r .. max_b (all six or none)";
  const PlyProperty* vp[4] = {};
  for (int k = 0; k < 4; ++k) {
    vp[k] = find(*vertex, compressed_vertex_names[k], PlyType::u32, "uint");
    if (!vp[k]) missing += std::string(missing.empty() ? "" : ", ") + compressed_vertex_names[k];
  }
  if (!missing.empty()) throw Error("compressed PLY is missing properties: " + missing, where);
  c.chunk_colours = colour_props == 6;

  std::vector<const PlyProperty*> shp;
  if (sh) {
    if (sh->count != vertex->count)
      throw Error("element sh has " + std::to_string(sh->count) + " rows, element vertex " + std::to_string(vertex->count), where);
    c.sh_rest = static_cast<int>(sh->props.size());
    if (c.sh_rest != 9 && c.sh_rest != 24 && c.sh_rest != 45)
      throw Error("element sh has " + std::to_string(c.sh_rest) + " properties: expected 9, 24 or 45 (SH degree 1-3)", where);
    for (int j = 0; j < c.sh_rest; ++j) {
      const PlyProperty* p = find(*sh, "f_rest_" + std::to_string(j), PlyType::u8, "uchar");
      if (!p) throw Error("element sh has no property f_rest_" + std::to_string(j), where);
      shp.push_back(p);
    }
  }

  std::vector<std::uint8_t> buf;
  auto load = [&](std::uint64_t at, const PlyElement& e) {
    buf.resize(static_cast<std::size_t>(e.count * e.stride));
    in.clear();
    in.seekg(static_cast<std::streamoff>(at));
    in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
    if (static_cast<std::size_t>(in.gcount()) != buf.size())
      throw Error("truncated data in element '" + e.name + "' (at byte " + std::to_string(at) + ")", where);
  };
  load(chunk_at, *chunk);
  c.chunks.assign(static_cast<std::size_t>(chunk->count) * 18, 0.f);
  for (std::size_t r = 0; r < chunk->count; ++r)
    for (int k = 0; k < 18; ++k)
      c.chunks[r * 18 + static_cast<std::size_t>(k)] =
          cp[k] ? load_f32(buf.data() + r * chunk->stride + cp[k]->offset) : (k < 15 ? 0.f : 1.f);
  load(vertex_at, *vertex);
  c.packed.assign(c.n * 4, 0u);
  for (std::size_t i = 0; i < c.n; ++i)
    for (int k = 0; k < 4; ++k) c.packed[i * 4 + static_cast<std::size_t>(k)] = load_u32(buf.data() + i * vertex->stride + vp[k]->offset);
  if (sh) {
    load(sh_at, *sh);
    c.sh.assign(c.n * static_cast<std::size_t>(c.sh_rest), 0);
    for (std::size_t i = 0; i < c.n; ++i)
      for (int j = 0; j < c.sh_rest; ++j) c.sh[i * static_cast<std::size_t>(c.sh_rest) + static_cast<std::size_t>(j)] = buf[i * sh->stride + shp[static_cast<std::size_t>(j)]->offset];
  }
  for (std::size_t k = 0; k < c.chunks.size(); ++k)
    if (!std::isfinite(c.chunks[k]))
      throw Error("chunk " + std::to_string(k / 18) + ", property '" + compressed_chunk_names[k % 18] + "' is not finite", where);
  return c;
}

inline CompressedPly read_compressed_ply_raw(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) throw Error("cannot open compressed PLY file: " + ec.message(), where);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open compressed PLY file", where);
  return read_compressed_ply_raw(in, file_size, where);
}

// The scene of unpacked columns `c` (see the top of this file); `where` names the file.
inline GaussianScene unpack_compressed_ply(const CompressedPly& c, const std::string& where) {
  const int degree = c.sh_rest == 45 ? 3 : c.sh_rest == 24 ? 2 : c.sh_rest == 9 ? 1 : 0;
  GaussianScene s;
  s.resize(c.n, degree);
  const std::size_t B = static_cast<std::size_t>(s.sh_coeffs());
  const float rot_range = std::sqrt(2.f);  // (unorm - 0.5) * sqrt(2) in [-1/sqrt(2), 1/sqrt(2)]
  for (std::size_t i = 0; i < c.n; ++i) {
    const float* ch = c.chunks.data() + (i / compressed_ply_chunk) * 18;
    const std::uint32_t* p = c.packed.data() + i * 4;
    const float t[3] = {detail::unorm(p[0] >> 21, 11), detail::unorm(p[0] >> 11, 10), detail::unorm(p[0], 11)};
    const float u[3] = {detail::unorm(p[2] >> 21, 11), detail::unorm(p[2] >> 11, 10), detail::unorm(p[2], 11)};
    for (int d = 0; d < 3; ++d) {
      s.mean[d][i] = detail::lerp(ch[d], ch[3 + d], t[d]);
      s.log_scale[d][i] = detail::lerp(ch[6 + d], ch[9 + d], u[d]);
    }
    const float rgba[4] = {detail::unorm(p[3] >> 24, 8), detail::unorm(p[3] >> 16, 8), detail::unorm(p[3] >> 8, 8), detail::unorm(p[3], 8)};
    for (std::size_t k = 0; k < 3; ++k) {
      const float colour = c.chunk_colours ? detail::lerp(ch[12 + k], ch[15 + k], rgba[k]) : rgba[k];
      s.sh[i * B * 3 + k] = dc_from_colour(colour);
    }
    s.opacity_logit[i] = opacity_logit_from_alpha(rgba[3]);
    const std::uint32_t largest = p[1] >> 30;
    float q[4], sum = 0.f;
    for (int k = 0, shift = 20; k < 4; ++k) {
      if (static_cast<std::uint32_t>(k) == largest) continue;
      q[k] = (detail::unorm(p[1] >> shift, 10) - 0.5f) * rot_range;
      sum += q[k] * q[k];
      shift -= 10;
    }
    q[largest] = std::sqrt(std::max(0.f, 1.f - sum));
    for (int k = 0; k < 4; ++k) s.rotation[k][i] = q[k];
    for (int j = 0; j < c.sh_rest; ++j) {  // f_rest_j: coefficient j % (B-1) + 1 of channel j / (B-1)
      const std::uint8_t v = c.sh[i * static_cast<std::size_t>(c.sh_rest) + static_cast<std::size_t>(j)];
      const float n = v == 0 ? 0.f : v == 255 ? 1.f : (static_cast<float>(v) + 0.5f) / 256.f;
      const std::size_t ch_ = static_cast<std::size_t>(j) / (B - 1), kk = static_cast<std::size_t>(j) % (B - 1) + 1;
      s.sh[(i * B + kk) * 3 + ch_] = (n - 0.5f) * 8.f;
    }
  }
  s.validate(where);
  return s;
}

}  // namespace detail

// Reads a PlayCanvas compressed PLY (see the top of this file).
inline GaussianScene read_compressed_ply(const std::filesystem::path& path) {
  return detail::unpack_compressed_ply(detail::read_compressed_ply_raw(path), path.string());
}

// The same from the file's bytes in memory; `name` stands for the file in errors.
inline GaussianScene read_compressed_ply(std::span<const std::uint8_t> bytes, const std::string& name) {
  detail::ByteStream in(bytes);
  return detail::unpack_compressed_ply(detail::read_compressed_ply_raw(in, bytes.size(), name), name);
}

}  // namespace vcar::io
