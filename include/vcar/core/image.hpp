#pragma once
// Images and masks: row-major, interleaved channels. A Mask is W x H, 8-bit, nonzero =
// foreground (conventions §4).
#include <cmath>
#include <cstdint>
#include <vector>

namespace vcar {

template <class T>
struct Image {
  int width = 0, height = 0, channels = 1;
  std::vector<T> data;

  Image() = default;
  Image(int w, int h, int c = 1, T fill = T{})
      : width(w), height(h), channels(c), data(static_cast<std::size_t>(w) * h * c, fill) {}

  bool empty() const noexcept { return data.empty(); }
  std::size_t pixels() const noexcept { return static_cast<std::size_t>(width) * height; }
  T& operator()(int x, int y, int c = 0) {
    return data[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
  const T& operator()(int x, int y, int c = 0) const {
    return data[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
};

using Mask = Image<std::uint8_t>;      // 1 channel, nonzero = foreground
using ImageRGB8 = Image<std::uint8_t>;  // 3 channels
using ImageF = Image<float>;            // renderer output (rgb: 3 channels, alpha/depth: 1)

// Foreground at a continuous point: the pixel containing it (floor); false outside the image.
inline bool mask_at(const Mask& m, float u, float v) {
  if (!(u >= 0.f && v >= 0.f && u < static_cast<float>(m.width) && v < static_cast<float>(m.height)))
    return false;
  return m.data[static_cast<std::size_t>(static_cast<int>(v)) * m.width + static_cast<int>(u)] != 0;
}

// mask_at without a branch on the bounds, for lookups whose outcome the data decides (ABR's
// endpoints): outside the image the index is pixel 0's and the answer false. Where the caller has
// already tested the bounds, mask_at costs less (the compiler merges the two tests).
inline bool mask_at_branchless(const Mask& m, float u, float v) {
  if (m.data.empty()) return false;  // no pixel 0
  const bool in = (u >= 0.f) & (v >= 0.f) & (u < static_cast<float>(m.width)) & (v < static_cast<float>(m.height));
  const std::size_t i = static_cast<std::size_t>(static_cast<int>(in ? v : 0.f)) * static_cast<std::size_t>(m.width) +
                        static_cast<std::size_t>(static_cast<int>(in ? u : 0.f));
  return in & (m.data[i] != 0);
}

// Float image in [0,1] to 8-bit: round(255 v), halves away from zero (std::lround), v clamped
// to [0, 1], NaN to 0. Every frame the segmenter gets goes through here, so without a call per
// value: x = 255 v in [0, 255], t = trunc(x), and x - t is exact (t <= x < t + 1).
inline Image<std::uint8_t> to_8bit(const ImageF& img) {
  Image<std::uint8_t> out(img.width, img.height, img.channels);
  const float* in = img.data.data();
  std::uint8_t* o = out.data.data();
  for (std::size_t k = 0; k < img.data.size(); ++k) {
    const float v = in[k] > 0.f ? (in[k] < 1.f ? in[k] : 1.f) : 0.f;  // NaN: 0
    const float x = v * 255.f;
    const int t = static_cast<int>(x);
    o[k] = static_cast<std::uint8_t>(t + (x - static_cast<float>(t) >= 0.5f ? 1 : 0));
  }
  return out;
}

// Predicted mask of a rendering: alpha > threshold (conventions §6).
inline Mask threshold(const ImageF& alpha, float a) {
  Mask m(alpha.width, alpha.height, 1);
  for (std::size_t k = 0; k < m.data.size(); ++k) m.data[k] = alpha.data[k] > a ? 255 : 0;
  return m;
}

}  // namespace vcar
