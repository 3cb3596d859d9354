#pragma once
// Image and mask files through stb (PNG, JPEG and whatever else stb_image decodes).
//
// Masks (conventions §4): the result is one 8-bit channel, 255 = foreground, 0 = background.
// - 8-bit grey or colour: a pixel is foreground when a colour channel reaches half range
//   (>= 128), so compression noise around 0 and 255 (JPEG masks) counts for nothing; 16-bit PNG
//   (read with stbi_load_16) likewise at >= 32768. A mask that holds only the values 0 and 1 is
//   a 0/1 label mask: 1 is foreground.
// - paletted PNG: by index, as conventions §4 says: a pixel is foreground when its palette index
//   is not 0, whatever the colours (DAVIS/VOC palettes: index 0 black, objects coloured, some
//   dark; other writers pad their palettes with black entries). stb expands a palette to colours,
//   so the palette is rewritten first, in memory, to entry k = grey k (detail::palette_as_index).
// - Alpha is ignored, except when the colour is background everywhere: then the alpha channel
//   is the mask (same threshold).
// - a mask of another size than expected is an error naming the file and both sizes.
// PNG and JPEG writing is atomic (encoded in memory, then temp file + rename).
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <stb_image.h>
#include <stb_image_write.h>

#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"
#include "vcar/io/atomic_file.hpp"

namespace vcar::io {

namespace detail {
inline std::string stb_reason() {
  const char* r = stbi_failure_reason();
  return r ? r : "unknown reason";
}

// The whole file in memory (masks and frames are small; stb then decodes from memory).
inline std::vector<stbi_uc> read_file_bytes(const std::filesystem::path& path, const std::string& where) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!in || ec) throw Error("cannot open image file", where);
  if (size > (std::uintmax_t{1} << 31)) throw Error("image file is larger than 2 GiB", where);
  std::vector<stbi_uc> bytes(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<std::size_t>(in.gcount()) != bytes.size()) throw Error("cannot read image file", where);
  return bytes;
}

// Calls f(at, len, type) for each chunk of a PNG's bytes (nothing for another format): `at` the
// chunk's first byte, `len` its declared data length, `type` its four letters; stops after IEND
// or at the end of the bytes. f may write the chunk's data, not its length.
template <class Bytes, class F>
void for_each_png_chunk(Bytes& b, F&& f) {
  static constexpr stbi_uc png_sig[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  if (b.size() < 8 || !std::equal(png_sig, png_sig + 8, b.begin())) return;
  for (std::size_t at = 8; at + 8 <= b.size();) {
    const std::uint64_t len = (std::uint64_t{b[at]} << 24) | (std::uint64_t{b[at + 1]} << 16) |
                              (std::uint64_t{b[at + 2]} << 8) | b[at + 3];
    const std::string_view type(reinterpret_cast<const char*>(b.data() + at + 4), 4);
    f(at, len, type);
    if (type == "IEND") break;
    at += static_cast<std::size_t>(len) + 12;  // length, type, data, CRC
  }
}

// A paletted PNG's bytes with each PLTE entry k replaced by the grey (k, k, k), so that stb's
// decoded colour is the index (a palette holds at most 256 entries). The chunk's CRC is left as
// it was: stb does not check CRCs (stb_image.h: "no CRC checking"), and these bytes are only
// decoded here, never written. Call after check_image_bytes (chunk lengths within the file).
inline std::vector<stbi_uc> palette_as_index(std::vector<stbi_uc> b) {
  for_each_png_chunk(b, [&](std::size_t at, std::uint64_t len, std::string_view type) {
    if (type == "PLTE")
      for (std::size_t k = 0; 3 * k + 2 < len && k < 256; ++k)
        for (std::size_t c = 0; c < 3; ++c) b[at + 8 + 3 * k + c] = static_cast<stbi_uc>(k);
  });
  return b;
}

// Lying sizes are rejected before stb allocates for them: a PNG chunk longer than the rest of
// the file (stb reserves the declared length first), or a header claiming more pixels than the
// file can encode (no format stb decodes packs over 4096 raw bytes into one file byte).
inline void check_image_bytes(const std::vector<stbi_uc>& b, const std::string& where) {
  for_each_png_chunk(b, [&](std::size_t at, std::uint64_t len, std::string_view) {
    if (len + 12 > b.size() - at)
      throw Error("PNG chunk at byte " + std::to_string(at) + " declares " + std::to_string(len) +
                  " bytes, more than the file holds (corrupt or truncated?)", where);
  });
  const int len = static_cast<int>(b.size());
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(b.data(), len, &w, &h, &n)) throw Error("cannot read image: " + stb_reason(), where);
  const double raw = static_cast<double>(w) * static_cast<double>(h) * static_cast<double>(n) *
                     (stbi_is_16_bit_from_memory(b.data(), len) ? 2.0 : 1.0);
  if (w <= 0 || h <= 0 || raw > 4096.0 * static_cast<double>(b.size()) + static_cast<double>(1 << 20))
    throw Error("header claims " + std::to_string(w) + " x " + std::to_string(h) +
                " pixels, more than the file can hold (corrupt or truncated?)", where);
}
}  // namespace detail

// Any image stb can decode, as 8-bit RGB (grey is replicated, alpha dropped).
inline ImageRGB8 read_image_rgb8(const std::filesystem::path& path) {
  const std::string where = path.string();
  const std::vector<stbi_uc> bytes = detail::read_file_bytes(path, where);
  detail::check_image_bytes(bytes, where);
  int w = 0, h = 0, n = 0;
  stbi_uc* px = stbi_load_from_memory(bytes.data(), static_cast<int>(bytes.size()), &w, &h, &n, 3);
  if (!px) throw Error("cannot read image: " + detail::stb_reason(), where);
  ImageRGB8 img(w, h, 3);
  std::copy(px, px + img.data.size(), img.data.begin());
  stbi_image_free(px);
  return img;
}

// 8-bit PNG with 1 (grey), 3 (RGB) or 4 (RGBA) channels.
inline void write_png(const std::filesystem::path& path, const Image<std::uint8_t>& img) {
  const std::string where = path.string();
  if (img.channels != 1 && img.channels != 3 && img.channels != 4)
    throw Error("PNG needs 1, 3 or 4 channels, got " + std::to_string(img.channels), where);
  if (img.width <= 0 || img.height <= 0 || img.data.size() != img.pixels() * static_cast<std::size_t>(img.channels))
    throw Error("image is empty or its data does not match its size", where);
  std::vector<unsigned char> png;
  auto sink = [](void* ctx, void* data, int size) {
    auto* v = static_cast<std::vector<unsigned char>*>(ctx);
    v->insert(v->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
  };
  if (!stbi_write_png_to_func(sink, &png, img.width, img.height, img.channels, img.data.data(),
                              img.width * img.channels))
    throw Error("PNG encoding failed", where);
  atomic_write(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

// 8-bit baseline JPEG with 1 (grey) or 3 (RGB) channels, quality 1-100 (stb), atomic like PNG.
inline void write_jpg(const std::filesystem::path& path, const Image<std::uint8_t>& img, int quality = 95) {
  const std::string where = path.string();
  if (img.channels != 1 && img.channels != 3)
    throw Error("JPEG needs 1 or 3 channels, got " + std::to_string(img.channels), where);
  if (img.width <= 0 || img.height <= 0 || img.data.size() != img.pixels() * static_cast<std::size_t>(img.channels))
    throw Error("image is empty or its data does not match its size", where);
  if (quality < 1 || quality > 100) throw Error("JPEG quality must be in [1, 100]", where);
  std::vector<unsigned char> jpg;
  auto sink = [](void* ctx, void* data, int size) {
    auto* v = static_cast<std::vector<unsigned char>*>(ctx);
    v->insert(v->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
  };
  if (!stbi_write_jpg_to_func(sink, &jpg, img.width, img.height, img.channels, img.data.data(), quality))
    throw Error("JPEG encoding failed", where);
  atomic_write(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(jpg.data()), static_cast<std::streamsize>(jpg.size()));
  });
}

// PNG or JPEG by the file's extension (.png; .jpg or .jpeg, any case); any other is an error
// naming the file, so an image is never written in a format its name does not say.
inline void write_image(const std::filesystem::path& path, const Image<std::uint8_t>& img) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".png") return write_png(path, img);
  if (ext == ".jpg" || ext == ".jpeg") return write_jpg(path, img);
  throw Error("unknown image format '" + ext + "': name the file .png, .jpg or .jpeg", path.string());
}

// Float image in [0,1] (clamped, rounded to 8 bits).
inline void write_png(const std::filesystem::path& path, const ImageF& img) {
  if (img.data.size() != img.pixels() * static_cast<std::size_t>(img.channels))
    throw Error("image data does not match its size", path.string());
  write_png(path, to_8bit(img));
}

// A binary mask (see the top of this file); expected_width/height < 0 accept any size.
inline Mask read_mask(const std::filesystem::path& path, int expected_width = -1, int expected_height = -1) {
  const std::string where = path.string();
  const std::vector<stbi_uc> bytes = detail::read_file_bytes(path, where);
  const int len = static_cast<int>(bytes.size());
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(bytes.data(), len, &w, &h, &n)) throw Error("cannot read mask: " + detail::stb_reason(), where);
  if ((expected_width >= 0 && w != expected_width) || (expected_height >= 0 && h != expected_height))
    throw Error("mask is " + std::to_string(w) + " x " + std::to_string(h) + " but the view is " +
                std::to_string(expected_width) + " x " + std::to_string(expected_height), where);
  detail::check_image_bytes(bytes, where);
  Mask m;
  std::size_t N = 0;
  // PNG colour type 3 (IHDR byte 25): paletted; read by index (the top of this file).
  const bool paletted = bytes.size() > 25 && bytes[0] == 0x89 && bytes[1] == 'P' && bytes[25] == 3;
  if (paletted) {
    const std::vector<stbi_uc> indexed = detail::palette_as_index(bytes);
    int n2 = 0;
    stbi_uc* px = stbi_load_from_memory(indexed.data(), len, &w, &h, &n2, 0);
    if (!px) throw Error("cannot read mask: " + detail::stb_reason(), where);
    m = Mask(w, h, 1);
    for (std::size_t p = 0; p < m.pixels(); ++p) m.data[p] = px[p * static_cast<std::size_t>(n2)] != 0 ? 255 : 0;  // index != 0
    stbi_image_free(px);
    return m;
  }
  auto fill = [&](const auto* px, unsigned half) {
    m = Mask(w, h, 1);  // sized from the decoded image, not from the header alone
    N = m.pixels();
    const int colour = (n == 2 || n == 4) ? n - 1 : n;  // channels before alpha
    unsigned colour_max = 0, alpha_max = 0;
    for (std::size_t p = 0; p < N; ++p) {
      for (int c = 0; c < colour; ++c) colour_max = std::max<unsigned>(colour_max, px[p * n + c]);
      if (colour != n) alpha_max = std::max<unsigned>(alpha_max, px[p * n + colour]);
    }
    // Black everywhere: the alpha channel carries the mask.
    const int channel0 = colour_max == 0 && colour != n ? colour : 0;
    const int channels = colour_max == 0 && colour != n ? 1 : colour;
    const unsigned value_max = channel0 == 0 ? colour_max : alpha_max;
    const unsigned threshold = value_max == 1 ? 1 : half;  // 0/1 label masks: 1 is foreground
    for (std::size_t p = 0; p < N; ++p) {
      bool fg = false;
      for (int c = channel0; c < channel0 + channels; ++c) fg = fg || px[p * n + c] >= threshold;
      m.data[p] = fg ? 255 : 0;
    }
  };
  if (stbi_is_16_bit_from_memory(bytes.data(), len)) {
    int n2 = 0;
    stbi_us* px = stbi_load_16_from_memory(bytes.data(), len, &w, &h, &n2, 0);
    if (!px) throw Error("cannot read mask: " + detail::stb_reason(), where);
    n = n2;
    fill(px, 32768u);
    stbi_image_free(px);
  } else {
    int n2 = 0;
    stbi_uc* px = stbi_load_from_memory(bytes.data(), len, &w, &h, &n2, 0);
    if (!px) throw Error("cannot read mask: " + detail::stb_reason(), where);
    n = n2;
    fill(px, 128u);
    stbi_image_free(px);
  }
  return m;
}

}  // namespace vcar::io
