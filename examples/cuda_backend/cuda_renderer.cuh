#pragma once
// vcar::cuda::Renderer: a CUDA splatter that satisfies vcar::Renderer and
// vcar::ContributionRenderer (concepts/renderer.hpp), following gsplat's rules (conventions §3)
// like the CPU backend. This header is host code: it gathers the drawn Gaussians (the request's
// subset, with its log-scale override) and hands them to the kernels in splat_kernels.cu through
// the plain interface of splat_kernels.h, so it compiles with the host compiler (C++20) and the
// vcar headers never go through nvcc.
//
// Per call: upload the drawn Gaussians (11 floats each, plus SH colour when rendering), project,
// bin into 16 x 16 tiles sorted by (tile, depth), composite, download rgb / alpha (/ depth).
// The scene is not cached on the device: a host that renders one scene many times and owns its
// device copy would skip the gather and the upload (the kernels take plain device columns).
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "splat_kernels.h"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/projection.hpp"

namespace vcar::cuda {

class Renderer {
public:
  Renderer() = default;
  explicit Renderer(ProjectionParams p) : projection_(p) {}

  ProjectionParams& projection() { return projection_; }
  // Milliseconds of the last call's stages (CUDA events).
  const detail::FrameTimings& last_timings() const { return splatter_.last_timings(); }
  static std::string device_name() { return detail::Splatter::device_name(); }

  RenderOutput render(const RenderRequest& q) {
    const Camera& cam = check(q);
    gather(q, /*colour=*/true);
    RenderOutput out;
    out.rgb = ImageF(cam.width, cam.height, 3);
    out.alpha = ImageF(cam.width, cam.height, 1);
    if (q.want_depth) out.depth = ImageF(cam.width, cam.height, 1);
    const float bg[3] = {q.background[0], q.background[1], q.background[2]};
    splatter_.render(drawn(q), camera(cam), constants(), bg, out.rgb.data.data(), out.alpha.data.data(),
                     q.want_depth ? out.depth.data.data() : nullptr);
    return out;
  }

  // weight[i] += sum_p alpha_i T_i, weight_fg[i] += sum_p alpha_i T_i [mask != 0], i indexing
  // the scene; empty vectors are sized to the scene first.
  void accumulate_contributions(const RenderRequest& q, const Mask& mask, Contributions& acc) {
    const Camera& cam = check(q);
    if (mask.width != cam.width || mask.height != cam.height || mask.channels != 1)
      throw Error("mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) + ", view is " +
                  std::to_string(cam.width) + "x" + std::to_string(cam.height), "view '" + cam.name + "'");
    const std::size_t n = q.scene->size();
    if (acc.weight.empty() && acc.weight_fg.empty()) acc.reset(n);
    if (acc.weight.size() != n || acc.weight_fg.size() != n)
      throw Error("contribution vectors must be sized like the scene", "Contributions");
    gather(q, /*colour=*/false);
    const std::size_t m = count(q);
    w_.assign(m, 0.0);
    wfg_.assign(m, 0.0);
    splatter_.contributions(drawn(q), camera(cam), constants(), mask.data.data(), w_.data(), wfg_.data());
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t i = q.subset ? (*q.subset)[k] : k;
      acc.weight[i] += w_[k];
      acc.weight_fg[i] += wfg_[k];
    }
  }

private:
  static std::size_t count(const RenderRequest& q) { return q.subset ? q.subset->size() : q.scene->size(); }

  // Boundary checks, as the CPU backend: scene and camera given and valid, indices in range,
  // the log-scale override aligned with the drawn Gaussians.
  static const Camera& check(const RenderRequest& q) {
    if (!q.scene || !q.camera) throw Error("request needs a scene and a camera", "RenderRequest");
    q.camera->validate();
    const GaussianScene& sc = *q.scene;
    const std::size_t n = sc.size();
    for (int d = 0; d < 3; ++d)
      if (sc.mean[d].size() != n || sc.log_scale[d].size() != n) throw Error("scene columns disagree in size", "scene");
    for (int c = 0; c < 4; ++c)
      if (sc.rotation[c].size() != n) throw Error("scene columns disagree in size", "scene");
    if (sc.sh_degree < 0 || sc.sh_degree > 3 || sc.sh.size() != n * static_cast<std::size_t>(sc.sh_coeffs()) * 3)
      throw Error("SH degree must be 0..3 with (degree+1)^2 x 3 coefficients per Gaussian", "scene");
    if (q.subset)
      for (Index i : *q.subset)
        if (i >= n) throw Error("subset index " + std::to_string(i) + " out of range (scene has " + std::to_string(n) + ")",
                                "RenderRequest::subset");
    if (count(q) >= (std::size_t{1} << 32)) throw Error("more than 2^32 drawn Gaussians", "RenderRequest");
    if (q.log_scale)
      for (int d = 0; d < 3; ++d)
        if ((*q.log_scale)[d].size() != count(q))
          throw Error("log-scale column " + std::to_string(d) + " has " + std::to_string((*q.log_scale)[d].size()) +
                      " values, expected " + std::to_string(count(q)), "RenderRequest::log_scale");
    return *q.camera;
  }

  // The drawn Gaussians in request order, column-major (splat_kernels.h), opacity = sigmoid(o).
  void gather(const RenderRequest& q, bool colour) {
    const GaussianScene& sc = *q.scene;
    const std::size_t n = count(q), B3 = static_cast<std::size_t>(sc.sh_coeffs()) * 3;
    columns_.resize(n * detail::gaussian_columns);
    float* c = columns_.data();
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = q.subset ? (*q.subset)[k] : k;
      for (int d = 0; d < 3; ++d) {
        c[d * n + k] = sc.mean[d][i];
        c[(3 + d) * n + k] = q.log_scale ? (*q.log_scale)[d][k] : sc.log_scale[d][i];
      }
      for (int r = 0; r < 4; ++r) c[(6 + r) * n + k] = sc.rotation[r][i];
      c[10 * n + k] = sc.opacity(i);
    }
    if (!colour) return;
    if (!q.subset) return;  // the scene's own SH array is already in request order
    sh_.resize(n * B3);
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t b = 0; b < B3; ++b) sh_[k * B3 + b] = sc.sh[(*q.subset)[k] * B3 + b];
  }

  detail::HostGaussians drawn(const RenderRequest& q) const {
    return {count(q), q.scene->sh_degree, columns_.data(), q.subset ? sh_.data() : q.scene->sh.data()};
  }

  static detail::CameraParams camera(const Camera& cam) {
    detail::CameraParams c;
    c.width = cam.width; c.height = cam.height;
    c.fx = cam.fx; c.fy = cam.fy; c.cx = cam.cx; c.cy = cam.cy;
    const Eigen::Vector3f eye = cam.position();
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) c.R[3 * r + k] = cam.R_w(r, k);
      c.t[r] = cam.t_w[r];
      c.eye[r] = eye[r];
    }
    return c;
  }

  detail::ProjectionConstants constants() const {
    return {projection_.near_plane, projection_.far_plane, projection_.eps2d, projection_.frustum_margin,
            projection_.alpha_min, projection_.extend_max};
  }

  ProjectionParams projection_{};
  detail::Splatter splatter_;
  std::vector<float> columns_, sh_;  // host staging, reused between calls
  std::vector<double> w_, wfg_;
};

static_assert(vcar::Renderer<Renderer>);
static_assert(vcar::ContributionRenderer<Renderer>);

}  // namespace vcar::cuda
