#pragma once
// The seed pixels of an image, listed row by row: the exact squared distance from any pixel to
// the nearest seed, found by visiting the rows outwards from the pixel's own, each by a binary
// search, until the rows left lie farther than the nearest seed found. For a measure that needs
// the whole image's distances at a few pixels only (the contour pixels that a transform over a
// box around the mask cannot decide): the same values as squared_distance_to at those pixels,
// without a transform of the whole image.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vcar/core/distance_transform.hpp"

namespace vcar {

class RowSeeds {
public:
  // seed(x, y) for every pixel of a W x H image.
  template <class Seed>
  RowSeeds(int width, int height, Seed&& seed) {
    start_.reserve(static_cast<std::size_t>(std::max(height, 0)) + 1);
    start_.push_back(0);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x)
        if (seed(x, y)) xs_.push_back(x);
      start_.push_back(static_cast<std::uint32_t>(xs_.size()));
    }
  }
  bool empty() const noexcept { return xs_.empty(); }

  // The squared Euclidean distance from (x, y) to the nearest seed (pixel centres); no_seed when
  // the image has none. Equal to squared_distance_to(seeds, W, H) at (x, y).
  double nearest_squared(int x, int y) const {
    if (xs_.empty()) return no_seed;
    long long best = -1;
    auto row = [&](int v, long long dy2) {
      const auto b = xs_.begin() + start_[static_cast<std::size_t>(v)], e = xs_.begin() + start_[static_cast<std::size_t>(v) + 1];
      const auto it = std::lower_bound(b, e, x);  // the first seed at or right of x, and the one before it
      for (auto c : {it, it == b ? e : it - 1}) {
        if (c == e) continue;
        const long long dx = *c - x, d2 = dx * dx + dy2;
        if (best < 0 || d2 < best) best = d2;
      }
    };
    const int height = static_cast<int>(start_.size()) - 1;
    for (int dy = 0; dy < height; ++dy) {
      const long long dy2 = static_cast<long long>(dy) * dy;
      if (best >= 0 && dy2 >= best) break;  // every row left lies at least this far
      const bool up = y - dy >= 0, down = dy > 0 && y + dy < height;
      if (!up && !down) break;
      if (up) row(y - dy, dy2);
      if (down) row(y + dy, dy2);
    }
    return static_cast<double>(best);
  }

private:
  std::vector<std::uint32_t> start_;  // row y's seeds: xs_[start_[y], start_[y + 1]), ascending; H + 1 entries
  std::vector<int> xs_;
};

}  // namespace vcar
