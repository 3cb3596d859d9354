#pragma once
// Inria 3DGS PLY files (conventions §1): binary little-endian or ASCII, SH degree 0-3.
//
// Reading matches properties by NAME, in any order, of any numeric type (char .. double; values
// are converted to float). Required: x y z, f_dc_0..2, opacity, scale_0..2, rot_0..3; the SH
// degree follows from the number of f_rest_* properties (0, 9, 24 or 45; they are channel-major
// in the file, f_rest_{c (B-1) + k-1} = coefficient k of channel c, and go to the [i][k][c]
// layout of GaussianScene::sh). Every other vertex property (normals nx ny nz, custom fields) is
// kept, as float, in GaussianScene::extra_names / extra and written back: a read -> write round
// trip loses nothing but the precision of non-float extras. Elements other than `vertex` are
// skipped (fixed-size ones only, when they come before it). Opacity logits of +inf / -inf
// (opacity 1 / 0, as some converters write them) are read as fully opaque / transparent
// (GaussianScene::settle_infinite_opacities) and counted in `*infinite` when given. The whole
// scene is checked (GaussianScene::validate: NaN anywhere, infinite positions, scales,
// rotations or colours are refused) and sizes are checked against the file size before anything is
// allocated; bad input throws vcar::Error naming the file (and the byte offset or vertex).
//
// Writing follows the Inria writer: `format binary_little_endian 1.0` (or ascii), one `vertex`
// element, float properties in the order x y z [nx ny nz] f_dc_* f_rest_* opacity scale_* rot_*,
// then the remaining extras in their order. Files are written atomically (temp + rename).
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/byte_stream.hpp"

namespace vcar::io {

namespace detail {

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

// PLY type names, both spellings of the standard (char / int8 ...); size 0 = unknown.
inline int ply_type(std::string_view s, PlyType& t) {
  if (s == "char" || s == "int8") { t = PlyType::i8; return 1; }
  if (s == "uchar" || s == "uint8") { t = PlyType::u8; return 1; }
  if (s == "short" || s == "int16") { t = PlyType::i16; return 2; }
  if (s == "ushort" || s == "uint16") { t = PlyType::u16; return 2; }
  if (s == "int" || s == "int32") { t = PlyType::i32; return 4; }
  if (s == "uint" || s == "uint32") { t = PlyType::u32; return 4; }
  if (s == "float" || s == "float32") { t = PlyType::f32; return 4; }
  if (s == "double" || s == "float64") { t = PlyType::f64; return 8; }
  return 0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;
  int size = 4;
  std::size_t offset = 0;  // byte offset inside a binary row
  bool is_list = false;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
  std::size_t stride = 0;  // bytes per binary row (meaningless with lists)
  bool has_list = false;
};

struct PlyHeader {
  bool binary = true;
  std::vector<PlyElement> elements;
  std::uint64_t data_offset = 0;  // first byte after end_header
};

inline std::vector<std::string_view> split_ws(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

inline PlyHeader parse_ply_header(std::istream& in, const std::string& where) {
  PlyHeader h;
  std::string line;
  constexpr std::size_t max_lines = 100000;  // a header longer than this is not a header
  bool format_seen = false;
  for (std::size_t n = 0;; ++n) {
    if (n >= max_lines || !std::getline(in, line))
      throw Error("no 'end_header' line: not a PLY file or truncated header", where);
    const std::string at = " (header line " + std::to_string(n + 1) + ")";
    const auto tok = split_ws(line);
    if (n == 0) {
      if (tok.size() != 1 || tok[0] != "ply") throw Error("not a PLY file (first line is not 'ply')", where);
      continue;
    }
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "end_header") break;
    if (tok[0] == "format") {
      if (tok.size() < 2) throw Error("malformed format line" + at, where);
      if (tok[1] == "binary_little_endian") h.binary = true;
      else if (tok[1] == "ascii") h.binary = false;
      else if (tok[1] == "binary_big_endian")
        throw Error("big-endian PLY is not supported (convert to binary_little_endian)", where);
      else throw Error("unknown PLY format '" + std::string(tok[1]) + "'" + at, where);
      format_seen = true;
    } else if (tok[0] == "element") {
      if (tok.size() != 3) throw Error("malformed element line" + at, where);
      PlyElement e;
      e.name = std::string(tok[1]);
      const auto r = std::from_chars(tok[2].data(), tok[2].data() + tok[2].size(), e.count);
      if (r.ec != std::errc() || r.ptr != tok[2].data() + tok[2].size())
        throw Error("bad element count '" + std::string(tok[2]) + "'" + at, where);
      h.elements.push_back(std::move(e));
    } else if (tok[0] == "property") {
      if (h.elements.empty()) throw Error("property before any element" + at, where);
      PlyElement& e = h.elements.back();
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        PlyType t;
        if (!ply_type(tok[2], t) || !ply_type(tok[3], t))
          throw Error("unknown list type in '" + line + "'" + at, where);
        p.name = std::string(tok[4]);
        p.is_list = true;
        e.has_list = true;
      } else {
        if (tok.size() != 3) throw Error("malformed property line" + at, where);
        p.size = ply_type(tok[1], p.type);
        if (p.size == 0) throw Error("unknown property type '" + std::string(tok[1]) + "'" + at, where);
        p.name = std::string(tok[2]);
        p.offset = e.stride;
        e.stride += static_cast<std::size_t>(p.size);
      }
      for (const auto& q : e.props)
        if (q.name == p.name) throw Error("duplicate property '" + p.name + "'" + at, where);
      e.props.push_back(std::move(p));
    } else {
      throw Error("unexpected header keyword '" + std::string(tok[0]) + "'" + at, where);
    }
  }
  if (!format_seen) throw Error("no format line in the header", where);
  if (!in.good()) { in.clear(); in.seekg(0, std::ios::end); }  // end_header was the last byte
  h.data_offset = static_cast<std::uint64_t>(in.tellg());
  return h;
}

inline float decode_ply_value(const unsigned char* p, PlyType t) {
  unsigned char b[8];
  const int n = t == PlyType::f64 ? 8 : (t == PlyType::i8 || t == PlyType::u8) ? 1
                : (t == PlyType::i16 || t == PlyType::u16) ? 2 : 4;
  std::memcpy(b, p, static_cast<std::size_t>(n));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + n);  // file is LE
  switch (t) {
    case PlyType::i8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
    case PlyType::u8: return b[0];
    case PlyType::i16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case PlyType::u16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case PlyType::i32: { std::int32_t v; std::memcpy(&v, b, 4); return static_cast<float>(v); }
    case PlyType::u32: { std::uint32_t v; std::memcpy(&v, b, 4); return static_cast<float>(v); }
    case PlyType::f32: { float v; std::memcpy(&v, b, 4); return v; }
    case PlyType::f64: { double v; std::memcpy(&v, b, 8); return static_cast<float>(v); }
  }
  return 0.f;
}

// Where a vertex property lands: value of Gaussian i at base[offset + i * stride] (the offset
// is kept apart: with 0 vertices base is null, and null + offset is undefined behaviour).
struct PlyTarget { float* base = nullptr; std::size_t offset = 0, stride = 1; };

inline bool parse_index_suffix(std::string_view name, std::string_view prefix, int& k) {
  if (name.size() <= prefix.size() || name.substr(0, prefix.size()) != prefix) return false;
  const auto s = name.substr(prefix.size());
  const auto r = std::from_chars(s.data(), s.data() + s.size(), k);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && k >= 0 &&
         std::to_string(k) == s;  // "f_rest_01" is not f_rest_1
}

inline const char* ply_skip_ws(const char* p, const char* end) {
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')) ++p;
  return p;
}

// The names in the order the Inria writer uses; normals (extras) follow x y z when present.
inline std::vector<std::string> ply_standard_names(int sh_degree) {
  std::vector<std::string> n = {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2"};
  const int rest = 3 * ((sh_degree + 1) * (sh_degree + 1) - 1);
  for (int j = 0; j < rest; ++j) n.push_back("f_rest_" + std::to_string(j));
  n.push_back("opacity");
  for (int d = 0; d < 3; ++d) n.push_back("scale_" + std::to_string(d));
  for (int k = 0; k < 4; ++k) n.push_back("rot_" + std::to_string(k));
  return n;
}

inline bool ply_is_standard_name(std::string_view s) {
  int k = 0;
  return s == "x" || s == "y" || s == "z" || s == "opacity" || parse_index_suffix(s, "f_dc_", k) ||
         parse_index_suffix(s, "f_rest_", k) || parse_index_suffix(s, "scale_", k) ||
         parse_index_suffix(s, "rot_", k);
}

// Writes the Gaussians `indices` (all when null) with optional replacement log-scales and an
// optional last `uchar state` property (SuperSplat's flags, io/state_ply.hpp; it replaces an
// extra named "state").
// With `label`, a last `int label` property (io/label_ply.hpp) follows.
inline void write_ply_stream(std::ostream& out, const GaussianScene& scene,
                             const std::vector<Index>* indices, const LogScales* log_scale,
                             bool binary, const std::vector<std::uint8_t>* state = nullptr,
                             const std::vector<std::int32_t>* label = nullptr) {
  const std::size_t n = indices ? indices->size() : scene.size();
  const std::size_t B = static_cast<std::size_t>(scene.sh_coeffs()), E = scene.extra_names.size();
  // Column order: x y z, normals, f_dc, f_rest, opacity, scale, rot, other extras.
  std::vector<std::size_t> normals, others;
  for (const char* nn : {"nx", "ny", "nz"})
    for (std::size_t e = 0; e < E; ++e)
      if (scene.extra_names[e] == nn) normals.push_back(e);
  if (normals.size() != 3) normals.clear();
  for (std::size_t e = 0; e < E; ++e)
    if (std::find(normals.begin(), normals.end(), e) == normals.end() && !(state && scene.extra_names[e] == "state") &&
        !(label && scene.extra_names[e] == "label"))
      others.push_back(e);

  std::vector<std::string> names = {"x", "y", "z"};
  for (std::size_t e : normals) names.push_back(scene.extra_names[e]);
  const auto standard = ply_standard_names(scene.sh_degree);
  names.insert(names.end(), standard.begin() + 3, standard.end());
  for (std::size_t e : others) names.push_back(scene.extra_names[e]);

  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
      << "element vertex " << n << "\n";
  for (const auto& nm : names) out << "property float " << nm << "\n";
  if (state) out << "property uchar state\n";
  if (label) out << "property int label\n";
  out << "end_header\n";

  const std::size_t P = names.size();
  constexpr std::size_t rows_per_chunk = 4096;
  std::vector<float> row(P);
  std::vector<char> buf;
  buf.reserve(rows_per_chunk * P * (binary ? 4 : 16));
  for (std::size_t r = 0; r < n; ++r) {
    const std::size_t i = indices ? (*indices)[r] : r;
    std::size_t p = 0;
    for (int d = 0; d < 3; ++d) row[p++] = scene.mean[d][i];
    for (std::size_t e : normals) row[p++] = scene.extra[i * E + e];
    for (int c = 0; c < 3; ++c) row[p++] = scene.sh[(i * B) * 3 + c];
    for (int c = 0; c < 3; ++c)  // channel-major f_rest (conventions §1)
      for (std::size_t k = 1; k < B; ++k) row[p++] = scene.sh[(i * B + k) * 3 + c];
    row[p++] = scene.opacity_logit[i];
    for (int d = 0; d < 3; ++d) row[p++] = log_scale ? (*log_scale)[d][r] : scene.log_scale[d][i];
    for (int k = 0; k < 4; ++k) row[p++] = scene.rotation[k][i];
    for (std::size_t e : others) row[p++] = scene.extra[i * E + e];
    if (binary) {
      const std::size_t at = buf.size();
      buf.resize(at + P * 4);
      std::memcpy(buf.data() + at, row.data(), P * 4);
      if constexpr (std::endian::native == std::endian::big)
        for (std::size_t q = 0; q < P; ++q) std::reverse(buf.data() + at + 4 * q, buf.data() + at + 4 * q + 4);
      if (state) buf.push_back(static_cast<char>((*state)[i]));
      if (label) {
        std::uint32_t u;
        const std::int32_t v = (*label)[i];
        std::memcpy(&u, &v, 4);
        for (int b = 0; b < 4; ++b) buf.push_back(static_cast<char>((u >> (8 * b)) & 0xffu));  // little endian
      }
    } else {
      char tmp[32];
      for (std::size_t q = 0; q < P; ++q) {
        // Shortest representation that reads back to the same float.
        const auto res = std::to_chars(tmp, tmp + sizeof tmp, row[q]);
        buf.insert(buf.end(), tmp, res.ptr);
        buf.push_back(q + 1 < P || state || label ? ' ' : '\n');
      }
      if (state) {
        const std::string v = std::to_string(static_cast<int>((*state)[i]));
        buf.insert(buf.end(), v.begin(), v.end());
        buf.push_back(label ? ' ' : '\n');
      }
      if (label) {
        const std::string v = std::to_string((*label)[i]);
        buf.insert(buf.end(), v.begin(), v.end());
        buf.push_back('\n');
      }
    }
    if ((r + 1) % rows_per_chunk == 0 || r + 1 == n) {
      out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
      buf.clear();
    }
  }
}

inline void check_writable(const std::filesystem::path& path, const GaussianScene& scene,
                           const std::vector<Index>* indices, const LogScales* log_scale) {
  const std::string where = path.string();
  scene.validate(where);
  for (const auto& nm : scene.extra_names) {
    if (nm.empty() || nm.find_first_of(" \t\r\n") != std::string::npos)
      throw Error("extra property name '" + nm + "' is not a valid PLY name", where);
    if (ply_is_standard_name(nm))
      throw Error("extra property '" + nm + "' clashes with a Gaussian property", where);
  }
  if (indices)
    for (std::size_t r = 0; r < indices->size(); ++r)
      if ((*indices)[r] >= scene.size())
        throw Error("index " + std::to_string((*indices)[r]) + " (entry " + std::to_string(r) +
                    ") is out of range for a scene of " + std::to_string(scene.size()), where);
  if (log_scale) {
    const std::size_t n = indices ? indices->size() : scene.size();
    for (int d = 0; d < 3; ++d) {
      if ((*log_scale)[d].size() != n)
        throw Error("log_scale column " + std::to_string(d) + " has " +
                    std::to_string((*log_scale)[d].size()) + " values, expected " + std::to_string(n), where);
      for (std::size_t r = 0; r < n; ++r)
        if (!std::isfinite((*log_scale)[d][r]))
          throw Error("log_scale entry " + std::to_string(r) + " is not finite", where);
    }
  }
}

}  // namespace detail

namespace detail {
// read_ply on a stream of `file_size` bytes (a file or bytes in memory); `where` names it.
inline GaussianScene read_ply_stream(std::istream& in, std::uint64_t file_size, const std::string& where,
                                     InfiniteOpacities* infinite) {
  const detail::PlyHeader h = detail::parse_ply_header(in, where);

  // Skip the elements before `vertex` (fixed-size rows only).
  std::uint64_t skip = 0;
  const detail::PlyElement* v = nullptr;
  std::uint64_t ascii_skip_lines = 0;
  for (const auto& e : h.elements) {
    if (e.name == "vertex") { v = &e; break; }
    if (h.binary) {
      if (e.has_list) throw Error("cannot skip element '" + e.name + "' with list properties before 'vertex'", where);
      if (e.stride && e.count > (file_size - h.data_offset - skip) / e.stride)
        throw Error("element '" + e.name + "' is larger than the file (truncated?)", where);
      skip += e.count * e.stride;
    } else {
      ascii_skip_lines += e.count;
    }
  }
  if (!v) throw Error("no 'vertex' element", where);
  for (const auto& p : v->props)
    if (p.is_list) throw Error("list property '" + p.name + "' in 'vertex' is not supported", where);

  // Map properties by name; collect every missing required one.
  int rest_count = 0, rest_max = -1;
  for (const auto& p : v->props) {
    int k;
    if (detail::parse_index_suffix(p.name, "f_rest_", k)) { ++rest_count; rest_max = std::max(rest_max, k); }
  }
  int degree = -1;
  for (int d = 0; d <= 3; ++d)
    if (rest_count == 3 * ((d + 1) * (d + 1) - 1)) degree = d;
  if (degree < 0 || rest_max + 1 != rest_count)
    throw Error(std::to_string(rest_count) + " f_rest_* properties (highest f_rest_" +
                std::to_string(rest_max) + "): expected f_rest_0 .. f_rest_{8, 23 or 44} for SH degree 1-3, or none", where);
  std::vector<std::string> missing;
  for (const auto& nm : detail::ply_standard_names(degree)) {
    bool found = false;
    for (const auto& p : v->props) found = found || p.name == nm;
    if (!found) missing.push_back(nm);
  }
  if (!missing.empty()) {
    std::string list;
    for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
    throw Error("missing required vertex properties: " + list, where);
  }

  // Sizes against the file before allocating (a huge count in a tiny file fails here).
  const std::uint64_t n = v->count;
  const std::uint64_t P = v->props.size();
  const std::uint64_t avail = file_size - std::min<std::uint64_t>(file_size, h.data_offset + skip);
  if (h.binary) {
    if (v->stride == 0 || n > avail / v->stride)
      throw Error("element vertex declares " + std::to_string(n) + " vertices (" +
                  std::to_string(v->stride) + " bytes each) but only " + std::to_string(avail) +
                  " bytes follow the header at byte " + std::to_string(h.data_offset + skip) + " (truncated?)", where);
  } else if (n > 0 && (P == 0 || n > (avail + 1) / (2 * P))) {  // each ASCII value takes >= 2 bytes
    throw Error("element vertex declares " + std::to_string(n) + " vertices but the file has only " +
                std::to_string(avail) + " bytes of data (truncated?)", where);
  }

  GaussianScene scene;
  for (const auto& p : v->props)
    if (!detail::ply_is_standard_name(p.name)) scene.extra_names.push_back(p.name);
  scene.resize(static_cast<std::size_t>(n), degree);
  const std::size_t B = static_cast<std::size_t>(scene.sh_coeffs()), E = scene.extra_names.size();
  std::vector<detail::PlyTarget> target(v->props.size());
  for (std::size_t q = 0, e = 0; q < v->props.size(); ++q) {
    const std::string& nm = v->props[q].name;
    int k = 0;
    auto& t = target[q];
    if (nm == "x" || nm == "y" || nm == "z") t = {scene.mean[static_cast<std::size_t>(nm[0] - 'x')].data(), 0, 1};
    else if (nm == "opacity") t = {scene.opacity_logit.data(), 0, 1};
    else if (detail::parse_index_suffix(nm, "scale_", k) && k < 3) t = {scene.log_scale[static_cast<std::size_t>(k)].data(), 0, 1};
    else if (detail::parse_index_suffix(nm, "rot_", k) && k < 4) t = {scene.rotation[static_cast<std::size_t>(k)].data(), 0, 1};
    else if (detail::parse_index_suffix(nm, "f_dc_", k) && k < 3) t = {scene.sh.data(), static_cast<std::size_t>(k), B * 3};
    else if (detail::parse_index_suffix(nm, "f_rest_", k)) {
      const std::size_t c = static_cast<std::size_t>(k) / (B - 1), kk = static_cast<std::size_t>(k) % (B - 1) + 1;
      t = {scene.sh.data(), kk * 3 + c, B * 3};  // channel-major file -> [i][k][c]
    } else if (detail::ply_is_standard_name(nm)) {
      throw Error("unexpected property '" + nm + "' (index out of range)", where);
    } else {
      t = {scene.extra.data(), e, E};
      ++e;
    }
  }

  if (h.binary) {
    in.seekg(static_cast<std::streamoff>(h.data_offset + skip));
    const std::size_t stride = v->stride;
    const std::size_t chunk = std::max<std::size_t>(1, (std::size_t{1} << 20) / stride);
    std::vector<unsigned char> buf(std::min<std::size_t>(chunk, static_cast<std::size_t>(n)) * stride);
    for (std::size_t r0 = 0; r0 < n; r0 += chunk) {
      const std::size_t rows = std::min<std::size_t>(chunk, static_cast<std::size_t>(n) - r0);
      in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(rows * stride));
      if (!in) throw Error("truncated vertex data at vertex " + std::to_string(r0), where);
      for (std::size_t r = 0; r < rows; ++r) {
        const unsigned char* row = buf.data() + r * stride;
        for (std::size_t q = 0; q < target.size(); ++q)
          target[q].base[target[q].offset + (r0 + r) * target[q].stride] = detail::decode_ply_value(row + v->props[q].offset, v->props[q].type);
      }
    }
  } else {
    std::string text(static_cast<std::size_t>(file_size - h.data_offset), '\0');
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<std::size_t>(in.gcount()));
    const char* p = text.data();
    const char* end = p + text.size();
    for (std::uint64_t l = 0; l < ascii_skip_lines; ++l) {  // rows of earlier elements
      const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
      if (!nl) throw Error("truncated data before the vertex element", where);
      p = nl + 1;
    }
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t q = 0; q < target.size(); ++q) {
        p = detail::ply_skip_ws(p, end);
        const char* tok_end = p;
        while (tok_end < end && *tok_end != ' ' && *tok_end != '\t' && *tok_end != '\r' && *tok_end != '\n') ++tok_end;
        if (tok_end == p)
          throw Error("truncated: vertex " + std::to_string(i) + " has no value for '" + v->props[q].name + "'", where);
        float value = 0.f;
        std::from_chars_result res;
        if (v->props[q].type == detail::PlyType::f32) {
          res = std::from_chars(p, tok_end, value);
        } else {
          double dv = 0.0;
          res = std::from_chars(p, tok_end, dv);
          value = static_cast<float>(dv);
        }
        if (res.ec != std::errc() || res.ptr != tok_end)
          throw Error("vertex " + std::to_string(i) + ", property '" + v->props[q].name + "': '" +
                      std::string(p, tok_end) + "' is not a number", where);
        target[q].base[target[q].offset + i * target[q].stride] = value;
        p = tok_end;
      }
  }
  const InfiniteOpacities settled = scene.settle_infinite_opacities();
  if (infinite) *infinite = settled;
  scene.validate(where);
  return scene;
}
}  // namespace detail

// Reads an Inria 3DGS PLY (see the top of this file for what is accepted and kept).
inline GaussianScene read_ply(const std::filesystem::path& path, InfiniteOpacities* infinite = nullptr) {
  const std::string where = path.string();
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) throw Error("cannot open PLY file: " + ec.message(), where);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open PLY file", where);
  return detail::read_ply_stream(in, file_size, where, infinite);
}

// The same from the file's bytes in memory; `name` stands for the file in errors.
inline GaussianScene read_ply(std::span<const std::uint8_t> bytes, const std::string& name,
                              InfiniteOpacities* infinite = nullptr) {
  detail::ByteStream in(bytes);
  return detail::read_ply_stream(in, bytes.size(), name, infinite);
}

// Writes every Gaussian of `scene` (atomic: temp file + rename).
inline void write_ply(const std::filesystem::path& path, const GaussianScene& scene, bool binary = true) {
  detail::check_writable(path, scene, nullptr, nullptr);
  atomic_write(path, [&](std::ostream& out) { detail::write_ply_stream(out, scene, nullptr, nullptr, binary); });
}

// Writes the Gaussians `indices` (in that order); `log_scale`, when given, replaces their
// log-scales (column d aligned with `indices`), e.g. the refined scales of ABR.
inline void write_ply(const std::filesystem::path& path, const GaussianScene& scene,
                      const std::vector<Index>& indices, const LogScales* log_scale = nullptr,
                      bool binary = true) {
  detail::check_writable(path, scene, &indices, log_scale);
  atomic_write(path, [&](std::ostream& out) { detail::write_ply_stream(out, scene, &indices, log_scale, binary); });
}

}  // namespace vcar::io
