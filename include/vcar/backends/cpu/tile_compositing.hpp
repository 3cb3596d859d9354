#pragma once
// Front-to-back compositing of one 16 x 16 tile, SIMD over the pixels of a row (conventions §3):
// alpha = min(0.999, opacity exp(-sigma)), skip alpha < 1/255, stop before the Gaussian whose
// next transmittance T (1 - alpha) would be <= 1e-4 (gsplat does not composite that one).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "vcar/backends/cpu/tile_binning.hpp"
#include "vcar/core/simd.hpp"

namespace vcar::cpu {

using Lane = simd::batch<float>;  // width follows the compiler flags (SSE2, NEON, scalar: 4; AVX2: 8; AVX-512: 16)
static_assert(tile_size % Lane::size == 0, "a tile row is a whole number of SIMD batches");

inline constexpr float alpha_max = 0.999f;        // gsplat clamp
inline constexpr float alpha_skip = 1.f / 255.f;  // below this a splat is skipped at a pixel
inline constexpr float T_stop = 1e-4f;            // stop when T (1 - alpha) <= this

// Per-tile state; lives on the worker's stack, nothing is allocated per tile or pixel.
struct TileState {
  static constexpr int P = tile_size * tile_size;
  alignas(64) float T[P];                 // transmittance
  alignas(64) float active[P];            // 1 while the pixel still composites, else 0
  alignas(64) float cr[P], cg[P], cb[P];  // sum c alpha T
  alignas(64) float D[P];                 // sum z alpha T
  alignas(64) float fg[P];                // mask value (0/1), contributions only
  // Bit r * NB + b: batch b of row r still has an active pixel (lets whole splats be skipped
  // once the pixels they cover are done).
  static constexpr int NB = tile_size / static_cast<int>(Lane::size);
  static_assert(tile_size * NB <= 64, "one bit per batch fits a 64-bit word");
  std::uint64_t live = 0;

  // Pixels outside the image (edge tiles) start inactive: they neither render nor contribute.
  void reset(int w_valid, int h_valid) {
    for (int p = 0; p < P; ++p) {
      const int r = p / tile_size, c = p % tile_size;
      T[p] = 1.f;
      active[p] = (r < h_valid && c < w_valid) ? 1.f : 0.f;
      cr[p] = cg[p] = cb[p] = D[p] = fg[p] = 0.f;
    }
    update_live();
  }
  // `live` from `active` (after reset, or after active was loaded back).
  void update_live() {
    live = 0;
    for (int p = 0; p < P; p += static_cast<int>(Lane::size))
      if (simd::any(Lane::load_aligned(active + p) > Lane(0.f))) live |= std::uint64_t{1} << (p / static_cast<int>(Lane::size));
  }
  bool all_done() const { return live == 0; }
};

// floor(v) clamped to [lo, tile_size], ceil(v) clamped to [-1, hi]; in float first, so huge
// splats do not overflow, and without a branch (whether a splat crosses the tile's edge is hard
// to predict).
inline int clamp_floor(float v, int lo) {
  return static_cast<int>(std::max(std::min(std::floor(v), static_cast<float>(tile_size)), static_cast<float>(lo)));
}
inline int clamp_ceil(float v, int hi) {
  return static_cast<int>(std::min(std::max(std::ceil(v), -1.f), static_cast<float>(hi)));
}

// Composites the splats ids[0..count) (front to back) into tile (x0, y0) of size
// w_valid x h_valid. Colour: accumulate rgb (the splat's r, g, b) and depth. Contrib: entry_w[e] /
// entry_wfg[e] get sum alpha T and sum alpha T fg over the tile for entry e (entries never
// reached stay as given).
template <bool Colour, bool Contrib>
void composite_tile(const PackedSplat* splat, const std::uint32_t* ids, std::int64_t count, int x0, int y0,
                    int w_valid, int h_valid, TileState& st, float* entry_w = nullptr,
                    float* entry_wfg = nullptr) {
  constexpr int L = static_cast<int>(Lane::size);
  constexpr int NB = TileState::NB;
  // 1 at bit r * NB of every row r: times a row's batch bits, the same bits on every row.
  constexpr std::uint64_t row_ones = [] {
    std::uint64_t m = 0;
    for (int r = 0; r < tile_size; ++r) m |= std::uint64_t{1} << (r * NB);
    return m;
  }();
  alignas(64) float lane_x[tile_size];  // pixel-centre x of each column (conventions §2)
  for (int c = 0; c < tile_size; ++c) lane_x[c] = static_cast<float>(x0 + c) + 0.5f;
  const Lane zero(0.f), one(1.f), amax(alpha_max), askip(alpha_skip), tstop(T_stop);

  // A tile's splats are scattered in memory: each is fetched `ahead` entries before its turn.
  constexpr std::int64_t ahead = 16;
  for (std::int64_t e = 0; e < count; ++e) {
    if (e + ahead < count) __builtin_prefetch(splat + ids[e + ahead]);
    const PackedSplat& s = splat[ids[e]];
    const float mx = s.mx, my = s.my, rx = s.rx, ry = s.ry;
    // Rows and columns of the tile inside the bounding box widened by one pixel, and whose pixel
    // centres (+0.5) lie within the exact extents ex, ey.
    const float fx = mx - static_cast<float>(x0) - 0.5f, fy = my - static_cast<float>(y0) - 0.5f;
    const int r_lo = clamp_floor(std::max(std::floor(fy - ry - 0.5f), std::ceil(fy - s.ey)), 0);
    const int r_hi = clamp_ceil(std::min(std::ceil(fy + ry + 1.5f), std::floor(fy + s.ey)), h_valid - 1);
    const int c_lo = clamp_floor(std::max(std::floor(fx - rx - 0.5f), std::ceil(fx - s.ex)), 0);
    const int c_hi = clamp_ceil(std::min(std::ceil(fx + rx + 1.5f), std::floor(fx + s.ex)), w_valid - 1);
    if (r_lo > r_hi || c_lo > c_hi) continue;
    // Batches under the bounding box: the row's batch bits copied to rows r_lo..r_hi.
    const std::uint64_t row_bits = ((std::uint64_t{2} << (c_hi / L - c_lo / L)) - 1) << (c_lo / L);
    const int rows = r_hi - r_lo + 1;
    const std::uint64_t row_span = rows * NB >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << (rows * NB)) - 1;
    const std::uint64_t cover = (row_bits * row_ones) & (row_span << (r_lo * NB));
    if ((cover & st.live) == 0) continue;  // every pixel it covers is done
    const float ca = s.ca, cb = s.cb, cc = s.cc;
    const float sig_max = s.sigma_max + sigma_slack;  // the lanes decide exactly
    const Lane half_ca(0.5f * ca), op(s.opacity), lane_sig_max(sig_max), lmx(mx), depth(s.depth);
    const Lane cr(s.r), cg(s.g), cbl(s.b);
    Lane sw = zero, swfg = zero;
    bool stopped = false;
    // sigma at the pixels of batch `bit`, and whether any live one may reach alpha >= 1/255.
    auto sigma_at = [&](int bit, Lane& sigma) {
      const int r = bit / NB, b = bit % NB;
      const float dy = my - (static_cast<float>(y0 + r) + 0.5f);
      const Lane act = Lane::load_aligned(st.active + r * tile_size + b * L);
      const Lane dx = lmx - Lane::load_aligned(lane_x + b * L);
      sigma = half_ca * dx * dx + Lane(cb * dy) * dx + Lane(0.5f * cc * dy * dy);
      return simd::any((act > zero) && (sigma <= lane_sig_max));
    };
    // Front-to-back blend of the splat into batch `bit`, given sigma and alpha there.
    auto blend = [&](int bit, const Lane& sigma, const Lane& alpha) VCAR_FORCE_INLINE {
      const int p = (bit / NB) * tile_size + (bit % NB) * L;
      const Lane act = Lane::load_aligned(st.active + p);
      const auto ok = (act > zero) && (sigma >= zero) && (alpha >= askip);
      // No branch on any(ok): it waits for exp and mispredicts often; with no lane ok, w is 0
      // and T is stored back unchanged, so the sums below keep their bits.
      const Lane T = Lane::load_aligned(st.T + p);
      const Lane nT = T * (one - alpha);
      const auto stop = ok && (nT <= tstop);
      const auto take = ok && !stop;
      const Lane w = simd::select(take, alpha * T, zero);
      simd::select(take, nT, T).store_aligned(st.T + p);
      if (simd::any(stop)) {
        const Lane still = simd::select(stop, zero, act);
        still.store_aligned(st.active + p);
        if (!simd::any(still > zero)) {
          st.live &= ~(std::uint64_t{1} << bit);
          stopped = true;
        }
      }
      if constexpr (Colour) {
        (Lane::load_aligned(st.cr + p) + w * cr).store_aligned(st.cr + p);
        (Lane::load_aligned(st.cg + p) + w * cg).store_aligned(st.cg + p);
        (Lane::load_aligned(st.cb + p) + w * cbl).store_aligned(st.cb + p);
        (Lane::load_aligned(st.D + p) + w * depth).store_aligned(st.D + p);
      }
      if constexpr (Contrib) {
        sw += w;
        swfg += w * Lane::load_aligned(st.fg + p);
      }
    };
    auto alpha_of = [&](const Lane& sigma) { return simd::min(amax, op * simd::exp(-sigma)); };
    // First which live batches under the box the splat may reach, with no branch per batch
    // (whether one is needed is hard to predict; the sigmas wait on the stack), then the needed
    // ones two at a time: their exps are independent, and issued together their latencies overlap.
    alignas(64) float sigmas[TileState::P];  // batch `bit`'s sigma at sigmas + bit * L
    std::uint64_t need = 0;
    for (std::uint64_t todo = cover & st.live; todo != 0; todo &= todo - 1) {
      const int a = std::countr_zero(todo);
      Lane sigma;
      need |= static_cast<std::uint64_t>(sigma_at(a, sigma)) << a;
      sigma.store_aligned(sigmas + a * L);
    }
    while (need != 0) {
      const int a = std::countr_zero(need);
      need &= need - 1;
      const Lane sig_a = Lane::load_aligned(sigmas + a * L);
      if (need == 0) {
        blend(a, sig_a, alpha_of(sig_a));
        break;
      }
      const int b = std::countr_zero(need);
      need &= need - 1;
      const Lane sig_b = Lane::load_aligned(sigmas + b * L);
      const Lane alpha_a = alpha_of(sig_a), alpha_b = alpha_of(sig_b);
      blend(a, sig_a, alpha_a);
      blend(b, sig_b, alpha_b);
    }
    if constexpr (Contrib) {
      entry_w[e] = simd::reduce_add(sw);
      entry_wfg[e] = simd::reduce_add(swfg);
    }
    if (stopped && st.all_done()) break;  // every pixel of the tile has saturated
  }
}

}  // namespace vcar::cpu
