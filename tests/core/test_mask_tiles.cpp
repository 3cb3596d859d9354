#include <catch2/catch.hpp>

#include <random>

#include "vcar/core/mask_tiles.hpp"
#include "vcar/core/rle_mask.hpp"

using vcar::Mask;
using vcar::MaskTiles;

namespace {

// Brute force over the rectangle's pixels (clipped): 0 none, 2 all, 1 both.
int brute(const Mask& m, int x0, int y0, int x1, int y1) {
  bool fg = false, bg = false;
  for (int y = std::max(0, y0); y <= std::min(m.height - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(m.width - 1, x1); ++x) (m(x, y) ? fg : bg) = true;
  return fg && bg ? 1 : fg ? 2 : 0;
}

}  // namespace

TEST_CASE("MaskTiles: none and all are exact, mixed is conservative, tile-aligned rectangles are exact") {
  std::mt19937 rng(4);
  for (auto [W, H] : {std::pair{64, 48}, std::pair{37, 29}}) {  // whole and partial tiles
    Mask m(W, H, 1, 0);
    // Blocks of foreground with ragged edges and a few isolated pixels.
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) m(x, y) = (x > 5 && x < W - 9 && y > 3 && y < H / 2 + (x % 5)) ? 255 : 0;
    m(1, H - 2) = 7;
    MaskTiles t;
    t.build(m);
    std::uniform_int_distribution<int> X(-5, W + 4), Y(-5, H + 4);
    int counts[3] = {0, 0, 0};
    for (int k = 0; k < 4000; ++k) {
      int x0 = X(rng), x1 = X(rng), y0 = Y(rng), y1 = Y(rng);
      if (x0 > x1) std::swap(x0, x1);
      if (y0 > y1) std::swap(y0, y1);
      const int want = brute(m, x0, y0, x1, y1);
      const MaskTiles::Content got = t.classify(x0, y0, x1, y1);
      INFO(W << "x" << H << " rect " << x0 << "," << y0 << " - " << x1 << "," << y1);
      if (got == MaskTiles::background) CHECK(want == 0);
      if (got == MaskTiles::foreground) CHECK(want == 2);
      if (want == 1) CHECK(got == MaskTiles::mixed);
      ++counts[got];
    }
    CHECK(counts[0] > 0);
    CHECK(counts[1] > 0);
    if (W == 64) CHECK(t.classify(8, 16, 23, 23) == MaskTiles::foreground);  // whole tiles inside the block
    // Tile-aligned rectangles (clipped at the image border) are answered exactly.
    for (int ty = 0; ty * 8 < H; ++ty)
      for (int tx = 0; tx * 8 < W; ++tx) {
        const int want = brute(m, tx * 8, ty * 8, tx * 8 + 7, ty * 8 + 7);
        CHECK(static_cast<int>(t.classify(tx * 8, ty * 8, tx * 8 + 7, ty * 8 + 7)) == want);
      }
  }
  MaskTiles t;
  t.build(Mask(10, 10, 1, 0));
  CHECK(t.classify(20, 20, 30, 30) == MaskTiles::background);  // wholly outside: no foreground
  t.build(Mask(10, 10, 1, 1));  // rebuilt in place, all foreground
  CHECK(t.classify(0, 0, 9, 9) == MaskTiles::foreground);
  CHECK(t.classify(-3, 4, 5, 40) == MaskTiles::foreground);  // clipped to the image
}

TEST_CASE("MaskTiles: the summary of a large mask (tile rows counted in parallel) is exact per tile, the same for any thread count") {
  // 1001 x 701 (partial tiles at the right and bottom) is above parallel_pixels: its tile rows are
  // packed and counted in parallel, then integrated.
  const int W = 1001, H = 701;
  REQUIRE(static_cast<std::size_t>(W) * H >= MaskTiles::parallel_pixels);
  Mask m(W, H, 1, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float dx = static_cast<float>(x - 480), dy = static_cast<float>(y - 330);
      m(x, y) = dx * dx / (400.f * 400.f) + dy * dy / (250.f * 250.f) < 1.f ? 255 : 0;  // an ellipse
    }
  for (int y = 696; y < H; ++y)  // the partial bottom tile row (5 rows): foreground, then a gap
    for (int x = 0; x < W; ++x) m(x, y) = x < 900 || x > 940 ? 255 : 0;
  for (int y = 0; y < H; ++y) m(W - 1, y) = y % 97 ? 255 : 0;  // the partial right tile column (1 pixel)
  const int saved = vcar::max_threads();
  vcar::set_num_threads(1);
  MaskTiles one;
  one.build(m);
  vcar::set_num_threads(std::max(2, saved));
  MaskTiles many;
  many.build(m);
  vcar::set_num_threads(saved);
  int answers[3] = {0, 0, 0};
  for (int ty = 0; ty * 8 < H; ++ty)  // every tile, exactly
    for (int tx = 0; tx * 8 < W; ++tx) {
      const int want = brute(m, tx * 8, ty * 8, tx * 8 + 7, ty * 8 + 7);
      CHECK(static_cast<int>(one.classify(tx * 8, ty * 8, tx * 8 + 7, ty * 8 + 7)) == want);
      CHECK(static_cast<int>(many.classify(tx * 8, ty * 8, tx * 8 + 7, ty * 8 + 7)) == want);
      ++answers[want];
    }
  CHECK(answers[0] > 0);
  CHECK(answers[1] > 0);
  CHECK(answers[2] > 0);
  // Rectangles of whole tiles spanning many rows and columns: exact as well.
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> TX(0, (W + 7) / 8 - 1), TY(0, (H + 7) / 8 - 1);
  for (int k = 0; k < 300; ++k) {
    int a = TX(rng), b = TX(rng), c = TY(rng), d = TY(rng);
    if (a > b) std::swap(a, b);
    if (c > d) std::swap(c, d);
    const int want = brute(m, a * 8, c * 8, b * 8 + 7, d * 8 + 7);
    CHECK(static_cast<int>(many.classify(a * 8, c * 8, b * 8 + 7, d * 8 + 7)) == want);
  }
  CHECK(many.classify(300, 250, 660, 410) == MaskTiles::foreground);  // inside the ellipse
  CHECK(many.classify(0, 0, W - 1, H - 1) == MaskTiles::mixed);
  CHECK(many.classify(0, 696, 895, H - 1) == MaskTiles::foreground);      // partial tiles, all foreground
  CHECK(many.classify(W - 1, 8, W - 1, 95) == MaskTiles::foreground);
  CHECK(many.classify(W - 8, H - 5, W - 1, H - 1) == MaskTiles::foreground);  // the corner tile
}

TEST_CASE("MaskTiles: counts kept in 16-bit halves stay exact past 65535 tiles; larger rectangles are mixed") {
  // 2400 x 2056 px: 300 x 257 = 77100 tiles, so the integral counts wrap around 2^16.
  const int W = 2400, H = 2056, TW = W / 8, TH = H / 8;
  Mask m(W, H, 1, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float dx = static_cast<float>(x - 1300), dy = static_cast<float>(y - 1000);
      m(x, y) = dx * dx / (1000.f * 1000.f) + dy * dy / (900.f * 900.f) < 1.f || y < 300 ? 255 : 0;
    }
  MaskTiles t;
  t.build(m);
  // Each tile's content by brute force, then any rectangle of whole tiles from those.
  std::vector<int> tile(static_cast<std::size_t>(TW) * TH);
  for (int ty = 0; ty < TH; ++ty)
    for (int tx = 0; tx < TW; ++tx) tile[static_cast<std::size_t>(ty) * TW + tx] = brute(m, tx * 8, ty * 8, tx * 8 + 7, ty * 8 + 7);
  auto rect = [&](int a, int c, int b, int d) {  // tiles [a, b] x [c, d]
    bool fg = false, bg = false;
    for (int ty = c; ty <= d; ++ty)
      for (int tx = a; tx <= b; ++tx) {
        const int v = tile[static_cast<std::size_t>(ty) * TW + tx];
        fg = fg || v != 0;
        bg = bg || v != 2;
      }
    return fg && bg ? 1 : fg ? 2 : 0;
  };
  std::mt19937 rng(8);
  std::uniform_int_distribution<int> TX(0, TW - 1), TY(0, TH - 1);
  int answers[3] = {0, 0, 0}, large = 0;
  for (int k = 0; k < 400; ++k) {
    int a = TX(rng), b = TX(rng), c = TY(rng), d = TY(rng);
    if (a > b) std::swap(a, b);
    if (c > d) std::swap(c, d);
    if ((b - a + 1) * (d - c + 1) > 65535) continue;
    large += (b - a + 1) * (d - c + 1) > 20000;
    const int want = rect(a, c, b, d);
    ++answers[want];
    CHECK(static_cast<int>(t.classify(a * 8, c * 8, b * 8 + 7, d * 8 + 7)) == want);
  }
  CHECK(answers[0] > 0);
  CHECK(answers[1] > 0);
  CHECK(answers[2] > 0);
  CHECK(large > 10);
  // All foreground: 255 x 257 = 65535 tiles are foreground; 256 x 256 = 65536 tiles (a count of
  // 2^16, 0 in 16 bits) are mixed, never background.
  t.build(Mask(W, H, 1, 255));
  CHECK(t.classify(0, 0, 255 * 8 - 1, 257 * 8 - 1) == MaskTiles::foreground);
  CHECK(t.classify(0, 0, 256 * 8 - 1, 256 * 8 - 1) == MaskTiles::mixed);
  CHECK(t.classify(0, 0, W - 1, H - 1) == MaskTiles::mixed);
  t.build(Mask(W, H, 1, 0));
  CHECK(t.classify(0, 0, 255 * 8 - 1, 257 * 8 - 1) == MaskTiles::background);
  CHECK(t.classify(0, 0, W - 1, H - 1) == MaskTiles::mixed);
}

TEST_CASE("MaskTiles: packed bits, one 64-bit word per 8 x 8 tile, equal the mask and are 0 past its edges") {
  std::mt19937 rng(9);
  for (auto [W, H] : {std::pair{64, 48}, std::pair{37, 29}, std::pair{8, 1}, std::pair{1000, 700}}) {
    Mask m(W, H, 1, 0);
    std::bernoulli_distribution fg(0.4);
    for (auto& b : m.data) b = fg(rng) ? static_cast<std::uint8_t>(1 + rng() % 255) : 0;  // any nonzero value
    MaskTiles t;
    t.build(m);  // 1000 x 700 packs its tile rows in parallel
    const int tw = (W + 7) / 8, th = (H + 7) / 8;
    REQUIRE(t.tiles_x() == tw);
    std::size_t wrong = 0;
    for (int ty = 0; ty < th; ++ty)
      for (int tx = 0; tx < tw; ++tx)
        for (int b = 0; b < 64; ++b) {  // bit (y % 8) * 8 + x % 8 of word ty * tw + tx
          const int x = tx * 8 + b % 8, y = ty * 8 + b / 8;
          const bool want = x < W && y < H && m(x, y) != 0;
          const bool got = (t.words()[static_cast<std::size_t>(ty) * tw + tx] >> b) & 1u;
          wrong += got != want;
        }
    INFO(W << "x" << H);
    CHECK(wrong == 0);
  }
  // Hand value: pixel (9, 10) of a 16 x 16 mask is tile (1, 1) = word 3, bit 2 * 8 + 1 = 17.
  Mask one(16, 16, 1, 0);
  one(9, 10) = 255;
  MaskTiles t;
  t.build(one);
  CHECK(t.words()[3] == (std::uint64_t{1} << 17));
  CHECK(t.words()[0] == 0);
  CHECK(t.words()[1] == 0);
  CHECK(t.words()[2] == 0);
}

TEST_CASE("MaskTiles built from a run-length encoded mask equals the one built from its pixels") {
  std::mt19937 rng(12);
  for (auto [W, H] : {std::pair{64, 48}, std::pair{37, 29}, std::pair{8, 1}, std::pair{1, 9}, std::pair{1001, 701}}) {
    for (int pattern = 0; pattern < 4; ++pattern) {
      Mask m(W, H, 1, 0);
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          const float dx = static_cast<float>(x) - 0.45f * static_cast<float>(W), dy = static_cast<float>(y) - 0.5f * static_cast<float>(H);
          const bool blob = dx * dx / (0.16f * static_cast<float>(W * W)) + dy * dy / (0.1f * static_cast<float>(H * H)) < 1.f;
          switch (pattern) {
            case 0: m(x, y) = blob ? 255 : 0; break;                              // a blob
            case 1: m(x, y) = rng() % 3 == 0 ? 9 : 0; break;                     // noise: short runs, any nonzero value
            case 2: m(x, y) = 255; break;                                        // all foreground: one run over every row
            case 3: m(x, y) = (blob != (x > W / 2)) || y == H - 1 ? 255 : 0; break;  // runs across row ends
          }
        }
      MaskTiles from_pixels, from_runs;
      from_pixels.build(m);
      from_runs.build(vcar::RleMask::encode(m));
      INFO(W << "x" << H << " pattern " << pattern);
      REQUIRE(from_runs.tiles_x() == from_pixels.tiles_x());
      const std::size_t words = static_cast<std::size_t>(from_pixels.tiles_x()) * static_cast<std::size_t>((H + 7) / 8);
      CHECK(std::equal(from_runs.words(), from_runs.words() + words, from_pixels.words()));
      std::uniform_int_distribution<int> X(-3, W + 2), Y(-3, H + 2);
      int differ = 0;
      for (int k = 0; k < 500; ++k) {
        int x0 = X(rng), x1 = X(rng), y0 = Y(rng), y1 = Y(rng);
        if (x0 > x1) std::swap(x0, x1);
        if (y0 > y1) std::swap(y0, y1);
        differ += from_runs.classify(x0, y0, x1, y1) != from_pixels.classify(x0, y0, x1, y1);
      }
      CHECK(differ == 0);
    }
  }
  MaskTiles t;  // rebuilt in place, from a larger mask to an empty one
  t.build(vcar::RleMask::encode(Mask(1001, 701, 1, 255)));
  t.build(vcar::RleMask::encode(Mask(10, 10, 1, 0)));
  CHECK(t.classify(0, 0, 9, 9) == MaskTiles::background);
  for (auto [W, H] : {std::pair{0, 5}, std::pair{5, 0}, std::pair{0, 0}}) {  // no pixels: background everywhere
    const Mask none(W, H, 1, 0);
    t.build(none);
    CHECK(t.classify(0, 0, 4, 4) == MaskTiles::background);
    t.build(vcar::RleMask::encode(none));
    CHECK(t.classify(0, 0, 4, 4) == MaskTiles::background);
  }
}

TEST_CASE("MaskTiles::pixels: a batch of lookups equals the mask's bytes") {
  using BI = vcar::simd::batch<std::int32_t>;
  constexpr std::size_t L = BI::size;
  std::mt19937 rng(9);
  for (auto [W, H] : {std::pair{64, 48}, std::pair{37, 29}, std::pair{301, 203}}) {
    Mask m(W, H, 1, 0);
    for (auto& v : m.data) v = rng() % 3 == 0 ? static_cast<std::uint8_t>(1 + rng() % 255) : 0;
    MaskTiles t;
    t.build(m);
    int mismatches = 0, foreground = 0;
    for (int trial = 0; trial < 500; ++trial) {
      alignas(64) std::int32_t u[L], v[L], got[L];
      for (std::size_t l = 0; l < L; ++l) {
        u[l] = static_cast<std::int32_t>(rng() % W);
        v[l] = static_cast<std::int32_t>(rng() % H);
        if (trial == 0 && l < 4) u[l] = (l & 1) ? W - 1 : 0, v[l] = (l & 2) ? H - 1 : 0;  // the corners
      }
      t.pixels(BI::load_aligned(u), BI::load_aligned(v)).store_aligned(got);
      for (std::size_t l = 0; l < L; ++l) {
        mismatches += got[l] != (m(u[l], v[l]) != 0 ? 1 : 0);
        foreground += got[l];
      }
    }
    CHECK(foreground > 100);
    CHECK(mismatches == 0);
  }
}

TEST_CASE("mask_at on tiles for a batch of points equals mask_at on the mask, outside and NaN included") {
  using BF = vcar::simd::batch<float>;
  constexpr std::size_t L = BF::size;
  std::mt19937 rng(10);
  std::uniform_real_distribution<float> U(-3.f, 40.f);
  Mask m(37, 29, 1, 0);
  for (auto& v : m.data) v = rng() % 2 ? 255 : 0;
  MaskTiles t;
  t.build(m);
  int mismatches = 0, inside_fg = 0;
  for (int trial = 0; trial < 400; ++trial) {
    alignas(64) float u[L], v[L];
    alignas(64) std::int32_t got[L];
    for (std::size_t l = 0; l < L; ++l) u[l] = U(rng), v[l] = U(rng);
    if (trial == 0) u[0] = NAN, v[1] = NAN, u[2] = 37.f, v[3] = 28.999f;  // NaN, the right edge, just inside
    vcar::mask_at(t, BF::load_aligned(u), BF::load_aligned(v)).store_aligned(got);
    for (std::size_t l = 0; l < L; ++l) {
      mismatches += got[l] != (vcar::mask_at(m, u[l], v[l]) ? 1 : 0);
      inside_fg += got[l];
    }
  }
  CHECK(inside_fg > 100);
  CHECK(mismatches == 0);
}
