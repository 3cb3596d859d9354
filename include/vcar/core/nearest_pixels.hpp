#pragma once
// The pixels around a pixel, nearest first: the offsets (dx, dy) with dx^2 + dy^2 <= reach^2,
// in order of that squared distance. A measure that needs, at a few pixels (a mask's contour),
// the distance to the nearest pixel of some kind finds it by visiting them in this order, and
// stops at the first: exact, and no transform of the whole image, when the kind lies near.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

namespace vcar {

inline constexpr int contour_reach_px = 16;  // the reach of the robust vote's contour measures (Eq. R6a, R11b)

class NearestPixels {
public:
  explicit NearestPixels(int reach) : reach_(reach) {
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx)
        if (dx * dx + dy * dy <= reach * reach) offsets_.push_back({dx * dx + dy * dy, dy, dx});
    std::sort(offsets_.begin(), offsets_.end());
  }
  int reach() const noexcept { return reach_; }

  // f(q, d2) for the pixels q (row-major) of a W x H image within reach of (x, y), nearest
  // first (squared distance d2, ties in a fixed order), until f returns false. Returns false
  // when f stopped the visit.
  template <class F>
  bool visit(int x, int y, int W, int H, F&& f) const {
    for (const auto& [d2, dy, dx] : offsets_) {
      const int u = x + dx, v = y + dy;
      if (u < 0 || v < 0 || u >= W || v >= H) continue;
      if (!f(static_cast<std::size_t>(v) * static_cast<std::size_t>(W) + static_cast<std::size_t>(u), d2)) return false;
    }
    return true;
  }

private:
  int reach_;
  std::vector<std::tuple<int, int, int>> offsets_;  // (d2, dy, dx), ascending
};

// The offsets of one reach, built on first use and kept (thread-safe).
inline const NearestPixels& nearest_pixels(int reach) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<NearestPixels>> built;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& p = built[reach];
  if (!p) p = std::make_unique<NearestPixels>(reach);
  return *p;
}

// The squared distance from (x, y) to the nearest pixel q with kind(q), or -1 when none lies
// within the reach of `near`.
template <class Kind>
int nearest_squared_distance(const NearestPixels& near, int x, int y, int W, int H, Kind&& kind) {
  int found = -1;
  near.visit(x, y, W, H, [&](std::size_t q, int d2) { return kind(q) ? (found = d2, false) : true; });
  return found;
}

}  // namespace vcar
