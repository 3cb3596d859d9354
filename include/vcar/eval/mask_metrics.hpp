#pragma once
// Per (object, view) region metrics (conventions §6): IoU and pixel accuracy of a predicted mask
// against a ground-truth mask, and the predicted mask of a rendering (alpha > a).
#include <cstddef>
#include <string>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"

namespace vcar::eval {

// Alpha thresholds reported by the benchmarks: 0.5 (our default) and 0.1 (the paper's released
// evaluation), conventions §6.
inline constexpr float alpha_default = 0.5f;
inline constexpr float alpha_released = 0.1f;

// Predicted mask of a rendered alpha image: alpha > a.
inline Mask predicted_mask(const ImageF& alpha, float a = alpha_default) { return threshold(alpha, a); }

// Throws vcar::Error naming `where` when the two masks differ in size or are not 1-channel.
inline void check_same_size(const Mask& pred, const Mask& gt, const std::string& where) {
  if (pred.width != gt.width || pred.height != gt.height)
    throw Error("predicted mask is " + std::to_string(pred.width) + "x" + std::to_string(pred.height) +
                    ", ground truth is " + std::to_string(gt.width) + "x" + std::to_string(gt.height),
                where);
  if (pred.channels != 1 || gt.channels != 1) throw Error("masks must have one channel", where);
  if (pred.data.size() != pred.pixels() || gt.data.size() != gt.pixels())
    throw Error("mask data does not match its size", where);
}

// Pixel counts of the confusion matrix of a predicted vs a ground-truth mask.
struct Confusion {
  std::size_t tp = 0, fp = 0, fn = 0, tn = 0;
  std::size_t total() const noexcept { return tp + fp + fn + tn; }
};

inline Confusion confusion(const Mask& pred, const Mask& gt, const std::string& where = "mask") {
  check_same_size(pred, gt, where);
  Confusion c;
  for (std::size_t k = 0; k < gt.data.size(); ++k) {
    const bool p = pred.data[k] != 0, g = gt.data[k] != 0;
    c.tp += p && g; c.fp += p && !g; c.fn += !p && g; c.tn += !p && !g;
  }
  return c;
}

// |P n G| / |P u G|; both empty -> 1 (nothing to find, nothing found).
inline double iou(const Confusion& c) {
  const std::size_t uni = c.tp + c.fp + c.fn;
  return uni == 0 ? 1.0 : static_cast<double>(c.tp) / static_cast<double>(uni);
}
// (tp + tn) / pixels; an empty image scores 1.
inline double pixel_accuracy(const Confusion& c) {
  return c.total() == 0 ? 1.0 : static_cast<double>(c.tp + c.tn) / static_cast<double>(c.total());
}

inline double mask_iou(const Mask& pred, const Mask& gt, const std::string& where = "mask") {
  return iou(confusion(pred, gt, where));
}
inline double mask_accuracy(const Mask& pred, const Mask& gt, const std::string& where = "mask") {
  return pixel_accuracy(confusion(pred, gt, where));
}

}  // namespace vcar::eval
