#pragma once
// Image and mask files through stb (PNG, JPEG and whatever else stb_image decodes).
//
// Masks (CONVENTIONS 4): the result is one 8-bit channel, 255 = foreground, 0 = background.
// - 8-bit grey: nonzero is foreground; 16-bit PNG (read with stbi_load_16): nonzero likewise.
// - colour masks, including paletted PNG (stb expands the palette to RGB(A)): a pixel is
//   foreground when it is not black, i.e. any colour channel is nonzero. Alpha is ignored,
//   except when the colour is black everywhere: then the alpha channel is the mask.
// - a mask of another size than expected is an error naming the file and both sizes.
// PNG writing is atomic (encoded in memory, then temp file + rename).
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <ostream>
#include <string>
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
}  // namespace detail

// Any image stb can decode, as 8-bit RGB (grey is replicated, alpha dropped).
inline ImageRGB8 read_image_rgb8(const std::filesystem::path& path) {
  int w = 0, h = 0, n = 0;
  stbi_uc* px = stbi_load(path.string().c_str(), &w, &h, &n, 3);
  if (!px) throw Error("cannot read image: " + detail::stb_reason(), path.string());
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

// Float image in [0,1] (clamped, rounded to 8 bits).
inline void write_png(const std::filesystem::path& path, const ImageF& img) {
  if (img.data.size() != img.pixels() * static_cast<std::size_t>(img.channels))
    throw Error("image data does not match its size", path.string());
  write_png(path, to_8bit(img));
}

// A binary mask (see the top of this file); expected_width/height < 0 accept any size.
inline Mask read_mask(const std::filesystem::path& path, int expected_width = -1, int expected_height = -1) {
  const std::string where = path.string();
  const std::string file = path.string();
  int w = 0, h = 0, n = 0;
  if (!stbi_info(file.c_str(), &w, &h, &n)) throw Error("cannot read mask: " + detail::stb_reason(), where);
  if ((expected_width >= 0 && w != expected_width) || (expected_height >= 0 && h != expected_height))
    throw Error("mask is " + std::to_string(w) + " x " + std::to_string(h) + " but the view is " +
                std::to_string(expected_width) + " x " + std::to_string(expected_height), where);
  Mask m(w, h, 1);
  const std::size_t N = m.pixels();
  auto fill = [&](const auto* px) {
    const int colour = (n == 2 || n == 4) ? n - 1 : n;  // channels before alpha
    bool any_colour = false;
    for (std::size_t p = 0; p < N; ++p) {
      bool fg = false;
      for (int c = 0; c < colour; ++c) fg = fg || px[p * n + c] != 0;
      m.data[p] = fg ? 255 : 0;
      any_colour = any_colour || fg;
    }
    if (!any_colour && colour != n)  // black everywhere: the alpha channel carries the mask
      for (std::size_t p = 0; p < N; ++p) m.data[p] = px[p * n + colour] != 0 ? 255 : 0;
  };
  if (stbi_is_16_bit(file.c_str())) {
    int n2 = 0;
    stbi_us* px = stbi_load_16(file.c_str(), &w, &h, &n2, 0);
    if (!px) throw Error("cannot read mask: " + detail::stb_reason(), where);
    n = n2;
    fill(px);
    stbi_image_free(px);
  } else {
    int n2 = 0;
    stbi_uc* px = stbi_load(file.c_str(), &w, &h, &n2, 0);
    if (!px) throw Error("cannot read mask: " + detail::stb_reason(), where);
    n = n2;
    fill(px);
    stbi_image_free(px);
  }
  return m;
}

}  // namespace vcar::io
