#pragma once
// Candidates' means sorted along a Morton curve and cut into chunks with their bounding boxes,
// so that one view can decide a whole chunk at once (VisibilityVoting, RobustVoting).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "vcar/algo/mean_projection.hpp"
#include "vcar/core/morton_order.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/scratch_vector.hpp"

namespace vcar::detail {

// Means sorted along a Morton curve and cut into chunks of `chunk_size` with their bounding
// boxes: one view decides a whole chunk when its box is clearly invisible, or clearly visible
// over uniform mask tiles (project_box, MaskTiles); only the other chunks are voted mean by mean.
struct ChunkedMeans {
  static constexpr std::size_t chunk_size = 256;  // a multiple of mean_batch
  scratch_vector<std::uint32_t> order;   // sorted position j -> candidate position
  std::array<scratch_vector<float>, 3> xyz;  // sorted means, padded with NaN to whole chunks
  std::vector<std::array<float, 6>> box;  // per chunk: lo x, y, z, hi x, y, z

  static_assert(chunk_size % mean_batch == 0);
  ChunkedMeans() = default;
  ChunkedMeans(const float* x, const float* y, const float* z, std::size_t n) {
    order = morton_order(x, y, z, n, 20);  // chunks need compact runs, not the finest order
    const std::size_t chunks = (n + chunk_size - 1) / chunk_size, padded = chunks * chunk_size;
    const float* src[3] = {x, y, z};
    for (int d = 0; d < 3; ++d) {  // written below by the chunks' tasks, the padding here
      xyz[d].resize(padded);
      std::fill(xyz[d].begin() + static_cast<std::ptrdiff_t>(n), xyz[d].end(), std::numeric_limits<float>::quiet_NaN());
    }
    box.resize(chunks);
    parallel_for(static_cast<std::int64_t>(chunks), [&](std::int64_t c) {  // each chunk its own means and box
      const std::size_t j0 = static_cast<std::size_t>(c) * chunk_size, j1 = std::min(n, j0 + chunk_size);
      for (int d = 0; d < 3; ++d)
        for (std::size_t j = j0; j < j1; ++j) xyz[d][j] = src[d][order[j]];
      box[c] = mean_box(xyz[0].data(), xyz[1].data(), xyz[2].data(), j0, j1);
    });
  }
  std::size_t chunks() const { return box.size(); }
};

}  // namespace vcar::detail
