#pragma once
// A mask kept as run lengths: what the pipeline holds of a view after voting on it, so the
// masks ABR needs later cost O(boundary) bytes instead of W x H ("views streamed, not stored").
#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/simd.hpp"

namespace vcar {

struct RleMask {
  int width = 0, height = 0;
  // Alternating run lengths over the row-major pixels, starting with background (may be 0).
  std::vector<std::uint32_t> runs;

  static constexpr std::size_t parallel_pixels = std::size_t{1} << 18;  // masks this large encode in parallel

  // The runs from the pixels' run boundaries (each pixel that differs from the one before it,
  // the first pixel against background): serially, or for large masks in fixed blocks of pixels
  // in parallel, joined in block order (the same runs for any thread count).
  static RleMask encode(const Mask& m) {
    RleMask r;
    r.width = m.width;
    r.height = m.height;
    const std::uint8_t* p = m.data.data();
    const std::size_t n = m.data.size();
    std::size_t start = 0;  // first pixel of the current run
    const auto push = [&](std::size_t at) {
      r.runs.push_back(static_cast<std::uint32_t>(at - start));
      start = at;
    };
    if (n < parallel_pixels) {
      for_each_boundary(p, 0, n, push);
    } else {
      constexpr std::size_t block = std::size_t{1} << 16;  // a multiple of 64
      std::vector<std::vector<std::uint32_t>> found((n + block - 1) / block);
      parallel_for(static_cast<std::int64_t>(found.size()), [&](std::int64_t b) {
        const std::size_t b0 = static_cast<std::size_t>(b) * block;
        auto& f = found[static_cast<std::size_t>(b)];
        for_each_boundary(p, b0, std::min(n, b0 + block), [&](std::size_t at) { f.push_back(static_cast<std::uint32_t>(at)); });
      });
      std::size_t total = 0;
      for (const auto& f : found) total += f.size();
      r.runs.reserve(total + 1);
      for (const auto& f : found)
        for (std::uint32_t at : f) push(at);
    }
    r.runs.push_back(static_cast<std::uint32_t>(n - start));
    return r;
  }

  // Decodes into `out` (reusing its storage): foreground pixels are 255.
  void decode(Mask& out) const {
    out.width = width;
    out.height = height;
    out.channels = 1;
    out.data.resize(static_cast<std::size_t>(width) * height);
    std::size_t p = 0;
    std::uint8_t value = 0;
    for (std::uint32_t run : runs) {
      std::fill_n(out.data.begin() + static_cast<std::ptrdiff_t>(p), run, value);
      p += run;
      value = value ? 0 : 255;
    }
  }
  Mask decode() const {
    Mask m;
    decode(m);
    return m;
  }
  std::size_t bytes() const noexcept { return runs.size() * sizeof(std::uint32_t); }

  // f(begin, end) for each foreground run [begin, end) of row-major pixels, in order.
  template <class F>
  void for_each_foreground(F&& f) const {
    std::size_t p = 0;
    bool fg = false;
    for (std::uint32_t run : runs) {
      if (fg && run) f(p, p + run);
      p += run;
      fg = !fg;
    }
  }

  // f(at) for each pixel `at` in [b0, b1) that differs (zero / nonzero) from the pixel before it
  // (pixel 0 from background), in order: 64 pixels at a time, their nonzero bits
  // (simd::nonzero_bytes_64), then one boundary per set bit of bits ^ (bits << 1 | previous
  // pixel), found with countr_zero. b0 is a multiple of 64 or 0.
  template <class F>
  static void for_each_boundary(const std::uint8_t* p, std::size_t b0, std::size_t b1, F&& f) {
    std::uint64_t before = b0 > 0 && p[b0 - 1] != 0;  // the pixel before the current 64
    auto boundaries = [&](std::size_t base, std::uint64_t bits, std::uint64_t valid) {
      std::uint64_t t = (bits ^ ((bits << 1) | before)) & valid;  // pixel base + i starts a run
      before = (bits >> 63) & 1u;
      for (; t; t &= t - 1) f(base + static_cast<std::size_t>(std::countr_zero(t)));
    };
    std::size_t b = b0;
    for (; b + 64 <= b1; b += 64) boundaries(b, simd::nonzero_bytes_64(p + b), ~std::uint64_t{0});
    if (b < b1) {  // the last b1 - b < 64 pixels
      std::uint64_t bits = 0;
      for (std::size_t i = b; i < b1; ++i) bits |= static_cast<std::uint64_t>(p[i] != 0) << (i - b);
      boundaries(b, bits, (std::uint64_t{1} << (b1 - b)) - 1);
    }
  }
};

// Decodes run-length masks one after another into one Mask, in time that grows with their
// foreground rather than with the image: a mask of the size decoded last only clears the last
// one's foreground runs and writes its own (ABR decodes every view's mask, once or twice).
class MaskDecoder {
public:
  // The decoded mask (foreground pixels 255), valid until the next call.
  const Mask& decode(const RleMask& r) {
    if (r.width != mask_.width || r.height != mask_.height || mask_.channels != 1) {
      r.decode(mask_);
    } else {
      std::uint8_t* px = mask_.data.data();
      last_.for_each_foreground([&](std::size_t b, std::size_t e) { std::fill(px + b, px + e, std::uint8_t{0}); });
      r.for_each_foreground([&](std::size_t b, std::size_t e) { std::fill(px + b, px + e, std::uint8_t{255}); });
    }
    last_.width = r.width;
    last_.height = r.height;
    last_.runs.assign(r.runs.begin(), r.runs.end());
    return mask_;
  }

private:
  Mask mask_;    // the decode of last_
  RleMask last_;
};

}  // namespace vcar
