#pragma once
// Niantic SPZ files (github.com/nianticlabs/spz). Two containers:
//   v2, v3: one gzip stream holding a 16-byte header {u32 magic 0x5053474e "NGSP", u32 version,
//           u32 n, u8 sh_degree, u8 fractional_bits, u8 flags, u8 reserved} and the arrays;
//   v4:     a plain 32-byte header {magic, version, n, sh_degree, fractional_bits, flags,
//           u8 streams, u32 toc_offset, 12 reserved bytes}, extension records up to toc_offset,
//           a table of {u64 compressed, u64 uncompressed} per stream, then one zstd frame per array.
// Arrays, in this order: positions (24-bit signed fixed point, `fractional_bits`), alphas
// (u8, opacity AFTER the sigmoid), colours (u8, f_dc * 0.15 * 255 + 127.5), scales (u8, LOG scale
// (v / 16) - 10), rotations (v2: x y z as u8 (v / 127.5 - 1), w >= 0 derived; v3+: smallest
// three, 2-bit index + 3 x (sign + 9-bit magnitude / 511 / sqrt(2)), quaternion order x y z w),
// SH (u8, (v - 128) / 128, coefficient-major with the channel inner: [k][c]).
// SPZ stores RUB axes (x right, y up, z back); the scene model (and the Inria PLY) is RDF, so
// reading and writing flip y and z: position (x, -y, -z), quaternion (w, x, -y, -z), and each SH
// coefficient by (-1)^(powers of y and z in its basis polynomial) (docs/formats.md).
// Gaussians keep the file's order. Reading checks every size against the file before allocating
// (a header may not claim more than 1024 bytes of output per byte of input). Writing produces v3
// (gzip; every SPZ reader opens it), SH at 8 bits. Needs zlib and zstd (Debian zlib1g-dev,
// libzstd-dev), linked by the target that provides the io headers.
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/compact_values.hpp"

namespace vcar::io {

inline constexpr std::uint32_t spz_magic = 0x5053474eu;  // "NGSP" little-endian

namespace detail {

inline constexpr float spz_colour_scale = 0.15f;
inline constexpr std::uint64_t spz_max_ratio = 1024;  // output bytes per input byte, at most
inline constexpr std::uint32_t spz_flag_antialiased = 0x1, spz_flag_extensions = 0x2;
inline constexpr std::uint32_t spz_ext_sh_quantization = 0xADBE0001u;

// RUB <-> RDF sign of SH coefficient k (1-based, k = l^2 + l + m) of the real basis: a flip of y
// and z multiplies Y_lm by (-1)^(degree of its polynomial in y and z).
inline float spz_sh_flip(int k) {
  static constexpr std::array<float, 16> s = {1,                 //
                                              -1, -1, 1,         // y, z, x
                                              -1, 1, 1, -1, 1,   // xy, yz, 3z^2-1, xz, x^2-y^2
                                              -1, 1, -1, -1, 1, -1, 1};
  return s[static_cast<std::size_t>(k)];
}

// Bytes per Gaussian of each array for a header; index: positions, alphas, colours, scales,
// rotations, sh.
inline std::array<std::uint64_t, 6> spz_array_bytes(std::uint32_t version, int sh_degree) {
  const std::uint64_t sh_dim = static_cast<std::uint64_t>((sh_degree + 1) * (sh_degree + 1) - 1);
  return {9, 1, 3, 3, version >= 3 ? 4u : 3u, sh_dim * 3};
}

struct SpzHeader {
  std::uint32_t version = 0, n = 0, flags = 0;
  int sh_degree = 0, fractional_bits = 0;
};

inline SpzHeader check_spz_header(const std::uint8_t* p, const std::string& where) {
  SpzHeader h;
  if (load_u32(p) != spz_magic) throw Error("not an SPZ stream (no NGSP magic)", where);
  h.version = load_u32(p + 4);
  h.n = load_u32(p + 8);
  h.sh_degree = p[12];
  h.fractional_bits = p[13];
  h.flags = p[14];
  if (h.version < 2 || h.version > 4)
    throw Error("SPZ version " + std::to_string(h.version) + " is not supported (2, 3 and 4 are)", where);
  if (h.sh_degree > 3)
    throw Error("SPZ SH degree " + std::to_string(h.sh_degree) + " is not supported: vcar keeps degree 0-3 "
                "(convert with `splat-transform in.spz -H 3 out.spz`)", where);
  if (h.fractional_bits > 23) throw Error("SPZ fractional bits " + std::to_string(h.fractional_bits) + " > 23", where);
  return h;
}

// The arrays (concatenated, in file order) into a scene, flipping RUB to RDF.
inline GaussianScene decode_spz_arrays(const SpzHeader& h, const std::uint8_t* a, float sh_min, float sh_max,
                                       const std::string& where) {
  const std::size_t n = h.n;
  const auto bytes = spz_array_bytes(h.version, h.sh_degree);
  GaussianScene s;
  s.resize(n, h.sh_degree);
  const std::size_t B = static_cast<std::size_t>(s.sh_coeffs()), sh_dim = B - 1;
  const std::uint8_t* pos = a;
  const std::uint8_t* alpha = pos + n * bytes[0];
  const std::uint8_t* colour = alpha + n * bytes[1];
  const std::uint8_t* scale = colour + n * bytes[2];
  const std::uint8_t* rot = scale + n * bytes[3];
  const std::uint8_t* sh = rot + n * bytes[4];
  const float fixed = 1.f / static_cast<float>(1u << h.fractional_bits);
  constexpr float flip[3] = {1.f, -1.f, -1.f};  // RUB -> RDF
  const bool legacy_sh = sh_min == -1.f && sh_max == 1.f;
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      const std::uint8_t* p = pos + (i * 3 + static_cast<std::size_t>(d)) * 3;
      std::int32_t v = static_cast<std::int32_t>(p[0] | p[1] << 8 | p[2] << 16);
      if (v & 0x800000) v -= 0x1000000;  // sign of the 24-bit value
      s.mean[d][i] = flip[d] * static_cast<float>(v) * fixed;
      s.log_scale[d][i] = static_cast<float>(scale[i * 3 + static_cast<std::size_t>(d)]) / 16.f - 10.f;
    }
    s.opacity_logit[i] = opacity_logit_from_alpha(static_cast<float>(alpha[i]) / 255.f);
    for (std::size_t c = 0; c < 3; ++c)
      s.sh[i * B * 3 + c] = (static_cast<float>(colour[i * 3 + c]) / 255.f - 0.5f) / spz_colour_scale;
    float xyzw[4];
    if (h.version >= 3) {  // smallest three
      const std::uint32_t comp = load_u32(rot + i * 4);
      const std::uint32_t largest = comp >> 30;
      std::uint32_t bits = comp;
      float sum = 0.f;
      for (int k = 3; k >= 0; --k) {
        if (static_cast<std::uint32_t>(k) == largest) continue;
        const float mag = static_cast<float>(bits & 511u) / 511.f * 0.70710678f;
        xyzw[k] = (bits >> 9) & 1u ? -mag : mag;
        sum += xyzw[k] * xyzw[k];
        bits >>= 10;
      }
      xyzw[largest] = std::sqrt(std::max(0.f, 1.f - sum));
    } else {  // x y z, w >= 0
      float sum = 0.f;
      for (int k = 0; k < 3; ++k) {
        xyzw[k] = static_cast<float>(rot[i * 3 + static_cast<std::size_t>(k)]) / 127.5f - 1.f;
        sum += xyzw[k] * xyzw[k];
      }
      xyzw[3] = std::sqrt(std::max(0.f, 1.f - sum));
    }
    s.rotation[0][i] = xyzw[3];
    for (int k = 0; k < 3; ++k) s.rotation[k + 1][i] = flip[k] * xyzw[k];
    for (std::size_t k = 0; k < sh_dim; ++k)
      for (std::size_t c = 0; c < 3; ++c) {
        const float v = static_cast<float>(sh[(i * sh_dim + k) * 3 + c]);
        const float value = legacy_sh ? (v - 128.f) / 128.f : sh_min + v / 255.f * (sh_max - sh_min);
        s.sh[(i * B + k + 1) * 3 + c] = spz_sh_flip(static_cast<int>(k + 1)) * value;
      }
  }
  s.validate(where);
  return s;
}

// gzip: inflates the first `limit` bytes of the stream; throws if the stream is corrupt or, when
// `exact`, ends before `limit` bytes (data after them is ignored, as SPZ readers do).
inline std::vector<std::uint8_t> gunzip(const std::uint8_t* data, std::size_t size, std::uint64_t limit, bool exact,
                                        const std::string& where) {
  z_stream z{};
  if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) throw Error("zlib inflateInit2 failed", where);
  std::vector<std::uint8_t> out(static_cast<std::size_t>(limit));
  constexpr std::size_t step = std::size_t{1} << 30;  // zlib counts in 32-bit uInt
  std::size_t in_left = size, out_done = 0;
  z.next_in = const_cast<Bytef*>(data);
  int rc = Z_OK;
  while (out_done < out.size()) {
    if (z.avail_in == 0 && in_left > 0) {
      z.avail_in = static_cast<uInt>(std::min(in_left, step));
      in_left -= z.avail_in;
    }
    const uInt chunk = static_cast<uInt>(std::min(out.size() - out_done, step));
    z.next_out = out.data() + out_done;
    z.avail_out = chunk;
    rc = inflate(&z, Z_NO_FLUSH);
    out_done += chunk - z.avail_out;
    if (rc == Z_STREAM_END) break;
    if (rc == Z_BUF_ERROR && z.avail_in == 0 && in_left == 0) break;  // input exhausted
    if (rc != Z_OK) break;
  }
  const std::string msg = z.msg ? z.msg : "zlib error " + std::to_string(rc);
  inflateEnd(&z);
  if (rc == Z_DATA_ERROR || rc == Z_STREAM_ERROR || rc == Z_MEM_ERROR || rc == Z_NEED_DICT)
    throw Error("corrupt gzip stream (" + msg + ")", where);
  if (exact && out_done < limit)
    throw Error("gzip stream ends after " + std::to_string(out_done) + " bytes, the header declares " +
                std::to_string(limit) + " (truncated?)", where);
  out.resize(out_done);
  return out;
}

}  // namespace detail

// Decodes SPZ bytes (the whole file); `where` names the file in errors.
inline GaussianScene decode_spz(const std::uint8_t* data, std::size_t size, const std::string& where) {
  using namespace detail;
  if (size >= 2 && data[0] == 0x1f && data[1] == 0x8b) {  // v2, v3: one gzip stream
    const std::vector<std::uint8_t> head = gunzip(data, size, 16, true, where);
    const SpzHeader h = check_spz_header(head.data(), where);
    if (h.version >= 4) throw Error("SPZ version 4 inside gzip: not a valid SPZ file", where);
    if (h.flags & spz_flag_extensions)
      throw Error("SPZ v" + std::to_string(h.version) + " with extension records is not supported (re-save as SPZ v4)", where);
    const auto per = spz_array_bytes(h.version, h.sh_degree);
    std::uint64_t total = 16;
    for (auto b : per) total += b * h.n;
    if (total > spz_max_ratio * static_cast<std::uint64_t>(size) + 4096)
      throw Error("header declares " + std::to_string(h.n) + " Gaussians (" + std::to_string(total) + " bytes) but a " +
                  std::to_string(size) + "-byte file cannot hold them (lying header?)", where);
    const std::vector<std::uint8_t> all = gunzip(data, size, total, true, where);
    return decode_spz_arrays(h, all.data() + 16, -1.f, 1.f, where);
  }
  if (size >= 16 && load_u32(data) == spz_magic && load_u32(data + 4) < 4) {  // v2, v3 already inflated
    const SpzHeader h = check_spz_header(data, where);
    if (h.flags & spz_flag_extensions)
      throw Error("SPZ v" + std::to_string(h.version) + " with extension records is not supported (re-save as SPZ v4)", where);
    std::uint64_t total = 16;
    for (auto b : spz_array_bytes(h.version, h.sh_degree)) total += b * h.n;
    if (total > size)
      throw Error("header declares " + std::to_string(h.n) + " Gaussians (" + std::to_string(total) + " bytes) but the " +
                  std::to_string(size) + " bytes hold fewer (truncated?)", where);
    return decode_spz_arrays(h, data + 16, -1.f, 1.f, where);
  }
  if (size < 32) throw Error("not an SPZ file (" + std::to_string(size) + " bytes, neither gzip nor a 32-byte NGSP header)", where);
  const SpzHeader h = check_spz_header(data, where);
  const std::uint32_t streams = data[15], toc = load_u32(data + 16);
  const auto per = spz_array_bytes(h.version, h.sh_degree);
  std::uint32_t wanted = 0;
  for (auto b : per) wanted += b > 0;
  if (streams != wanted)
    throw Error("SPZ v4 header declares " + std::to_string(streams) + " streams, SH degree " + std::to_string(h.sh_degree) +
                " needs " + std::to_string(wanted), where);
  if (toc < 32 || toc > size || (size - toc) / 16 < streams)
    throw Error("SPZ v4 table of contents at byte " + std::to_string(toc) + " lies outside the " + std::to_string(size) + "-byte file", where);
  // Extension records [u32 type][u32 length][payload] between the header and the table.
  float sh_min = -1.f, sh_max = 1.f;
  for (std::size_t at = 32; at < toc;) {
    if (toc - at < 8) throw Error("truncated SPZ extension record at byte " + std::to_string(at), where);
    const std::uint32_t type = load_u32(data + at), len = load_u32(data + at + 4);
    if (len > toc - at - 8) throw Error("SPZ extension record at byte " + std::to_string(at) + " runs past the table of contents", where);
    if (type == spz_ext_sh_quantization && len >= 10) {
      sh_min = load_f32(data + at + 10);
      sh_max = load_f32(data + at + 14);
      if (!std::isfinite(sh_min) || !std::isfinite(sh_max) || !(sh_max > sh_min))
        throw Error("SPZ SH quantisation extension has an invalid range", where);
    }
    at += 8 + static_cast<std::size_t>(len);
  }
  std::uint64_t total = 0, at = static_cast<std::uint64_t>(toc) + 16ull * streams;
  std::vector<std::array<std::uint64_t, 3>> frames;  // offset, compressed, uncompressed
  for (std::size_t k = 0, s = 0; k < per.size(); ++k) {
    if (per[k] == 0) continue;
    const std::uint64_t csize = load_u64(data + toc + 16 * s), usize = load_u64(data + toc + 16 * s + 8);
    ++s;
    if (usize != per[k] * h.n)
      throw Error("SPZ v4 stream " + std::to_string(k) + " declares " + std::to_string(usize) + " bytes, " +
                  std::to_string(h.n) + " Gaussians need " + std::to_string(per[k] * h.n), where);
    if (csize > size - std::min<std::uint64_t>(size, at))
      throw Error("SPZ v4 stream " + std::to_string(k) + " (" + std::to_string(csize) + " bytes at byte " + std::to_string(at) +
                  ") runs past the end of the file (truncated?)", where);
    frames.push_back({at, csize, usize});
    at += csize;
    total += usize;
  }
  if (total > spz_max_ratio * static_cast<std::uint64_t>(size) + 4096)
    throw Error("header declares " + std::to_string(h.n) + " Gaussians (" + std::to_string(total) + " bytes) but a " +
                std::to_string(size) + "-byte file cannot hold them (lying header?)", where);
  std::vector<std::uint8_t> all(static_cast<std::size_t>(total));
  std::size_t out = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const auto [off, csize, usize] = frames[k];
    const std::size_t got = usize == 0 ? 0
        : ZSTD_decompress(all.data() + out, static_cast<std::size_t>(usize), data + off, static_cast<std::size_t>(csize));
    if (ZSTD_isError(got)) throw Error("SPZ v4 stream " + std::to_string(k) + ": " + ZSTD_getErrorName(got), where);
    if (got != usize) throw Error("SPZ v4 stream " + std::to_string(k) + " holds " + std::to_string(got) + " bytes, expected " +
                                  std::to_string(usize) + " (truncated?)", where);
    out += got;
  }
  return decode_spz_arrays(h, all.data(), sh_min, sh_max, where);
}

inline GaussianScene read_spz(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = detail::read_whole_file(path, "SPZ file");
  return decode_spz(bytes.data(), bytes.size(), path.string());
}

// The same from the file's bytes in memory; `name` stands for the file in errors.
inline GaussianScene read_spz(std::span<const std::uint8_t> bytes, const std::string& name) {
  return decode_spz(bytes.data(), bytes.size(), name);
}

// The v3 payload (header + arrays, before gzip) of `scene`; throws if a position does not fit
// the 24-bit fixed point (|x| >= 2048 world units) or the SH degree exceeds 3.
inline std::string encode_spz_payload(const GaussianScene& scene, const std::string& where) {
  using namespace detail;
  constexpr int fractional_bits = 12;
  const std::size_t n = scene.size(), B = static_cast<std::size_t>(scene.sh_coeffs()), sh_dim = B - 1;
  if (n > 0xffffffffu) throw Error("too many Gaussians for SPZ", where);
  std::string out;
  store_u32(out, spz_magic);
  store_u32(out, 3);
  store_u32(out, static_cast<std::uint32_t>(n));
  out.push_back(static_cast<char>(scene.sh_degree));
  out.push_back(static_cast<char>(fractional_bits));
  out.push_back(0);  // flags
  out.push_back(0);  // reserved
  constexpr float flip[3] = {1.f, -1.f, -1.f};  // RDF -> RUB
  const float fixed = static_cast<float>(1 << fractional_bits);
  auto byte = [](double v) { return static_cast<char>(std::clamp(std::lround(v), 0L, 255L)); };
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      const double v = std::round(static_cast<double>(flip[d] * scene.mean[d][i]) * fixed);
      if (!(std::abs(v) < 8388608.0))
        throw Error("Gaussian " + std::to_string(i) + " lies at " + std::to_string(scene.mean[d][i]) +
                    ": SPZ positions must be within +-2048 world units", where);
      const std::int32_t q = static_cast<std::int32_t>(v);
      for (int b = 0; b < 3; ++b) out.push_back(static_cast<char>((static_cast<std::uint32_t>(q) >> (8 * b)) & 0xffu));
    }
  for (std::size_t i = 0; i < n; ++i) out.push_back(byte(sigmoid(scene.opacity_logit[i]) * 255.0));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < 3; ++c) out.push_back(byte(scene.sh[i * B * 3 + c] * (spz_colour_scale * 255.0) + 127.5));
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) out.push_back(byte((scene.log_scale[d][i] + 10.0) * 16.0));
  for (std::size_t i = 0; i < n; ++i) {  // smallest three of (x y z w) after the flip
    float q[4] = {scene.rotation[1][i], -scene.rotation[2][i], -scene.rotation[3][i], scene.rotation[0][i]};
    const float norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    std::uint32_t largest = 0;
    for (std::uint32_t k = 0; k < 4; ++k) {
      q[k] /= norm;
      if (std::abs(q[k]) > std::abs(q[largest])) largest = k;
    }
    const bool negate = q[largest] < 0.f;
    std::uint32_t comp = largest;
    for (std::uint32_t k = 0; k < 4; ++k) {
      if (k == largest) continue;
      const std::uint32_t sign = (q[k] < 0.f) != negate ? 1u : 0u;
      const std::uint32_t mag = std::min<std::uint32_t>(511u, static_cast<std::uint32_t>(std::lround(std::abs(q[k]) / 0.70710678 * 511.0)));
      comp = comp << 10 | sign << 9 | mag;
    }
    store_u32(out, comp);
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < sh_dim; ++k)
      for (std::size_t c = 0; c < 3; ++c)
        out.push_back(byte(spz_sh_flip(static_cast<int>(k + 1)) * scene.sh[(i * B + k + 1) * 3 + c] * 128.0 + 128.0));
  return out;
}

// Writes `scene` as SPZ v3 (gzip; atomic). Extras are dropped; values are quantised as above.
inline void write_spz(const std::filesystem::path& path, const GaussianScene& scene) {
  const std::string where = path.string();
  scene.validate(where);
  const std::string payload = encode_spz_payload(scene, where);
  z_stream z{};
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 9, Z_DEFAULT_STRATEGY) != Z_OK)
    throw Error("zlib deflateInit2 failed", where);
  std::string gz(static_cast<std::size_t>(deflateBound(&z, static_cast<uLong>(payload.size()))) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(payload.data()));
  z.avail_in = static_cast<uInt>(payload.size());
  z.next_out = reinterpret_cast<Bytef*>(gz.data());
  z.avail_out = static_cast<uInt>(gz.size());
  const int rc = deflate(&z, Z_FINISH);
  gz.resize(gz.size() - z.avail_out);
  deflateEnd(&z);
  if (rc != Z_STREAM_END) throw Error("zlib deflate failed (" + std::to_string(rc) + ")", where);
  atomic_write(path, [&](std::ostream& o) { o.write(gz.data(), static_cast<std::streamsize>(gz.size())); });
}

}  // namespace vcar::io
