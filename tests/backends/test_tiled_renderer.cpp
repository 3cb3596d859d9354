#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "vcar/backends/cpu/tiled_renderer.hpp"

namespace {

using vcar::Index;

// Brute force: every pixel against every drawn Gaussian, no tiles, double precision, the
// compositing rules of conventions §3. Projections come from the renderer's batch projection,
// one Gaussian at a time (tests/backends/test_batch_projection.cpp checks it against
// vcar::project_gaussian): a last-bit difference there can flip a pixel's stop test (T <= 1e-4)
// and move its depth by up to 1e-4 z, more than this test's bounds, so this test checks the
// culling, binning and compositing of the same splats.
struct BruteForce {
  std::vector<double> rgb, alpha, depth;  // W*H*3, W*H, W*H
  std::vector<double> weight, weight_fg;  // per scene index
};

BruteForce brute_force(const vcar::RenderRequest& q, const vcar::Mask* mask = nullptr) {
  const vcar::GaussianScene& sc = *q.scene;
  const vcar::Camera& cam = *q.camera;
  const std::size_t n = q.subset ? q.subset->size() : sc.size();
  struct G { double mx, my, a, b, c, op, z, r, g, bl; std::size_t i, k; };
  std::vector<G> gs;
  const vcar::cpu::BatchCamera bc(cam, vcar::ProjectionParams{});
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = q.subset ? (*q.subset)[k] : k;
    vcar::cpu::GaussianBatch g;  // Gaussian i in every lane
    for (int d = 0; d < 3; ++d) {
      g.mu[d] = vcar::cpu::Lane(sc.mean[d][i]);
      g.log_s[d] = vcar::cpu::Lane(q.log_scale ? (*q.log_scale)[d][k] : sc.log_scale[d][i]);
    }
    for (int c = 0; c < 4; ++c) g.q[c] = vcar::cpu::Lane(sc.rotation[c][i]);
    g.logit = vcar::cpu::Lane(sc.opacity_logit[i]);
    vcar::cpu::PackedSplat p{};
    std::uint64_t rect = 0;
    vcar::cpu::project_batch(bc, vcar::ProjectionParams{}, g, static_cast<std::uint32_t>(k), 1, &p, &rect);
    if (vcar::cpu::rect_empty(rect)) continue;  // culled
    const Eigen::Vector3f c = vcar::gaussian_rgb(sc, i, cam.position());
    gs.push_back({p.mx, p.my, p.ca, p.cb, p.cc, p.opacity, p.depth, c[0], c[1], c[2], i, k});
  }
  std::sort(gs.begin(), gs.end(), [](const G& a, const G& b) {
    return float(a.z) != float(b.z) ? a.z < b.z : a.k < b.k;
  });
  BruteForce out;
  const int W = cam.width, H = cam.height;
  out.rgb.assign(std::size_t(W) * H * 3, 0);
  out.alpha.assign(std::size_t(W) * H, 0);
  out.depth.assign(std::size_t(W) * H, 0);
  out.weight.assign(sc.size(), 0);
  out.weight_fg.assign(sc.size(), 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double px = x + 0.5, py = y + 0.5;
      const bool fg = mask && mask->data[std::size_t(y) * W + x] != 0;
      double T = 1, C[3] = {0, 0, 0}, D = 0;
      for (const G& g : gs) {
        const double dx = g.mx - px, dy = g.my - py;
        const double sigma = 0.5 * (g.a * dx * dx + g.c * dy * dy) + g.b * dx * dy;
        if (sigma < 0) continue;
        const double alpha = std::min(0.999, g.op * std::exp(-sigma));
        if (alpha < 1.0 / 255.0) continue;
        const double nT = T * (1 - alpha);
        if (nT <= 1e-4) break;  // this Gaussian is not composited (gsplat)
        const double w = alpha * T;
        C[0] += w * g.r; C[1] += w * g.g; C[2] += w * g.bl;
        D += w * g.z;
        out.weight[g.i] += w;
        if (fg) out.weight_fg[g.i] += w;
        T = nT;
      }
      const std::size_t o = std::size_t(y) * W + x;
      for (int c = 0; c < 3; ++c) out.rgb[o * 3 + c] = C[c] + q.background[c] * T;
      out.alpha[o] = 1 - T;
      out.depth[o] = D;
    }
  return out;
}

vcar::Camera random_view_camera(int W, int H) {
  vcar::Intrinsics k{W, H, 0.9f * W, 0.9f * W, 0.5f * W + 1.3f, 0.5f * H - 0.7f};
  return vcar::Camera::look_at(Eigen::Vector3f(0.2f, -0.3f, -3.f), Eigen::Vector3f(0, 0, 0),
                               Eigen::Vector3f(0, -1, 0), k, "random view");
}

// Random scene in front of the camera: sizes from ~1 px to tens of px, degree-3 SH, opacities
// up to saturation, a few Gaussians right behind/past the near plane.
vcar::GaussianScene random_scene(std::size_t n, unsigned seed, const vcar::Camera& cam, int degree = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-1.f, 1.f), LS(-4.5f, -2.2f), O(-3.f, 9.f), SH(-0.25f, 0.25f);
  std::normal_distribution<float> N(0, 1);
  vcar::GaussianScene sc;
  sc.resize(n, degree);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3f mu(1.2f * U(rng), 1.0f * U(rng), 1.2f * U(rng));
    if (i % 50 == 7) mu = cam.position() + cam.forward() * (0.0095f + 0.002f * (U(rng) + 1.f)) +
                          cam.right() * 0.002f * U(rng);  // touching the near plane
    Eigen::Vector3f log_s(LS(rng), LS(rng), LS(rng));
    if (i % 50 == 7) log_s.array() -= 5.f;  // a few pixels wide that close
    sc.set(i, mu, log_s, Eigen::Vector4f(N(rng), N(rng), N(rng), N(rng)), O(rng));
    for (int k = 0; k < sc.sh_coeffs(); ++k)
      for (int c = 0; c < 3; ++c) sc.sh[(i * sc.sh_coeffs() + k) * 3 + c] = k == 0 ? 2.f * SH(rng) : SH(rng);
  }
  return sc;
}

double max_abs(const std::vector<float>& a, const std::vector<double>& b) {
  REQUIRE(a.size() == b.size());
  double m = 0;
  for (std::size_t k = 0; k < a.size(); ++k) m = std::max(m, std::abs(double(a[k]) - b[k]));
  return m;
}

// A render of q by the tiled renderer whose colour and alpha match the brute force within 1e-4.
vcar::RenderOutput render_checked(const vcar::RenderRequest& q) {
  vcar::cpu::TiledRenderer r;
  vcar::RenderOutput out = r.render(q);
  const BruteForce ref = brute_force(q);
  CHECK(max_abs(out.rgb.data, ref.rgb) <= 1e-4);
  CHECK(max_abs(out.alpha.data, ref.alpha) <= 1e-4);
  return out;
}

vcar::Mask random_mask(int W, int H) {
  vcar::Mask m(W, H, 1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) m(x, y) = ((x - W / 2) * (x - W / 2) + (y - H / 3) * (y - H / 3) < W * H / 6) ? 255 : 0;
  return m;
}

void check_contributions(const vcar::Contributions& acc, const BruteForce& ref) {
  REQUIRE(acc.weight.size() == ref.weight.size());
  double total = 0;
  for (std::size_t i = 0; i < acc.weight.size(); ++i) {
    CHECK(acc.weight[i] == Approx(ref.weight[i]).epsilon(1e-4).margin(1e-4));
    CHECK(acc.weight_fg[i] == Approx(ref.weight_fg[i]).epsilon(1e-4).margin(1e-4));
    total += ref.weight[i];
  }
  CHECK(total > 1.0);  // the scene does contribute
}

}  // namespace

TEST_CASE("tiled renderer matches the brute-force renderer on random scenes") {
  // Odd sizes: edge tiles are partial; Gaussians cross tile borders everywhere.
  const int W = 101, H = 67;
  const vcar::Camera cam = random_view_camera(W, H);
  for (unsigned seed : {1u, 2u, 3u}) {
    const vcar::GaussianScene sc = random_scene(400, seed, cam, int(seed));
    vcar::RenderRequest q;
    q.scene = &sc;
    q.camera = &cam;
    q.background = Eigen::Vector3f(0.2f, 0.7f, 1.f);
    q.want_depth = true;
    vcar::cpu::TiledRenderer r;
    const vcar::RenderOutput out = r.render(q);
    const BruteForce ref = brute_force(q);
    CHECK(max_abs(out.rgb.data, ref.rgb) <= 1e-4);
    CHECK(max_abs(out.alpha.data, ref.alpha) <= 1e-4);
    CHECK(max_abs(out.depth.data, ref.depth) <= 1e-4 * 5);  // depths are ~3: same relative accuracy
    // The scene saturates some pixels and leaves others partly open.
    CHECK(*std::max_element(out.alpha.data.begin(), out.alpha.data.end()) > 0.99f);
    CHECK(*std::min_element(out.alpha.data.begin(), out.alpha.data.end()) < 0.9f);
  }
}

TEST_CASE("subset and log-scale override render only the drawn Gaussians with new scales") {
  const int W = 80, H = 64;
  const vcar::Camera cam = random_view_camera(W, H);
  const vcar::GaussianScene sc = random_scene(300, 9, cam);
  std::vector<Index> subset;
  for (int i = 299; i > 0; i -= 3) subset.push_back(Index(i));  // any order
  vcar::LogScales ls;
  for (int d = 0; d < 3; ++d)
    for (Index i : subset) ls[d].push_back(sc.log_scale[d][i] + (d == 0 ? 0.7f : -0.2f));
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  q.subset = &subset;
  q.log_scale = &ls;
  q.want_depth = true;
  vcar::cpu::TiledRenderer r;
  const auto out = r.render(q);
  const BruteForce ref = brute_force(q);
  CHECK(max_abs(out.rgb.data, ref.rgb) <= 1e-4);
  CHECK(max_abs(out.alpha.data, ref.alpha) <= 1e-4);
  // Same as rendering a copied scene with the scales written in.
  vcar::GaussianScene copy = sc.subset(subset);
  copy.log_scale = ls;
  vcar::RenderRequest q2 = q;
  q2.scene = &copy;
  q2.subset = nullptr;
  q2.log_scale = nullptr;
  const auto out2 = r.render(q2);
  CHECK(max_abs(out2.alpha.data, std::vector<double>(out.alpha.data.begin(), out.alpha.data.end())) == 0.0);
  // And different from the whole scene.
  vcar::RenderRequest q3 = q;
  q3.subset = nullptr;
  q3.log_scale = nullptr;
  CHECK(max_abs(r.render(q3).alpha.data, ref.alpha) > 1e-2);
}

TEST_CASE("the stand-ins for infinite opacity logits render as opacity 1 and 0") {
  const int W = 80, H = 64;
  const vcar::Camera cam = random_view_camera(W, H);
  vcar::GaussianScene sc = random_scene(300, 11, cam);
  // Every third Gaussian transparent (as a file's -inf reads), every seventh opaque (+inf).
  std::vector<Index> kept;
  for (std::size_t i = 0; i < sc.size(); ++i) {
    if (i % 3 == 0) { sc.opacity_logit[i] = -std::numeric_limits<float>::infinity(); continue; }
    if (i % 7 == 0) sc.opacity_logit[i] = std::numeric_limits<float>::infinity();
    kept.push_back(Index(i));
  }
  const vcar::InfiniteOpacities n = sc.settle_infinite_opacities();
  CHECK(n.transparent == 100);
  CHECK(n.opaque == 28);  // multiples of 7 below 300 that are not multiples of 3: 43 - 15
  sc.validate();
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  const auto out = render_checked(q);
  // The transparent ones draw nothing: the same image as the scene without them.
  vcar::RenderRequest q2 = q;
  q2.subset = &kept;
  const auto out2 = vcar::cpu::TiledRenderer().render(q2);
  CHECK(max_abs(out2.alpha.data, std::vector<double>(out.alpha.data.begin(), out.alpha.data.end())) == 0.0);
  CHECK(max_abs(out2.rgb.data, std::vector<double>(out.rgb.data.begin(), out.rgb.data.end())) == 0.0);
}

TEST_CASE("contribution sums match the brute force") {
  const int W = 96, H = 70;
  const vcar::Camera cam = random_view_camera(W, H);
  const vcar::GaussianScene sc = random_scene(350, 4, cam);
  const vcar::Mask mask = random_mask(W, H);
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  vcar::cpu::TiledRenderer r;
  vcar::Contributions acc;
  r.accumulate_contributions(q, mask, acc);
  check_contributions(acc, brute_force(q, &mask));
  // accumulating a second view adds
  r.accumulate_contributions(q, mask, acc);
  const BruteForce ref = brute_force(q, &mask);
  for (std::size_t i = 0; i < sc.size(); i += 17)
    CHECK(acc.weight[i] == Approx(2 * ref.weight[i]).epsilon(1e-4).margin(2e-4));

  SECTION("with a subset and log-scales, indices stay the scene's") {
    std::vector<Index> subset = {5, 100, 17, 3, 250, 251, 252, 60};
    for (Index i = 0; i < 300; i += 4) subset.push_back(i + 1);
    vcar::LogScales ls;
    for (int d = 0; d < 3; ++d)
      for (Index i : subset) ls[d].push_back(sc.log_scale[d][i] + 0.5f);
    q.subset = &subset;
    q.log_scale = &ls;
    vcar::Contributions a2;
    r.accumulate_contributions(q, mask, a2);
    const BruteForce ref2 = brute_force(q, &mask);
    check_contributions(a2, ref2);
    CHECK(a2.weight[0] == 0.0);  // not drawn
  }
}

TEST_CASE("equal depths: the lower drawn index is in front") {
  const vcar::Camera cam = random_view_camera(48, 48);
  vcar::GaussianScene sc;
  sc.resize(2, 0);
  const Eigen::Vector3f mu = cam.position() + 3.f * cam.forward();
  for (int i = 0; i < 2; ++i) sc.set(i, mu, Eigen::Vector3f::Constant(-2.5f), Eigen::Vector4f(1, 0, 0, 0), 2.f);
  sc.set_rgb(0, Eigen::Vector3f(1, 0, 0));
  sc.set_rgb(1, Eigen::Vector3f(0, 0, 1));
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  vcar::cpu::TiledRenderer r;
  const auto p = vcar::project_gaussian(cam, mu, Eigen::Matrix3f::Identity(), Eigen::Vector3f::Constant(std::exp(-2.5f)), sc.opacity(0));
  const int x = int(p.mean.x()), y = int(p.mean.y());
  const auto out = r.render(q);
  CHECK(out.rgb(x, y, 0) > 2.f * out.rgb(x, y, 2));  // red (index 0) in front
  std::vector<Index> flipped = {1, 0};
  q.subset = &flipped;
  const auto out2 = r.render(q);
  CHECK(out2.rgb(x, y, 2) > 2.f * out2.rgb(x, y, 0));  // drawn index 0 is now blue
  CHECK(out2.rgb(x, y, 2) == Approx(out.rgb(x, y, 0)));
}

TEST_CASE("one thread and many threads give bit-identical results") {
  const int W = 160, H = 120;
  const vcar::Camera cam = random_view_camera(W, H);
  const vcar::GaussianScene sc = random_scene(3000, 21, cam);
  const vcar::Mask mask = random_mask(W, H);
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  q.want_depth = true;
  q.background = Eigen::Vector3f(1, 1, 1);
  const int saved = vcar::max_threads();
  vcar::set_num_threads(1);
  vcar::cpu::TiledRenderer r1;
  const auto o1 = r1.render(q);
  vcar::Contributions c1;
  r1.accumulate_contributions(q, mask, c1);
  vcar::set_num_threads(4);
  vcar::cpu::TiledRenderer r4;
  const auto o4 = r4.render(q);
  vcar::Contributions c4;
  r4.accumulate_contributions(q, mask, c4);
  vcar::set_num_threads(saved);
  CHECK(o1.rgb.data == o4.rgb.data);
  CHECK(o1.alpha.data == o4.alpha.data);
  CHECK(o1.depth.data == o4.depth.data);
  CHECK(c1.weight == c4.weight);
  CHECK(c1.weight_fg == c4.weight_fg);
  // the option form gives the same too
  vcar::cpu::TiledRenderer r3(vcar::cpu::TiledRendererOptions{{}, 3});
  CHECK(r3.render(q).rgb.data == o1.rgb.data);
}

TEST_CASE("an empty draw is the background; bad input names the culprit") {
  const vcar::Camera cam = random_view_camera(33, 20);
  const vcar::GaussianScene sc = random_scene(10, 1, cam);
  std::vector<Index> none;
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  q.subset = &none;
  q.background = Eigen::Vector3f(0.25f, 0.5f, 0.75f);
  vcar::cpu::TiledRenderer r;
  const auto out = r.render(q);
  CHECK(out.rgb(32, 19, 2) == 0.75f);
  CHECK(out.alpha(0, 0) == 0.f);
  CHECK(out.depth.empty());

  std::vector<Index> bad = {3, 10};
  q.subset = &bad;
  CHECK_THROWS_WITH(r.render(q), Catch::Contains("subset"));
  q.subset = nullptr;
  vcar::LogScales ls;
  q.log_scale = &ls;
  CHECK_THROWS_WITH(r.render(q), Catch::Contains("log_scale"));
  q.log_scale = nullptr;
  vcar::Contributions acc;
  CHECK_THROWS_WITH(r.accumulate_contributions(q, vcar::Mask(10, 10), acc), Catch::Contains("random view"));
}

namespace {
// Minimal binary little-endian PLY reader for the Inria layout (float properties only), so this
// test does not depend on the io module.
bool read_inria_ply(const std::string& path, vcar::GaussianScene& sc) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  std::string line, fmt;
  std::size_t n = 0;
  std::vector<std::string> props;
  while (std::getline(f, line)) {
    std::istringstream ls(line);
    std::string w;
    ls >> w;
    if (w == "format") ls >> fmt;
    if (w == "element") { std::string e; ls >> e >> n; }
    if (w == "property") { std::string t, name; ls >> t >> name; if (t != "float") return false; props.push_back(name); }
    if (w == "end_header") break;
  }
  if (fmt != "binary_little_endian" || n == 0) return false;
  auto col = [&](const std::string& name) {
    return int(std::find(props.begin(), props.end(), name) - props.begin());
  };
  int rest = 0;
  while (col("f_rest_" + std::to_string(rest)) < int(props.size())) ++rest;
  const int degree = rest >= 45 ? 3 : rest >= 24 ? 2 : rest >= 9 ? 1 : 0;
  sc.resize(n, degree);
  const int B = sc.sh_coeffs();
  std::vector<float> row(props.size());
  for (std::size_t i = 0; i < n; ++i) {
    f.read(reinterpret_cast<char*>(row.data()), std::streamsize(row.size() * 4));
    if (!f) return false;
    for (int d = 0; d < 3; ++d) {
      sc.mean[d][i] = row[col(std::string(1, char('x' + d)))];
      sc.log_scale[d][i] = row[col("scale_" + std::to_string(d))];
    }
    for (int c = 0; c < 4; ++c) sc.rotation[c][i] = row[col("rot_" + std::to_string(c))];
    sc.opacity_logit[i] = row[col("opacity")];
    for (int c = 0; c < 3; ++c) {
      sc.sh[(i * B) * 3 + c] = row[col("f_dc_" + std::to_string(c))];
      for (int k = 1; k < B; ++k) sc.sh[(i * B + k) * 3 + c] = row[col("f_rest_" + std::to_string(c * (B - 1) + k - 1))];
    }
  }
  return true;
}
}  // namespace

TEST_CASE("a real 3DGS file renders like the brute force (when tests/data has one)") {
  const std::string path = std::string(VCAR_TEST_DATA_DIR) + "/train-1000.ply";
  vcar::GaussianScene sc;
  if (!std::filesystem::exists(path) || !read_inria_ply(path, sc)) {
    WARN("skipped: " << path << " not present");
    return;
  }
  REQUIRE_NOTHROW(sc.validate());
  Eigen::Vector3f c = Eigen::Vector3f::Zero();
  for (std::size_t i = 0; i < sc.size(); ++i) c += sc.mu(i);
  c /= float(sc.size());
  float spread = 0;
  for (std::size_t i = 0; i < sc.size(); ++i) spread += (sc.mu(i) - c).norm();
  spread /= float(sc.size());
  vcar::Intrinsics k{96, 72, 80.f, 80.f, 48.f, 36.f};
  const vcar::Camera cam = vcar::Camera::look_at(c + Eigen::Vector3f(0, 0, -2.5f * spread), c,
                                                 Eigen::Vector3f(0, -1, 0), k, "ply view");
  vcar::RenderRequest q;
  q.scene = &sc;
  q.camera = &cam;
  const auto out = render_checked(q);
  CHECK(*std::max_element(out.alpha.data.begin(), out.alpha.data.end()) > 0.5f);
}
