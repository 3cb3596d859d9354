#pragma once
// vcar::cpu::TiledRenderer: the CPU reference splatter, gsplat-equivalent (conventions §3).
// Steps: project every drawn Gaussian (core/projection.hpp, B.6-B.7), cull, shade the splats on
// screen (SH colour, batch_shading.hpp; renders only), bin into 16 x 16
// tiles in camera-depth order (ties by drawn index), composite each tile front to back,
// multi-threaded over tiles and SIMD over the pixels of a tile. Results are bit-identical for
// any thread count. One renderer serves one call at a time (it keeps scratch buffers).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/backends/cpu/batch_projection.hpp"
#include "vcar/backends/cpu/batch_shading.hpp"
#include "vcar/backends/cpu/tile_binning.hpp"
#include "vcar/backends/cpu/tile_compositing.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/projection.hpp"

namespace vcar::cpu {

struct TiledRendererOptions {
  ProjectionParams projection{};  // near plane, eps2d, Jacobian clamp, extent (conventions §3)
  int num_threads = 0;            // 0: the current vcar::max_threads()
};

// Wall time of the last call's stages (benchmarks/bench_render prints them).
struct TiledRendererTimes {
  double project_ms = 0, shade_ms = 0, bin_ms = 0, composite_ms = 0;  // shade_ms: 0 for contributions
};

class TiledRenderer {
public:
  TiledRenderer() = default;
  explicit TiledRenderer(TiledRendererOptions o) : opt_(o) {}
  const TiledRendererOptions& options() const { return opt_; }
  TiledRendererOptions& options() { return opt_; }
  const TiledRendererTimes& last_times() const { return times_; }

  // Renders rgb (bg * T_final behind), alpha = 1 - T_final and, if asked, depth = sum z alpha T.
  //
  // Tiles composite their splats in waves of depth ranks (the front 1/4, then the next 1/2, ...),
  // and each wave bins its splats only into the tiles that still have a pixel to composite: in
  // a deep scene most splats lie behind saturated pixels and are never binned (bench_render's 1M
  // splats at 1280 x 720 saturate every tile within the front 26%). Between waves a tile's state
  // waits in the output images; the image is the same, bit for bit, as with one wave. When after
  // a wave fewer than 1/20 of the tiles have saturated, the next wave takes every splat left (a
  // shallow scene pays for one wait at most).
  RenderOutput render(const RenderRequest& q) {
    const Camera& cam = check(q);
    ThreadScope threads(opt_.num_threads);
    prepare(q, true, false);
    const int W = cam.width, H = cam.height;
    RenderOutput out;
    out.rgb = ImageF(W, H, 3);
    out.alpha = ImageF(W, H, 1);
    if (q.want_depth) out.depth = ImageF(W, H, 1);
    const std::int64_t tiles = bins_.tiles(), m = static_cast<std::int64_t>(bins_.order.size());
    done_.assign(static_cast<std::size_t>(tiles), 0);
    active_.resize(static_cast<std::size_t>(tiles) * active_words);
    times_.composite_ms = 0;
    std::int64_t saturated = 0;
    const Eigen::Vector3f bg = q.background;
    for (std::int64_t j0 = 0, wave = 0, size = std::max<std::int64_t>(1, m / 4); wave == 0 || j0 < m; ++wave) {
      const std::int64_t j1 = saturated * 20 < tiles && wave > 0 ? m : std::min(m, j0 + size);
      const auto tb = Clock::now();
      bin_ranks(bins_, j0, j1, wave == 0 ? nullptr : done_.data());
      times_.bin_ms += ms_since(tb);
      const auto tc = Clock::now();
      parallel_for_dynamic(tiles, [&](std::int64_t t) {
        if (done_[t]) return;
        int x0, y0, w, h;
        tile_extent(t, W, H, x0, y0, w, h);
        TileState st;
        if (wave == 0)
          st.reset(w, h);
        else
          load_tile(out, t, x0, y0, w, h, st);
        const std::int64_t b = bins_.start[t], e = bins_.start[t + 1];
        composite_tile<true, false>(splats_.splat.data(), bins_.ids.data() + b, e - b, x0, y0, w, h, st);
        done_[t] = st.all_done();  // read by this tile only
        if (done_[t] || j1 == m)
          finish_tile(st, x0, y0, w, h, bg, out);
        else
          save_tile(st, t, x0, y0, w, h, out);
      });
      saturated = std::count(done_.begin(), done_.end(), std::uint8_t{1});
      times_.composite_ms += ms_since(tc);
      if (saturated == tiles) break;
      j0 = j1;
      size *= 2;
    }
    return out;
  }

  // weight[i] += sum_p alpha_i T_i, weight_fg[i] += sum_p alpha_i T_i [mask != 0] over the pixels
  // of this view, i indexing the scene. Empty `acc` is sized to the scene first.
  void accumulate_contributions(const RenderRequest& q, const Mask& mask, Contributions& acc) {
    const Camera& cam = check(q);
    const std::size_t n = q.scene->size();
    if (mask.width != cam.width || mask.height != cam.height || mask.channels != 1)
      throw Error("mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                  ", view is " + std::to_string(cam.width) + "x" + std::to_string(cam.height),
                  "view '" + cam.name + "'");
    if (acc.weight.empty() && acc.weight_fg.empty()) acc.reset(n);
    if (acc.weight.size() != n || acc.weight_fg.size() != n)
      throw Error("contribution vectors must be sized like the scene", "Contributions");
    ThreadScope threads(opt_.num_threads);
    prepare(q, false, true);
    const int W = cam.width, H = cam.height;
    const auto t0 = Clock::now();
    entry_w_.assign(bins_.ids.size(), 0.f);
    entry_wfg_.assign(bins_.ids.size(), 0.f);
    parallel_for_dynamic(bins_.tiles(), [&](std::int64_t t) {
      int x0, y0, w, h;
      tile_extent(t, W, H, x0, y0, w, h);
      TileState st;
      st.reset(w, h);
      for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c)
          st.fg[r * tile_size + c] = mask.data[static_cast<std::size_t>(y0 + r) * W + (x0 + c)] != 0 ? 1.f : 0.f;
      const std::int64_t b = bins_.start[t], e = bins_.start[t + 1];
      composite_tile<false, true>(splats_.splat.data(), bins_.ids.data() + b, e - b, x0, y0, w, h, st,
                                  entry_w_.data() + b, entry_wfg_.data() + b);
    });
    // Reduced in tile order, one thread: the sums do not depend on the thread count.
    for (std::size_t e = 0; e < bins_.ids.size(); ++e) {
      const std::size_t i = scene_index(q, bins_.ids[e]);
      acc.weight[i] += entry_w_[e];
      acc.weight_fg[i] += entry_wfg_[e];
    }
    times_.composite_ms = ms_since(t0);
  }

private:
  using Clock = std::chrono::steady_clock;
  static double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

  // Sets the thread count for one call (restored afterwards); 0 leaves it as it is.
  struct ThreadScope {
    int saved = 0;
    explicit ThreadScope(int n) {
      if (n > 0) { saved = max_threads(); set_num_threads(n); }
    }
    ~ThreadScope() { if (saved > 0) set_num_threads(saved); }
  };

  static std::size_t scene_index(const RenderRequest& q, std::size_t k) {
    return q.subset ? static_cast<std::size_t>((*q.subset)[k]) : k;
  }

  // Boundary checks: the request names a scene and a valid camera, subset indices and the
  // log-scale override fit the scene.
  static const Camera& check(const RenderRequest& q) {
    if (!q.scene || !q.camera) throw Error("request needs a scene and a camera", "RenderRequest");
    const Camera& cam = *q.camera;
    cam.validate();
    if (cam.width > 65535 * tile_size || cam.height > 65535 * tile_size ||  // tile indices in 16 bits
        static_cast<std::int64_t>(cam.width) * cam.height > (std::int64_t{1} << 31) - 1)
      throw Error("image larger than the CPU renderer supports (65535 tiles a side, 2^31 pixels)", "view '" + cam.name + "'");
    const GaussianScene& sc = *q.scene;
    const std::size_t n = sc.size();
    for (int d = 0; d < 3; ++d)
      if (sc.mean[d].size() != n || sc.log_scale[d].size() != n)
        throw Error("scene columns disagree in size", "scene");
    for (int c = 0; c < 4; ++c)
      if (sc.rotation[c].size() != n) throw Error("scene columns disagree in size", "scene");
    if (sc.sh_degree < 0 || sc.sh_degree > 3 || sc.sh.size() != n * static_cast<std::size_t>(sc.sh_coeffs()) * 3)
      throw Error("SH degree must be 0..3 with (degree+1)^2 x 3 coefficients per Gaussian", "scene");
    std::size_t drawn = n;
    if (q.subset) {
      drawn = q.subset->size();
      for (std::size_t k = 0; k < drawn; ++k)
        if ((*q.subset)[k] >= n)
          throw Error("subset index " + std::to_string((*q.subset)[k]) + " out of range (scene has " +
                      std::to_string(n) + ")", "RenderRequest::subset");
    }
    // (in 64 bits: on 32-bit targets such as WebAssembly, size_t << 32 would be undefined)
    if (static_cast<std::uint64_t>(drawn) >= (std::uint64_t{1} << 32)) throw Error("more than 2^32 drawn Gaussians", "RenderRequest");
    if (q.log_scale)
      for (int d = 0; d < 3; ++d)
        if ((*q.log_scale)[d].size() != drawn)
          throw Error("log-scale column " + std::to_string(d) + " has " +
                      std::to_string((*q.log_scale)[d].size()) + " values, expected " + std::to_string(drawn),
                      "RenderRequest::log_scale");
    return cam;
  }

  static void tile_extent(std::int64_t t, int W, int H, int& x0, int& y0, int& w, int& h) {
    const int tiles_x = (W + tile_size - 1) / tile_size;
    x0 = static_cast<int>(t % tiles_x) * tile_size;
    y0 = static_cast<int>(t / tiles_x) * tile_size;
    w = std::min(tile_size, W - x0);
    h = std::min(tile_size, H - y0);
  }

  // Projects every drawn Gaussian (one result per index, any thread count), Lane::size at a
  // time (batch_projection.hpp), shades the splats on screen if `shade` (batch_shading.hpp),
  // sorts them by depth and, if `bin_all`, bins all of them.
  void prepare(const RenderRequest& q, bool shade, bool bin_all) {
    const GaussianScene& sc = *q.scene;
    const std::size_t n = q.subset ? q.subset->size() : sc.size();
    splats_.resize(n);
    ProjectedSplats& s = splats_;
    const ProjectionParams& pp = opt_.projection;
    const BatchCamera bc(*q.camera, pp);
    constexpr int L = static_cast<int>(Lane::size);
    const auto t0 = Clock::now();
    parallel_chunks(static_cast<std::int64_t>(n), 4096, [&](std::int64_t, std::int64_t b, std::int64_t e) {
      for (std::int64_t k0 = b; k0 < e; k0 += L) {
        const int lanes = static_cast<int>(std::min<std::int64_t>(L, e - k0));
        const GaussianBatch g = load_batch(q, static_cast<std::size_t>(k0), lanes);
        project_batch(bc, pp, g, static_cast<std::uint32_t>(k0), lanes, s.splat.data() + k0, s.rect.data() + k0);
        for (int l = 0; l < lanes; ++l) s.depth[k0 + l] = s.splat[k0 + l].depth;
      }
    });
    times_.project_ms = ms_since(t0);
    const auto ts = Clock::now();
    if (shade) shade_splats(q);
    times_.shade_ms = ms_since(ts);
    const auto t1 = Clock::now();
    if (bin_all)
      bin_tiles(splats_, q.camera->width, q.camera->height, bins_);
    else
      sort_by_depth(splats_, q.camera->width, q.camera->height, bins_);  // render() bins in waves
    times_.bin_ms = ms_since(t1);
  }

  // Colour of every splat on screen (batch_shading.hpp), Lane::size drawn Gaussians at a time in
  // drawn order. A pass of its own: fused into the projection loop it ran 1.4x slower.
  void shade_splats(const RenderRequest& q) {
    const GaussianScene& sc = *q.scene;
    const Eigen::Vector3f eye_v = q.camera->position();
    const float eye[3] = {eye_v.x(), eye_v.y(), eye_v.z()};
    constexpr int L = static_cast<int>(Lane::size);
    ProjectedSplats& s = splats_;
    parallel_chunks(static_cast<std::int64_t>(s.size()), 4096, [&](std::int64_t, std::int64_t b, std::int64_t e) {
      for (std::int64_t k0 = b; k0 < e; k0 += L) {
        const int lanes = static_cast<int>(std::min<std::int64_t>(L, e - k0));
        std::uint32_t on = 0;  // lanes on screen
        std::size_t idx[L];
        alignas(64) float mu[3][L];
        for (int l = 0; l < L; ++l) {  // lanes past `lanes` repeat the last one (and stay off)
          if (l < lanes && !rect_empty(s.rect[k0 + l])) on |= std::uint32_t{1} << l;
          idx[l] = scene_index(q, static_cast<std::size_t>(k0 + std::min(l, lanes - 1)));
          for (int d = 0; d < 3; ++d) mu[d][l] = sc.mean[d][idx[l]];
        }
        if (on == 0) continue;
        const Lane m[3] = {Lane::load_aligned(mu[0]), Lane::load_aligned(mu[1]), Lane::load_aligned(mu[2])};
        alignas(64) float c[3][L];
        shade_batch(sc, idx, on, m, eye, c);
        PackedSplat* out = s.splat.data() + k0;
        for (int l = 0; l < lanes; ++l)
          if ((on >> l) & 1u) out[l].r = c[0][l], out[l].g = c[1][l], out[l].b = c[2][l];
      }
    });
  }

  // A tile's pixels as rendered: rgb with bg * T behind, alpha = 1 - T, depth sums.
  static void finish_tile(const TileState& st, int x0, int y0, int w, int h, const Eigen::Vector3f& bg, RenderOutput& out) {
    const int W = out.alpha.width;
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) {
        const int p = r * tile_size + c;
        const std::size_t o = static_cast<std::size_t>(y0 + r) * W + (x0 + c);
        out.rgb.data[o * 3 + 0] = st.cr[p] + bg[0] * st.T[p];
        out.rgb.data[o * 3 + 1] = st.cg[p] + bg[1] * st.T[p];
        out.rgb.data[o * 3 + 2] = st.cb[p] + bg[2] * st.T[p];
        out.alpha.data[o] = 1.f - st.T[p];
        if (!out.depth.data.empty()) out.depth.data[o] = st.D[p];
      }
  }

  // A tile's state between waves: colour sums in out.rgb, T in out.alpha, depth sums in
  // out.depth (when asked for), active pixels as bits in active_.
  static constexpr int active_words = TileState::P / 64;
  void save_tile(const TileState& st, std::int64_t t, int x0, int y0, int w, int h, RenderOutput& out) {
    const int W = out.alpha.width;
    std::uint64_t* bits = active_.data() + t * active_words;
    for (int i = 0; i < active_words; ++i) bits[i] = 0;
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) {
        const int p = r * tile_size + c;
        const std::size_t o = static_cast<std::size_t>(y0 + r) * W + (x0 + c);
        out.rgb.data[o * 3 + 0] = st.cr[p];
        out.rgb.data[o * 3 + 1] = st.cg[p];
        out.rgb.data[o * 3 + 2] = st.cb[p];
        out.alpha.data[o] = st.T[p];
        if (!out.depth.data.empty()) out.depth.data[o] = st.D[p];
        bits[p / 64] |= std::uint64_t{st.active[p] > 0.f} << (p % 64);
      }
  }
  void load_tile(const RenderOutput& out, std::int64_t t, int x0, int y0, int w, int h, TileState& st) const {
    st.reset(w, h);  // pixels outside the image stay inactive
    const int W = out.alpha.width;
    const std::uint64_t* bits = active_.data() + t * active_words;
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) {
        const int p = r * tile_size + c;
        const std::size_t o = static_cast<std::size_t>(y0 + r) * W + (x0 + c);
        st.cr[p] = out.rgb.data[o * 3 + 0];
        st.cg[p] = out.rgb.data[o * 3 + 1];
        st.cb[p] = out.rgb.data[o * 3 + 2];
        st.T[p] = out.alpha.data[o];
        if (!out.depth.data.empty()) st.D[p] = out.depth.data[o];
        st.active[p] = (bits[p / 64] >> (p % 64)) & 1u ? 1.f : 0.f;
      }
    st.update_live();
  }

  TiledRendererOptions opt_{};
  ProjectedSplats splats_;
  TileBins bins_;
  std::vector<float> entry_w_, entry_wfg_;  // per (tile, splat) entry partial sums
  std::vector<std::uint8_t> done_;          // per tile: every pixel saturated (render waves)
  std::vector<std::uint64_t> active_;       // per tile: active pixels between waves
  TiledRendererTimes times_{};
};

static_assert(ContributionRenderer<TiledRenderer>);

}  // namespace vcar::cpu
