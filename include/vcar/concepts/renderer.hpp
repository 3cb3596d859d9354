#pragma once
// The Renderer concept: how vcar asks a host application for images of a scene.
//
// A Renderer turns a RenderRequest into a RenderOutput:
//  - `scene`: the Gaussians (conventions §1); `camera`: the view (conventions §2).
//  - `subset`: when non-null, only these Gaussians are drawn (the others do not exist for this
//    render); null draws the whole scene. Indices are into `scene` and may come in any order.
//  - `log_scale`: when non-null, replaces the log-scales of the drawn Gaussians; column d has
//    one value per drawn Gaussian, aligned with `subset` (or with the scene when `subset` is
//    null). This is how refined scales (ABR) are rendered without copying the scene.
//  - `background`: the colour composited behind the Gaussians, RGB in [0, 1].
//  - `want_depth`: also return the expected depth sum z_i alpha_i T_i.
// The output images are width x height of the camera: `rgb` has 3 float channels, `alpha`
// (1 - final transmittance) and `depth` 1 each; `depth` stays empty unless asked for.
// The Renderer owns nothing that outlives the call; it may keep scratch buffers between calls.
// Rendering rules (tiles, culling, compositing) should match gsplat (conventions §3) so that
// masks of the rendered images line up with the projections the algorithms compute.
//
// A ContributionRenderer also accumulates, per Gaussian, over the pixels of one view:
//   weight[i]    += sum_p alpha_i(p) T_i(p)
//   weight_fg[i] += sum_p alpha_i(p) T_i(p) [mask(p) != 0]
// into vectors sized like the scene (the peers' methods, conventions §8, need these sums).
//
// Models: vcar::cpu::TiledRenderer (backends/cpu), or any host lambda through make_renderer:
//
//   auto r = vcar::make_renderer([&](const vcar::RenderRequest& q) {
//     vcar::RenderOutput out; /* call your CUDA splatter */ return out; });
//   static_assert(vcar::Renderer<decltype(r)>);
#include <concepts>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/image.hpp"

namespace vcar {

struct RenderRequest {
  const GaussianScene* scene = nullptr;
  const Camera* camera = nullptr;
  const std::vector<Index>* subset = nullptr;  // null: every Gaussian
  const LogScales* log_scale = nullptr;        // null: the scene's own log-scales
  Eigen::Vector3f background = Eigen::Vector3f::Zero();
  bool want_depth = false;
};

struct RenderOutput {
  ImageF rgb;    // 3 channels
  ImageF alpha;  // 1 channel, 1 - T_final
  ImageF depth;  // 1 channel, sum z alpha T (empty unless requested)
};

struct Contributions {
  std::vector<double> weight;     // sum alpha T
  std::vector<double> weight_fg;  // sum alpha T mask
  void reset(std::size_t n) { weight.assign(n, 0.0); weight_fg.assign(n, 0.0); }
};

template <class R>
concept Renderer = requires(R& r, const RenderRequest& q) {
  { r.render(q) } -> std::same_as<RenderOutput>;
};

template <class R>
concept ContributionRenderer =
    Renderer<R> && requires(R& r, const RenderRequest& q, const Mask& m, Contributions& acc) {
      { r.accumulate_contributions(q, m, acc) } -> std::same_as<void>;
    };

// Adapter from a callable RenderOutput(const RenderRequest&): no inheritance required.
template <class F>
struct LambdaRenderer {
  F fn;
  RenderOutput render(const RenderRequest& q) { return fn(q); }
};
template <class F>
LambdaRenderer<std::decay_t<F>> make_renderer(F&& f) { return {std::forward<F>(f)}; }

// Adapter from two callables (render, then accumulate) into a ContributionRenderer.
template <class F, class G>
struct LambdaContributionRenderer {
  F fn;
  G acc;
  RenderOutput render(const RenderRequest& q) { return fn(q); }
  void accumulate_contributions(const RenderRequest& q, const Mask& m, Contributions& c) { acc(q, m, c); }
};
template <class F, class G>
LambdaContributionRenderer<std::decay_t<F>, std::decay_t<G>> make_contribution_renderer(F&& f, G&& g) {
  return {std::forward<F>(f), std::forward<G>(g)};
}

}  // namespace vcar
