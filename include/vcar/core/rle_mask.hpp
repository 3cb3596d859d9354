#pragma once
// A mask kept as run lengths: what the pipeline holds of a view after voting on it, so the
// masks ABR needs later cost O(boundary) bytes instead of W x H ("views streamed, not stored").
#include <algorithm>
#include <cstdint>
#include <vector>

#include "vcar/core/image.hpp"

namespace vcar {

struct RleMask {
  int width = 0, height = 0;
  // Alternating run lengths over the row-major pixels, starting with background (may be 0).
  std::vector<std::uint32_t> runs;

  static RleMask encode(const Mask& m) {
    RleMask r;
    r.width = m.width;
    r.height = m.height;
    bool fg = false;
    std::uint32_t run = 0;
    for (std::uint8_t v : m.data) {
      if ((v != 0) != fg) {
        r.runs.push_back(run);
        run = 0;
        fg = !fg;
      }
      ++run;
    }
    r.runs.push_back(run);
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
};

}  // namespace vcar
