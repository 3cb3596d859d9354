#pragma once
// RenderedLabels: which object each pixel of a render shows, read from the render itself (the
// honest oracle's ground truth, OracleMode::rendered in synth/oracle_segmenter.hpp).
//
// A frame draws a set D of Gaussians (the whole scene, or a subset such as G_coarse). At pixel p
// label l's weight is W_l(p) = sum of alpha_i(p) T_i(p) over the Gaussians i of D whose true
// object id (World::object_id) is l (conventions §3: the light that label puts into the pixel),
// and T(p) = 1 - alpha(p) is the transmittance left. The pixel shows label l when W_l(p) is the
// largest weight of all labels and larger than T(p): l dominates the pixel. Ties go to the
// smaller id. Where no label dominates (the background shows through, or the weight is split),
// the pixel shows nothing (-1), which is also the label of floaters (id -1).
//
// How: the weights come from any vcar::Renderer. Copies of the scene's geometry are prepared
// once, one per group of three labels (ids in ascending order), their colour one-hot: SH degree
// 0 with a DC term giving colour 1 in channel c for the Gaussians of the group's c-th label and
// 0 elsewhere (rgb = max(0, 0.5 + C0 f_dc)); rendered on black, channel c of a copy's render
// is W_l of that label, and its alpha is the frame's (the geometry is the scene's). A frame costs
// one render per group that holds a label of D. Memory: 14 floats per Gaussian and group.
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

class RenderedLabels {
public:
  explicit RenderedLabels(const World& w) {
    if (w.object_id.size() != w.scene.size()) throw Error("object_id and scene sizes differ", "world");
    labels_ = w.object_id;
    std::sort(labels_.begin(), labels_.end());
    labels_.erase(std::unique(labels_.begin(), labels_.end()), labels_.end());
    const std::size_t n = w.scene.size(), groups = (labels_.size() + 2) / 3;
    slot_.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      slot_[i] = static_cast<int>(std::lower_bound(labels_.begin(), labels_.end(), w.object_id[i]) - labels_.begin());
    constexpr float C0 = 0.28209479177387814f;
    constexpr float one = 0.5f / C0, zero = -1.f / C0;  // colours 1 and max(0, -0.5) = 0
    copies_.resize(groups);
    for (std::size_t g = 0; g < groups; ++g) {
      GaussianScene& c = copies_[g];
      c.mean = w.scene.mean;
      c.log_scale = w.scene.log_scale;
      c.rotation = w.scene.rotation;
      c.opacity_logit = w.scene.opacity_logit;
      c.sh_degree = 0;
      c.sh.assign(3 * n, zero);
      for (std::size_t i = 0; i < n; ++i)
        if (static_cast<std::size_t>(slot_[i]) / 3 == g) c.sh[3 * i + static_cast<std::size_t>(slot_[i]) % 3] = one;
    }
  }

  // The distinct object ids of the world, ascending (label k of the weights below).
  const std::vector<int>& labels() const noexcept { return labels_; }
  std::size_t scene_size() const noexcept { return slot_.size(); }
  std::size_t renders_per_frame() const noexcept { return copies_.size(); }  // at most

  // Per label (aligned with labels()) the weight image W_l, and the transmittance left T; a
  // label none of whose Gaussians is drawn has an empty image (weight 0 everywhere).
  struct Weights {
    std::vector<ImageF> weight;
    ImageF transmittance;
  };
  // `drawn`: the Gaussians the frame draws (null: the whole scene).
  template <Renderer R>
  Weights weights(const Camera& cam, const std::vector<Index>* drawn, R& renderer) const {
    Weights out;
    out.weight.resize(labels_.size());
    out.transmittance = ImageF(cam.width, cam.height, 1, 1.f);
    std::vector<char> present(labels_.size(), drawn == nullptr);
    if (drawn)
      for (Index i : *drawn) {
        if (i >= slot_.size()) throw Error("drawn Gaussian " + std::to_string(i) + " out of range", "RenderedLabels");
        present[static_cast<std::size_t>(slot_[i])] = 1;
      }
    for (std::size_t g = 0; g < copies_.size(); ++g) {
      bool any = false;
      for (std::size_t s = 3 * g; s < std::min(labels_.size(), 3 * g + 3); ++s) any = any || present[s];
      if (!any) continue;
      RenderRequest q;
      q.scene = &copies_[g];
      q.camera = &cam;
      q.subset = drawn;
      const RenderOutput r = renderer.render(q);
      const std::size_t P = r.alpha.data.size();
      for (std::size_t k = 0; k < P; ++k) out.transmittance.data[k] = 1.f - r.alpha.data[k];
      for (std::size_t s = 3 * g; s < std::min(labels_.size(), 3 * g + 3); ++s) {
        if (!present[s]) continue;
        ImageF& wl = out.weight[s];
        wl = ImageF(cam.width, cam.height, 1, 0.f);
        for (std::size_t k = 0; k < P; ++k) wl.data[k] = r.rgb.data[3 * k + (s - 3 * g)];
      }
    }
    return out;
  }

  // The label each pixel shows (see the top of this file); IdImage::depth stays empty.
  template <Renderer R>
  IdImage label_image(const Camera& cam, const std::vector<Index>* drawn, R& renderer) const {
    return dominant(weights(cam, drawn, renderer));
  }

  IdImage dominant(const Weights& w) const {
    IdImage img;
    img.width = w.transmittance.width;
    img.height = w.transmittance.height;
    img.id.assign(w.transmittance.data.size(), -1);
    std::vector<float> best = w.transmittance.data;  // a label must beat what is left
    for (std::size_t s = 0; s < labels_.size(); ++s) {
      const ImageF& wl = w.weight[s];
      if (wl.data.empty()) continue;
      for (std::size_t k = 0; k < best.size(); ++k)
        if (wl.data[k] > best[k]) { best[k] = wl.data[k]; img.id[k] = labels_[s]; }
    }
    return img;
  }

private:
  std::vector<int> labels_;
  std::vector<int> slot_;               // per Gaussian: its label's place in labels_
  std::vector<GaussianScene> copies_;   // one per group of three labels
};

}  // namespace vcar::synth
