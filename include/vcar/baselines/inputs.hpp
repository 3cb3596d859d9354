#pragma once
// What every peer method (conventions §8) consumes and returns. The masks are the same per-view
// masks VCAR votes with, handed over on demand so a method never needs all of them at once.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar::baselines {

// mask(j): the mask of view j, or nullptr for "no mask" (no evidence, conventions §4). The
// pointer must stay valid until the next call. Masks collected from a Segmenter with
// vcar::segment_all plug in through masks_from.
using MaskProvider = std::function<const Mask*(std::size_t view)>;

inline MaskProvider masks_from(const std::vector<std::optional<Mask>>& masks) {
  return [&masks](std::size_t j) -> const Mask* { return j < masks.size() && masks[j] ? &*masks[j] : nullptr; };
}

// The mask of view j checked against its camera: throws vcar::Error naming the view when the
// size or channel count is wrong (a mask of another size is an error, not a resize).
inline const Mask* checked_mask(const MaskProvider& masks, std::span<const Camera> cameras, std::size_t j) {
  const Mask* m = masks(j);
  if (!m) return nullptr;
  const Camera& c = cameras[j];
  if (m->width != c.width || m->height != c.height || m->channels != 1 || m->data.size() != m->pixels())
    throw Error("mask is " + std::to_string(m->width) + "x" + std::to_string(m->height) + "x" +
                    std::to_string(m->channels) + ", view is " + std::to_string(c.width) + "x" +
                    std::to_string(c.height) + "x1",
                "view '" + c.name + "' (" + std::to_string(j) + ")");
  return m;
}

// A peer method's answer: the selected Gaussians (ascending) and one score per scene Gaussian
// (the statistic each method thresholds; its meaning is documented per method).
struct Result {
  std::vector<Index> selected;
  std::vector<float> score;
};

// Ascending indices i with keep(i).
template <class F>
std::vector<Index> select_where(std::size_t n, F&& keep) {
  std::vector<Index> out;
  for (std::size_t i = 0; i < n; ++i)
    if (keep(i)) out.push_back(static_cast<Index>(i));
  return out;
}

// Tri-valued label of a point in one view (Eq. 1-2): -1 invisible (behind the camera, outside
// the image, or the view has no mask), else the mask at the pixel containing the projection.
inline int point_label(const Camera& cam, const Mask* mask, const Eigen::Vector3f& p) {
  if (!mask) return -1;
  const Eigen::Vector3f t = cam.to_camera(p);
  if (!(t.z() > 0.f)) return -1;  // Eq. 1
  const float u = cam.fx * t.x() / t.z() + cam.cx, v = cam.fy * t.y() / t.z() + cam.cy;
  if (!inside_image(u, v, cam.width, cam.height)) return -1;
  return mask_at(*mask, u, v) ? 1 : 0;  // Eq. 2
}

// Degree-0 colour of Gaussian i, rgb = max(0, 0.5 + C0 f_dc) (conventions §3).
inline Eigen::Vector3f dc_colour(const GaussianScene& s, std::size_t i) {
  constexpr float C0 = 0.28209479177387814f;
  const std::size_t base = i * static_cast<std::size_t>(s.sh_coeffs()) * 3;
  Eigen::Vector3f c;
  for (int k = 0; k < 3; ++k) c[k] = std::max(0.f, 0.5f + C0 * s.sh[base + k]);
  return c;
}

}  // namespace vcar::baselines
