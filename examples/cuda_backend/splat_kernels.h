#pragma once
// The thin interface between the host code (C++20, vcar headers, compiled by the host
// compiler) and the CUDA kernels (splat_kernels.cu, compiled by nvcc). Plain types only: no
// Eigen, no CUDA types, so either compiler reads it.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace vcar::cuda::detail {

// A pinhole camera (conventions §2), world-to-camera rotation row-major.
struct CameraParams {
  int width = 0, height = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0;
  float R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // R_w, row-major
  float t[3] = {0, 0, 0};                    // t_w
  float eye[3] = {0, 0, 0};                  // camera centre in world (SH view direction)
};

// gsplat's projection constants (vcar::ProjectionParams, conventions §3).
struct ProjectionConstants {
  float near_plane = 0.01f, far_plane = 1e10f, eps2d = 0.3f, frustum_margin = 0.3f;
  float alpha_min = 1.f / 255.f, extend_max = 3.33f;
};

// The drawn Gaussians, gathered in request order (k = 0 .. n-1) on the host, column-major:
// columns[c * n + k] for c = mean x, y, z, log_s 0, 1, 2, q w, x, y, z, opacity (sigmoid'ed);
// sh[(k * B + b) * 3 + ch], B = (sh_degree + 1)^2 (empty when only contributions are wanted).
inline constexpr int gaussian_columns = 11;
struct HostGaussians {
  std::size_t n = 0;
  int sh_degree = 0;
  const float* columns = nullptr;
  const float* sh = nullptr;
};

// Milliseconds of the last call, measured with CUDA events on the stream.
struct FrameTimings {
  float upload_ms = 0, project_ms = 0, sort_ms = 0, composite_ms = 0, download_ms = 0;
  std::size_t entries = 0;  // (tile, splat) pairs composited
};

// Owns the device buffers (grown, never shrunk) and one CUDA stream. One call at a time.
// Throws vcar::Error naming the failing CUDA call.
class Splatter {
public:
  Splatter();
  ~Splatter();
  Splatter(const Splatter&) = delete;
  Splatter& operator=(const Splatter&) = delete;

  // rgb: 3 floats per pixel (interleaved), alpha and depth (may be null): 1 float per pixel.
  void render(const HostGaussians& g, const CameraParams& cam, const ProjectionConstants& pc,
              const float background[3], float* rgb, float* alpha, float* depth);
  // weight[k] += sum_p alpha_k T_k, weight_fg[k] += sum_p alpha_k T_k [mask != 0], k = drawn
  // index; mask is width x height bytes. Entry partial sums are reduced in (tile, depth) order:
  // the result does not depend on scheduling.
  void contributions(const HostGaussians& g, const CameraParams& cam, const ProjectionConstants& pc,
                     const std::uint8_t* mask, double* weight, double* weight_fg);

  const FrameTimings& last_timings() const;
  static std::string device_name();  // "" when no device can be used

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vcar::cuda::detail
