// CUDA kernels of the example backend: gsplat's forward pass with vcar's rules (conventions §3).
//   project   one thread per drawn Gaussian: B.6-B.7 projection, cull, extent, SH colour
//   duplicate one (tile, depth) key per touched tile, offsets from an exclusive scan
//   sort      cub radix sort of the 64-bit keys (stable: equal depths keep the drawn order)
//   ranges    first / last entry of each tile
//   composite one 16 x 16 block per tile, one thread per pixel, splats staged in shared memory
// Only vcar/core/error.hpp (standard headers only) is included from the library, so nvcc never
// sees Eigen or xsimd.
#include <cuda_runtime.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <cstdint>
#include <string>
#include <vector>

#include "splat_kernels.h"
#include "vcar/core/error.hpp"

namespace vcar::cuda::detail {
namespace {

constexpr int tile_size = 16;  // pixels per tile side (gsplat)
constexpr int block_pixels = tile_size * tile_size;
constexpr float alpha_max = 0.999f, alpha_skip = 1.f / 255.f, T_stop = 1e-4f;

void check(cudaError_t e, const char* call) {
  if (e != cudaSuccess) throw Error(std::string(call) + ": " + cudaGetErrorString(e), "cuda renderer");
}
#define VCAR_CUDA(call) check((call), #call)

// Grow-only device array.
template <class T>
struct DeviceBuffer {
  T* p = nullptr;
  std::size_t cap = 0;
  ~DeviceBuffer() { if (p) cudaFree(p); }
  T* get(std::size_t n) {
    if (n > cap) {
      if (p) VCAR_CUDA(cudaFree(p));
      p = nullptr;
      cap = 0;
      VCAR_CUDA(cudaMalloc(&p, (n > 0 ? n : 1) * sizeof(T)));
      cap = n;
    }
    return p;
  }
};

// What compositing reads of one projected Gaussian.
struct Splat {
  float mx, my;      // projected mean (px)
  float ca, cb, cc;  // conic, Sigma2D^-1 = [[ca, cb], [cb, cc]]
  float opacity, depth;
  float r, g, b;
};

// rgb = max(0, 0.5 + SH(dir)) with the basis and signs of the reference 3DGS code.
__device__ void sh_colour(int degree, const float* c, float x, float y, float z, float* rgb) {
  const float n = sqrtf(x * x + y * y + z * z);
  if (n > 0.f) { x /= n; y /= n; z /= n; } else { x = y = z = 0.f; }
  float Y[16];
  Y[0] = 0.28209479177387814f;
  if (degree >= 1) {
    const float C1 = 0.4886025119029199f;
    Y[1] = -C1 * y; Y[2] = C1 * z; Y[3] = -C1 * x;
  }
  if (degree >= 2) {
    const float xx = x * x, yy = y * y, zz = z * z;
    Y[4] = 1.0925484305920792f * x * y;
    Y[5] = -1.0925484305920792f * y * z;
    Y[6] = 0.31539156525252005f * (2.f * zz - xx - yy);
    Y[7] = -1.0925484305920792f * x * z;
    Y[8] = 0.5462742152960396f * (xx - yy);
    if (degree >= 3) {
      Y[9] = -0.5900435899266435f * y * (3.f * xx - yy);
      Y[10] = 2.890611442640554f * x * y * z;
      Y[11] = -0.4570457994644658f * y * (4.f * zz - xx - yy);
      Y[12] = 0.3731763325901154f * z * (2.f * zz - 3.f * xx - 3.f * yy);
      Y[13] = -0.4570457994644658f * x * (4.f * zz - xx - yy);
      Y[14] = 1.445305721320277f * z * (xx - yy);
      Y[15] = -0.5900435899266435f * x * (xx - 3.f * yy);
    }
  }
  const int B = (degree + 1) * (degree + 1);
  float acc[3] = {0.f, 0.f, 0.f};
  for (int k = 0; k < B; ++k)
    for (int ch = 0; ch < 3; ++ch) acc[ch] += Y[k] * c[k * 3 + ch];
  for (int ch = 0; ch < 3; ++ch) rgb[ch] = fmaxf(0.f, 0.5f + acc[ch]);
}

// Projection of Gaussian k (vcar/core/projection.hpp, B.6-B.7): near plane, clamped Jacobian,
// Sigma2D = sum_d s_d^2 q_d q_d^T + eps2d I, opacity-aware extent, tile rectangle.
__global__ void project_kernel(std::size_t n, const float* __restrict__ col, const float* __restrict__ sh,
                               int sh_degree, CameraParams cam, ProjectionConstants pc, int tiles_x,
                               int tiles_y, bool colour, Splat* __restrict__ out,
                               std::uint64_t* __restrict__ touched, int4* __restrict__ rect) {
  const std::size_t k = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x;
  if (k >= n) return;
  touched[k] = 0;
  const float mu[3] = {col[k], col[n + k], col[2 * n + k]};
  const float s[3] = {expf(col[3 * n + k]), expf(col[4 * n + k]), expf(col[5 * n + k])};
  float w = col[6 * n + k], x = col[7 * n + k], y = col[8 * n + k], z = col[9 * n + k];
  const float opacity = col[10 * n + k];
  const float qn = sqrtf(w * w + x * x + y * y + z * z);
  w /= qn; x /= qn; y /= qn; z /= qn;
  const float R[9] = {1.f - 2.f * (y * y + z * z), 2.f * (x * y - w * z), 2.f * (x * z + w * y),
                      2.f * (x * y + w * z), 1.f - 2.f * (x * x + z * z), 2.f * (y * z - w * x),
                      2.f * (x * z - w * y), 2.f * (y * z + w * x), 1.f - 2.f * (x * x + y * y)};
  float t[3];
  for (int r = 0; r < 3; ++r) t[r] = cam.R[3 * r] * mu[0] + cam.R[3 * r + 1] * mu[1] + cam.R[3 * r + 2] * mu[2] + cam.t[r];
  if (!(t[2] >= pc.near_plane && t[2] <= pc.far_plane)) return;
  const float mx = cam.fx * t[0] / t[2] + cam.cx, my = cam.fy * t[1] / t[2] + cam.cy;
  // Eq. 10 / B.7: Jacobian at the mean, tx/z and ty/z clamped to the widened frustum.
  const float Wf = static_cast<float>(cam.width), Hf = static_cast<float>(cam.height);
  const float tan_x = 0.5f * Wf / cam.fx, tan_y = 0.5f * Hf / cam.fy;
  const float lim_x_pos = (Wf - cam.cx) / cam.fx + pc.frustum_margin * tan_x;
  const float lim_x_neg = cam.cx / cam.fx + pc.frustum_margin * tan_x;
  const float lim_y_pos = (Hf - cam.cy) / cam.fy + pc.frustum_margin * tan_y;
  const float lim_y_neg = cam.cy / cam.fy + pc.frustum_margin * tan_y;
  const float rz = 1.f / t[2], rz2 = rz * rz;
  const float tx = t[2] * fminf(lim_x_pos, fmaxf(-lim_x_neg, t[0] * rz));
  const float ty = t[2] * fminf(lim_y_pos, fmaxf(-lim_y_neg, t[1] * rz));
  const float J[6] = {cam.fx * rz, 0.f, -cam.fx * tx * rz2, 0.f, cam.fy * rz, -cam.fy * ty * rz2};
  float M[6];  // M = J R_w (2 x 3)
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c)
      M[3 * r + c] = J[3 * r] * cam.R[c] + J[3 * r + 1] * cam.R[3 + c] + J[3 * r + 2] * cam.R[6 + c];
  float S00 = 0.f, S01 = 0.f, S11 = 0.f;
  for (int d = 0; d < 3; ++d) {  // q_d = M r_d; Sigma2D += s_d^2 q_d q_d^T (Eq. 10)
    const float q0 = M[0] * R[d] + M[1] * R[3 + d] + M[2] * R[6 + d];
    const float q1 = M[3] * R[d] + M[4] * R[3 + d] + M[5] * R[6 + d];
    const float ss = s[d] * s[d];
    S00 += ss * q0 * q0;
    S01 += ss * q0 * q1;
    S11 += ss * q1 * q1;
  }
  S00 += pc.eps2d;
  S11 += pc.eps2d;
  const float det = S00 * S11 - S01 * S01;
  if (!(det > 0.f) || !(opacity >= pc.alpha_min)) return;
  const float extend = fminf(pc.extend_max, sqrtf(2.f * logf(opacity / pc.alpha_min)));
  const float rx = ceilf(extend * sqrtf(S00)), ry = ceilf(extend * sqrtf(S11));
  const bool on_screen = (rx > 0.f || ry > 0.f) && mx + rx > 0.f && mx - rx < Wf && my + ry > 0.f && my - ry < Hf;
  if (!on_screen) return;
  const float ts = static_cast<float>(tile_size);
  const int tx0 = static_cast<int>(fminf(fmaxf(floorf((mx - rx) / ts), 0.f), static_cast<float>(tiles_x)));
  const int tx1 = static_cast<int>(fminf(fmaxf(ceilf((mx + rx) / ts), 0.f), static_cast<float>(tiles_x)));
  const int ty0 = static_cast<int>(fminf(fmaxf(floorf((my - ry) / ts), 0.f), static_cast<float>(tiles_y)));
  const int ty1 = static_cast<int>(fminf(fmaxf(ceilf((my + ry) / ts), 0.f), static_cast<float>(tiles_y)));
  if (tx0 >= tx1 || ty0 >= ty1) return;
  Splat sp{mx, my, S11 / det, -S01 / det, S00 / det, opacity, t[2], 0.f, 0.f, 0.f};
  if (colour) {
    float rgb[3];
    const int B3 = (sh_degree + 1) * (sh_degree + 1) * 3;
    sh_colour(sh_degree, sh + k * B3, mu[0] - cam.eye[0], mu[1] - cam.eye[1], mu[2] - cam.eye[2], rgb);
    sp.r = rgb[0]; sp.g = rgb[1]; sp.b = rgb[2];
  }
  out[k] = sp;
  rect[k] = make_int4(tx0, ty0, tx1, ty1);
  touched[k] = static_cast<std::uint64_t>(tx1 - tx0) * static_cast<std::uint64_t>(ty1 - ty0);
}

// Key (tile << 32 | depth bits) per touched tile; depth > 0, so its bits order like the floats.
__global__ void duplicate_kernel(std::size_t n, const Splat* __restrict__ splat, const std::uint64_t* __restrict__ touched,
                                 const std::uint64_t* __restrict__ offset, const int4* __restrict__ rect, int tiles_x,
                                 std::uint64_t* __restrict__ keys, std::uint32_t* __restrict__ vals) {
  const std::size_t k = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x;
  if (k >= n || touched[k] == 0) return;
  const int4 r = rect[k];
  const std::uint64_t depth_bits = __float_as_uint(splat[k].depth);
  std::uint64_t o = offset[k];
  for (int ty = r.y; ty < r.w; ++ty)
    for (int tx = r.x; tx < r.z; ++tx) {
      keys[o] = (static_cast<std::uint64_t>(ty * tiles_x + tx) << 32) | depth_bits;
      vals[o] = static_cast<std::uint32_t>(k);
      ++o;
    }
}

// ranges[2 t] .. ranges[2 t + 1]: the entries of tile t (zeroed beforehand).
__global__ void ranges_kernel(std::size_t m, const std::uint64_t* __restrict__ keys, std::uint64_t* __restrict__ ranges) {
  const std::size_t e = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x;
  if (e >= m) return;
  const std::uint64_t tile = keys[e] >> 32;
  if (e == 0 || (keys[e - 1] >> 32) != tile) ranges[2 * tile] = e;
  if (e + 1 == m || (keys[e + 1] >> 32) != tile) ranges[2 * tile + 1] = e + 1;
}

// One block per tile, one thread per pixel, front to back (conventions §3): sigma = 1/2 d^T
// Sigma2D^-1 d with d = m - p, alpha = min(0.999, o exp(-sigma)), skip alpha < 1/255, stop
// before the splat whose next transmittance would be <= 1e-4. Contrib: per entry, the block's
// sum of alpha T (and alpha T fg), reduced warp by warp in a fixed order.
template <bool Colour, bool Contrib>
__global__ void __launch_bounds__(block_pixels)
composite_kernel(int W, int H, int tiles_x, const Splat* __restrict__ splat, const std::uint32_t* __restrict__ vals,
                 const std::uint64_t* __restrict__ ranges, float bg_r, float bg_g, float bg_b,
                 float* __restrict__ rgb, float* __restrict__ alpha_out, float* __restrict__ depth_out,
                 const std::uint8_t* __restrict__ mask, float* __restrict__ entry_w, float* __restrict__ entry_wfg) {
  __shared__ Splat batch[block_pixels];
  __shared__ float part_w[Contrib ? block_pixels / 32 : 1][Contrib ? block_pixels : 1];
  __shared__ float part_wfg[Contrib ? block_pixels / 32 : 1][Contrib ? block_pixels : 1];
  const int tile = blockIdx.y * tiles_x + blockIdx.x;
  const int tid = threadIdx.y * tile_size + threadIdx.x;
  const int x = blockIdx.x * tile_size + threadIdx.x, y = blockIdx.y * tile_size + threadIdx.y;
  const bool inside = x < W && y < H;
  const float px = static_cast<float>(x) + 0.5f, py = static_cast<float>(y) + 0.5f;  // pixel centre
  const float fg = Contrib && inside ? (mask[static_cast<std::size_t>(y) * W + x] != 0 ? 1.f : 0.f) : 0.f;
  bool done = !inside;
  float T = 1.f, cr = 0.f, cg = 0.f, cb = 0.f, D = 0.f;
  const std::uint64_t begin = ranges[2 * tile], end = ranges[2 * tile + 1];
  for (std::uint64_t b = begin; b < end; b += block_pixels) {
    if (__syncthreads_count(done) == block_pixels) break;  // every pixel of the tile saturated
    const int count = end - b < block_pixels ? static_cast<int>(end - b) : block_pixels;
    if (tid < count) batch[tid] = splat[vals[b + tid]];
    __syncthreads();
    for (int j = 0; j < count; ++j) {
      float w = 0.f;
      if (!done) {
        const Splat& s = batch[j];
        const float dx = s.mx - px, dy = s.my - py;
        const float sigma = 0.5f * s.ca * dx * dx + s.cb * dy * dx + 0.5f * s.cc * dy * dy;
        const float a = fminf(alpha_max, s.opacity * expf(-sigma));
        if (sigma >= 0.f && a >= alpha_skip) {
          const float nT = T * (1.f - a);
          if (nT <= T_stop) {
            done = true;
          } else {
            w = a * T;
            if (Colour) { cr += w * s.r; cg += w * s.g; cb += w * s.b; D += w * s.depth; }
            T = nT;
          }
        }
      }
      if (Contrib) {
        float v = w, vfg = w * fg;
        for (int off = 16; off > 0; off >>= 1) {
          v += __shfl_down_sync(0xffffffffu, v, off);
          vfg += __shfl_down_sync(0xffffffffu, vfg, off);
        }
        if ((tid & 31) == 0) { part_w[tid >> 5][j] = v; part_wfg[tid >> 5][j] = vfg; }
      }
    }
    if (Contrib) {
      __syncthreads();
      if (tid < count) {
        float v = 0.f, vfg = 0.f;
        for (int k = 0; k < block_pixels / 32; ++k) { v += part_w[k][tid]; vfg += part_wfg[k][tid]; }
        entry_w[b + tid] = v;
        entry_wfg[b + tid] = vfg;
      }
    }
    __syncthreads();  // the batch is rewritten next
  }
  if (Colour && inside) {
    const std::size_t o = static_cast<std::size_t>(y) * W + x;
    rgb[3 * o + 0] = cr + bg_r * T;
    rgb[3 * o + 1] = cg + bg_g * T;
    rgb[3 * o + 2] = cb + bg_b * T;
    alpha_out[o] = 1.f - T;
    if (depth_out) depth_out[o] = D;
  }
}

int blocks_for(std::size_t n, int threads) { return static_cast<int>((n + threads - 1) / threads); }

}  // namespace

struct Splatter::Impl {
  cudaStream_t stream = nullptr;
  cudaEvent_t ev[6] = {};
  FrameTimings timings;
  DeviceBuffer<float> columns, sh, rgb, alpha, depth, entry_w, entry_wfg;
  DeviceBuffer<Splat> splat;
  DeviceBuffer<std::uint32_t> vals, vals_sorted;
  DeviceBuffer<std::uint64_t> touched, offset, keys, keys_sorted, ranges;
  DeviceBuffer<int4> rect;
  DeviceBuffer<std::uint8_t> mask, scratch;
  std::size_t entries = 0;
  int tiles_x = 0, tiles_y = 0;

  Impl() {
    VCAR_CUDA(cudaStreamCreate(&stream));
    for (auto& e : ev) VCAR_CUDA(cudaEventCreate(&e));
  }
  ~Impl() {
    for (auto& e : ev) if (e) cudaEventDestroy(e);
    if (stream) cudaStreamDestroy(stream);
  }

  // Upload, project, duplicate, sort, ranges: everything before compositing.
  void prepare(const HostGaussians& g, const CameraParams& cam, const ProjectionConstants& pc, bool colour) {
    const std::size_t n = g.n;
    tiles_x = (cam.width + tile_size - 1) / tile_size;
    tiles_y = (cam.height + tile_size - 1) / tile_size;
    const std::size_t tiles = static_cast<std::size_t>(tiles_x) * tiles_y;
    VCAR_CUDA(cudaEventRecord(ev[0], stream));
    float* d_col = columns.get(n * gaussian_columns);
    VCAR_CUDA(cudaMemcpyAsync(d_col, g.columns, n * gaussian_columns * sizeof(float), cudaMemcpyHostToDevice, stream));
    const std::size_t B3 = static_cast<std::size_t>((g.sh_degree + 1) * (g.sh_degree + 1)) * 3;
    float* d_sh = sh.get(colour ? n * B3 : 1);
    if (colour) VCAR_CUDA(cudaMemcpyAsync(d_sh, g.sh, n * B3 * sizeof(float), cudaMemcpyHostToDevice, stream));
    VCAR_CUDA(cudaEventRecord(ev[1], stream));
    Splat* d_splat = splat.get(n);
    std::uint64_t* d_touched = touched.get(n + 1);
    int4* d_rect = rect.get(n);
    if (n > 0)
      project_kernel<<<blocks_for(n, 256), 256, 0, stream>>>(n, d_col, d_sh, g.sh_degree, cam, pc, tiles_x, tiles_y,
                                                               colour, d_splat, d_touched, d_rect);
    VCAR_CUDA(cudaGetLastError());
    // Exclusive scan of the touched counts (64-bit: entries of large scenes overflow 32 bits).
    std::uint64_t* d_offset = offset.get(n + 1);
    VCAR_CUDA(cudaMemsetAsync(d_touched + n, 0, sizeof(std::uint64_t), stream));
    std::size_t tmp_bytes = 0;
    VCAR_CUDA(cub::DeviceScan::ExclusiveSum(nullptr, tmp_bytes, d_touched, d_offset, n + 1, stream));
    VCAR_CUDA(cub::DeviceScan::ExclusiveSum(scratch.get(tmp_bytes), tmp_bytes, d_touched, d_offset, n + 1, stream));
    std::uint64_t m = 0;
    VCAR_CUDA(cudaMemcpyAsync(&m, d_offset + n, sizeof m, cudaMemcpyDeviceToHost, stream));
    VCAR_CUDA(cudaStreamSynchronize(stream));
    entries = m;
    VCAR_CUDA(cudaEventRecord(ev[2], stream));
    std::uint64_t* d_keys = keys.get(m);
    std::uint32_t* d_vals = vals.get(m);
    if (n > 0)
      duplicate_kernel<<<blocks_for(n, 256), 256, 0, stream>>>(n, d_splat, d_touched, d_offset, d_rect, tiles_x,
                                                                 d_keys, d_vals);
    VCAR_CUDA(cudaGetLastError());
    // Sort only the bits in use: 32 of depth plus enough for the tile index.
    int tile_bits = 1;
    while ((std::size_t{1} << tile_bits) < tiles) ++tile_bits;
    std::uint64_t* d_keys_sorted = keys_sorted.get(m);
    std::uint32_t* d_vals_sorted = vals_sorted.get(m);
    if (m > 0) {
      tmp_bytes = 0;
      VCAR_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, tmp_bytes, d_keys, d_keys_sorted, d_vals, d_vals_sorted,
                                                static_cast<std::int64_t>(m), 0, 32 + tile_bits, stream));
      VCAR_CUDA(cub::DeviceRadixSort::SortPairs(scratch.get(tmp_bytes), tmp_bytes, d_keys, d_keys_sorted, d_vals,
                                                d_vals_sorted, static_cast<std::int64_t>(m), 0, 32 + tile_bits, stream));
    }
    std::uint64_t* d_ranges = ranges.get(2 * tiles);
    VCAR_CUDA(cudaMemsetAsync(d_ranges, 0, 2 * tiles * sizeof(std::uint64_t), stream));
    if (m > 0) ranges_kernel<<<blocks_for(m, 256), 256, 0, stream>>>(m, d_keys_sorted, d_ranges);
    VCAR_CUDA(cudaGetLastError());
    VCAR_CUDA(cudaEventRecord(ev[3], stream));
  }

  void finish_timings() {
    VCAR_CUDA(cudaEventSynchronize(ev[5]));
    VCAR_CUDA(cudaEventElapsedTime(&timings.upload_ms, ev[0], ev[1]));
    VCAR_CUDA(cudaEventElapsedTime(&timings.project_ms, ev[1], ev[2]));
    VCAR_CUDA(cudaEventElapsedTime(&timings.sort_ms, ev[2], ev[3]));
    VCAR_CUDA(cudaEventElapsedTime(&timings.composite_ms, ev[3], ev[4]));
    VCAR_CUDA(cudaEventElapsedTime(&timings.download_ms, ev[4], ev[5]));
    timings.entries = entries;
  }
};

Splatter::Splatter() : impl_(std::make_unique<Impl>()) {}
Splatter::~Splatter() = default;

const FrameTimings& Splatter::last_timings() const { return impl_->timings; }

std::string Splatter::device_name() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess || count == 0) return {};
  int dev = 0;
  cudaDeviceProp prop{};
  if (cudaGetDevice(&dev) != cudaSuccess || cudaGetDeviceProperties(&prop, dev) != cudaSuccess) return {};
  return prop.name;
}

void Splatter::render(const HostGaussians& g, const CameraParams& cam, const ProjectionConstants& pc,
                      const float background[3], float* rgb, float* alpha, float* depth) {
  Impl& s = *impl_;
  s.prepare(g, cam, pc, /*colour=*/true);
  const std::size_t P = static_cast<std::size_t>(cam.width) * cam.height;
  float* d_rgb = s.rgb.get(3 * P);
  float* d_alpha = s.alpha.get(P);
  float* d_depth = depth ? s.depth.get(P) : nullptr;
  const dim3 grid(s.tiles_x, s.tiles_y), block(tile_size, tile_size);
  composite_kernel<true, false><<<grid, block, 0, s.stream>>>(
      cam.width, cam.height, s.tiles_x, s.splat.p, s.vals_sorted.p, s.ranges.p, background[0],
      background[1], background[2], d_rgb, d_alpha, d_depth, nullptr, nullptr, nullptr);
  VCAR_CUDA(cudaGetLastError());
  VCAR_CUDA(cudaEventRecord(s.ev[4], s.stream));
  VCAR_CUDA(cudaMemcpyAsync(rgb, d_rgb, 3 * P * sizeof(float), cudaMemcpyDeviceToHost, s.stream));
  VCAR_CUDA(cudaMemcpyAsync(alpha, d_alpha, P * sizeof(float), cudaMemcpyDeviceToHost, s.stream));
  if (depth) VCAR_CUDA(cudaMemcpyAsync(depth, d_depth, P * sizeof(float), cudaMemcpyDeviceToHost, s.stream));
  VCAR_CUDA(cudaEventRecord(s.ev[5], s.stream));
  VCAR_CUDA(cudaStreamSynchronize(s.stream));
  s.finish_timings();
}

void Splatter::contributions(const HostGaussians& g, const CameraParams& cam, const ProjectionConstants& pc,
                             const std::uint8_t* mask, double* weight, double* weight_fg) {
  Impl& s = *impl_;
  s.prepare(g, cam, pc, /*colour=*/false);
  const std::size_t P = static_cast<std::size_t>(cam.width) * cam.height, m = s.entries;
  std::uint8_t* d_mask = s.mask.get(P);
  VCAR_CUDA(cudaMemcpyAsync(d_mask, mask, P, cudaMemcpyHostToDevice, s.stream));
  float* d_w = s.entry_w.get(m);
  float* d_wfg = s.entry_wfg.get(m);
  if (m > 0) {
    VCAR_CUDA(cudaMemsetAsync(d_w, 0, m * sizeof(float), s.stream));  // entries never reached stay 0
    VCAR_CUDA(cudaMemsetAsync(d_wfg, 0, m * sizeof(float), s.stream));
  }
  const dim3 grid(s.tiles_x, s.tiles_y), block(tile_size, tile_size);
  composite_kernel<false, true><<<grid, block, 0, s.stream>>>(
      cam.width, cam.height, s.tiles_x, s.splat.p, s.vals_sorted.p, s.ranges.p, 0.f, 0.f, 0.f, nullptr,
      nullptr, nullptr, d_mask, d_w, d_wfg);
  VCAR_CUDA(cudaGetLastError());
  VCAR_CUDA(cudaEventRecord(s.ev[4], s.stream));
  std::vector<float> w(m), wfg(m);
  std::vector<std::uint32_t> k(m);
  if (m > 0) {
    VCAR_CUDA(cudaMemcpyAsync(w.data(), d_w, m * sizeof(float), cudaMemcpyDeviceToHost, s.stream));
    VCAR_CUDA(cudaMemcpyAsync(wfg.data(), d_wfg, m * sizeof(float), cudaMemcpyDeviceToHost, s.stream));
    VCAR_CUDA(cudaMemcpyAsync(k.data(), s.vals_sorted.p, m * sizeof(std::uint32_t), cudaMemcpyDeviceToHost, s.stream));
  }
  VCAR_CUDA(cudaEventRecord(s.ev[5], s.stream));
  VCAR_CUDA(cudaStreamSynchronize(s.stream));
  s.finish_timings();
  for (std::size_t e = 0; e < m; ++e) {  // (tile, depth) order: independent of scheduling
    weight[k[e]] += w[e];
    weight_fg[k[e]] += wfg[e];
  }
}

}  // namespace vcar::cuda::detail
