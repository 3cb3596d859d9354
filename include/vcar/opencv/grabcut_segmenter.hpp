#pragma once
// GrabCutSegmenter: OpenCV's GrabCut (Rother, Kolmogorov, Blake 2004: colour GMMs of foreground
// and background, refined by graph cuts) as a vcar::Segmenter. Target vcar::opencv (OpenCV core
// and imgproc); nothing of vcar::vcar includes it.
//
// GrabCut needs a box on every frame; the prompt is given on the reference view only, so the
// segmenter holds the prompt lifted to 3D (vcar::lift_prompt, algo/prompt_lift.hpp) and boxes
// it in each frame it is asked about (the training views, and the sampled views of the fine
// round, which render only G_coarse: the same rule serves both rounds). Per frame k:
//  - the box: the prompt's own box on frame 0 (the reference view) when the prompt has one;
//    elsewhere LiftedPrompt::box_for(camera, margin, outliers), with point_margin instead of
//    margin when the prompt has no box (a point prompt lifts part of the object). No box (the
//    object behind the camera or out of view), a box under min_box_px on a side, or one that
//    leaves less than min_background of the frame outside it (nothing to learn the background
//    from): "no mask", sink(k, nullptr), and the frame is never rendered;
//  - the image: frames.image(k) (8-bit RGB), as a BGR cv::Mat, cropped around the box when
//    `context` >= 0 (the rest of the frame: background);
//  - cv::grabCut with GC_INIT_WITH_RECT, `iterations` rounds; on frame 0, prompt points seed
//    discs of seed_radius * (image diagonal): positive GC_FGD, negative GC_BGD (the box's
//    initial labels otherwise: GC_BGD outside, GC_PR_FGD inside; GC_INIT_WITH_MASK then);
//  - the mask: 255 where GrabCut says GC_FGD or GC_PR_FGD (the labels with bit 0 set), to the
//    sink; "no mask" when that is under min_foreground of the box's area (GrabCut found nothing
//    to separate: the box lies inside the object, or the object is hidden: no evidence, rather
//    than an empty mask that would vote against the object).
// Deterministic: OpenCV's random generator (its k-means initialisation of the GMMs) is reset to
// `seed` before each frame. Cost: about one GrabCut per frame (docs/concepts.md has the timing).
// Limits: GrabCut separates colours; an object coloured like its surroundings, or a box that
// covers only part of the object (a point prompt's box: algo/prompt_lift.hpp), gives poor masks.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "vcar/algo/prompt_lift.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"

namespace vcar::opencv {

struct GrabCutParams {
  int iterations = 5;            // cv::grabCut iterations per frame
  float margin = 0.1f;           // box padding on frames other than the reference, of the box's size (box_in)
  float point_margin = 0.5f;     // the same when the prompt has no box (points lift part of the object)
  float outliers = 0.02f;        // share of the lifted points' projections dropped as extremes (box_in)
  float seed_radius = 0.01f;     // radius of the discs prompt points seed on frame 0, of the image diagonal
  int min_box_px = 4;            // a box thinner than this (pixels) gives no mask
  float min_background = 0.01f;  // a box leaving less of the frame than this outside gives no mask
  float min_foreground = 0.05f;  // a mask with less foreground than this share of its box is no mask
  std::uint64_t seed = 0x6C8E9CF5u;  // OpenCV's RNG state before each frame
  // GrabCut sees the frame cropped to the box padded by ceil(context * its width) columns and
  // ceil(context * its height) rows each side (clipped; the rest of the frame is background);
  // negative: the whole frame. Its cost grows with the pixels it models.
  float context = -1.f;

  void validate() const {
    if (iterations < 1) throw Error("must be >= 1", "GrabCutParams.iterations");
    if (!(margin >= 0.f)) throw Error("must be >= 0", "GrabCutParams.margin");
    if (!(point_margin >= 0.f)) throw Error("must be >= 0", "GrabCutParams.point_margin");
    if (!(min_foreground >= 0.f && min_foreground < 1.f)) throw Error("must be in [0, 1)", "GrabCutParams.min_foreground");
    if (!(outliers >= 0.f && outliers < 1.f)) throw Error("must be in [0, 1)", "GrabCutParams.outliers");
    if (!(seed_radius >= 0.f && seed_radius <= 1.f)) throw Error("must be in [0, 1]", "GrabCutParams.seed_radius");
    if (min_box_px < 1) throw Error("must be >= 1", "GrabCutParams.min_box_px");
    if (!(min_background >= 0.f && min_background < 1.f)) throw Error("must be in [0, 1)", "GrabCutParams.min_background");
    if (std::isnan(context)) throw Error("must be a number", "GrabCutParams.context");
  }
};

// A point that seeds GrabCut's labels: pixel (u, v), foreground or background.
struct GrabCutSeed {
  Eigen::Vector2f pixel;
  bool foreground = true;
};

// GrabCut on one image: the foreground mask inside `box` (x0, y0, x1, y1; pixels), or nullopt
// when the box is degenerate for GrabCut (see min_box_px, min_background) or the mask has less
// foreground than min_foreground of the box. `seeds` are discs of
// `seed_radius_px`. Throws vcar::Error naming `where` for an image that is not 8-bit RGB and
// when OpenCV fails.
inline std::optional<Mask> grabcut(const ImageRGB8& image, const Eigen::Vector4f& box, const GrabCutParams& params = {},
                                   std::span<const GrabCutSeed> seeds = {}, float seed_radius_px = 0.f,
                                   const std::string& where = "GrabCut") {
  if (image.channels != 3 || image.width <= 0 || image.height <= 0 || image.data.size() != image.pixels() * 3)
    throw Error("the image must be 8-bit RGB with 3 channels", where);
  if (!box.allFinite()) return std::nullopt;
  const int W = image.width, H = image.height;
  // The pixels the box touches: columns floor(x0) .. ceil(x1) - 1, clipped to the image.
  const int x0 = std::clamp(static_cast<int>(std::floor(box[0])), 0, W), y0 = std::clamp(static_cast<int>(std::floor(box[1])), 0, H);
  const int x1 = std::clamp(static_cast<int>(std::ceil(box[2])), 0, W), y1 = std::clamp(static_cast<int>(std::ceil(box[3])), 0, H);
  if (x1 - x0 < params.min_box_px || y1 - y0 < params.min_box_px) return std::nullopt;
  const double outside = 1.0 - static_cast<double>(x1 - x0) * (y1 - y0) / (static_cast<double>(W) * H);
  if (outside < params.min_background || (x1 - x0 == W && y1 - y0 == H)) return std::nullopt;
  const cv::Rect rect(x0, y0, x1 - x0, y1 - y0);
  // The crop GrabCut sees (params.context), in frame pixels.
  cv::Rect crop(0, 0, W, H);
  if (params.context >= 0.f) {
    const int px = static_cast<int>(std::ceil(static_cast<double>(params.context) * (x1 - x0)));
    const int py = static_cast<int>(std::ceil(static_cast<double>(params.context) * (y1 - y0)));
    const int c0 = std::max(0, x0 - px), r0 = std::max(0, y0 - py);
    crop = cv::Rect(c0, r0, std::min(W, x1 + px) - c0, std::min(H, y1 + py) - r0);
    if (crop == rect) crop = cv::Rect(0, 0, W, H);  // no background in the crop: the whole frame
  }
  const cv::Rect in_crop(rect.x - crop.x, rect.y - crop.y, rect.width, rect.height);

  try {
    const cv::Mat rgb(H, W, CV_8UC3, const_cast<std::uint8_t*>(image.data.data()));
    cv::Mat bgr;
    cv::cvtColor(rgb(crop), bgr, cv::COLOR_RGB2BGR);
    cv::Mat labels(crop.height, crop.width, CV_8UC1, cv::Scalar(cv::GC_BGD));
    cv::Mat bgd_model, fgd_model;
    cv::theRNG().state = params.seed;  // k-means initialisation of the GMMs: the same per frame
    if (seeds.empty()) {
      cv::grabCut(bgr, labels, in_crop, bgd_model, fgd_model, params.iterations, cv::GC_INIT_WITH_RECT);
    } else {
      labels(in_crop).setTo(cv::Scalar(cv::GC_PR_FGD));  // what GC_INIT_WITH_RECT would set
      const int r = std::max(0, static_cast<int>(std::lround(seed_radius_px)));
      for (const GrabCutSeed& s : seeds)
        cv::circle(labels, cv::Point(static_cast<int>(s.pixel.x()) - crop.x, static_cast<int>(s.pixel.y()) - crop.y), r,
                   cv::Scalar(s.foreground ? cv::GC_FGD : cv::GC_BGD), cv::FILLED);
      cv::grabCut(bgr, labels, in_crop, bgd_model, fgd_model, params.iterations, cv::GC_INIT_WITH_MASK);
    }
    Mask m(W, H, 1);
    std::size_t foreground = 0;
    for (int i = 0; i < crop.height; ++i) {
      const std::uint8_t* row = labels.ptr<std::uint8_t>(i);
      for (int j = 0; j < crop.width; ++j) {
        const bool fg = (row[j] & 1) != 0;  // GC_FGD = 1, GC_PR_FGD = 3
        m.data[static_cast<std::size_t>(i + crop.y) * W + j + crop.x] = fg ? 255 : 0;
        foreground += fg;
      }
    }
    if (static_cast<double>(foreground) < params.min_foreground * rect.area()) return std::nullopt;
    return m;
  } catch (const cv::Exception& e) {
    throw Error(std::string("OpenCV failed: ") + e.what(), where);
  }
}

class GrabCutSegmenter {
public:
  explicit GrabCutSegmenter(LiftedPrompt lifted, GrabCutParams params = {})
      : lifted_(std::move(lifted)), params_(params) {
    params_.validate();
    if (lifted_.empty()) throw Error("the lifted prompt holds no point", "GrabCutSegmenter");
  }

  const LiftedPrompt& lifted() const noexcept { return lifted_; }
  const GrabCutParams& params() const noexcept { return params_; }

  // The box of frame k (see the top of the file), before GrabCut's own checks.
  std::optional<Eigen::Vector4f> box(const FrameSequence& frames, std::size_t k, const Prompt& prompt) const {
    if (k == 0 && prompt.box) return prompt.box;
    return lifted_.box_for(frames.cameras[k], prompt.box ? params_.margin : params_.point_margin, params_.outliers);
  }

  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    std::vector<GrabCutSeed> seeds;
    for (std::size_t p = 0; p < prompt.points.size(); ++p)
      seeds.push_back({prompt.points[p], p >= prompt.point_labels.size() || prompt.point_labels[p] != 0});
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const Camera& cam = frames.cameras[k];
      const std::optional<Eigen::Vector4f> b = box(frames, k, prompt);
      if (!b) {
        sink(k, nullptr);
        continue;
      }
      const std::string where = "GrabCut, frame " + std::to_string(k) + " (view '" + cam.name + "')";
      const ImageRGB8 image = frames.image(k);
      if (image.width != cam.width || image.height != cam.height)
        throw Error("the frame's image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                        ", its camera " + std::to_string(cam.width) + "x" + std::to_string(cam.height), where);
      const float radius = params_.seed_radius * std::hypot(static_cast<float>(cam.width), static_cast<float>(cam.height));
      const bool seeded = k == 0 && params_.seed_radius > 0.f && !seeds.empty();
      const std::optional<Mask> m =
          grabcut(image, *b, params_, seeded ? std::span<const GrabCutSeed>(seeds) : std::span<const GrabCutSeed>{},
                  radius, where);
      sink(k, m ? &*m : nullptr);
    }
  }

private:
  LiftedPrompt lifted_;
  GrabCutParams params_;
};

static_assert(Segmenter<GrabCutSegmenter>);

}  // namespace vcar::opencv
