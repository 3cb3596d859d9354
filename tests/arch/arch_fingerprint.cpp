// Cross-target check: runs the whole pipeline and the CPU renderer on the test scenes and writes
// what they produce (selections exactly, floats as hex) so that builds for different
// instruction sets (SSE2, AVX2, AVX-512, NEON, scalar) can be compared:
//
//   vcar_arch_fingerprint --out FILE          run and write
//   vcar_arch_fingerprint --compare REF FILE  exit 1 when a selection (or any integer) differs;
//                                             print, per float array, how much the floats differ
//
// Scenes: the synthetic world of tests/determinism (oracle masks) and the two real trained
// scenes of tests/data (donut.ply, train-1000.ply) seen by an orbit of cameras, the target a
// fixed half of the scene, masked by rendering it (alpha > 0.5). Every run forces the spiral
// views, so every stage (votes, sphere, view completeness, SSS, fine vote, ABR) contributes;
// each scene runs the paper's preset (nvos) and the default (robust).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/simd.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

struct Record {
  char kind = 'f';  // 'i': must match exactly; 'f': floats, differences are measured
  std::vector<std::int64_t> ints;
  std::vector<float> floats;
};
using Fingerprint = std::map<std::string, Record>;

void put_ints(Fingerprint& fp, const std::string& key, const std::vector<std::int64_t>& v) {
  fp[key] = Record{'i', v, {}};
}
void put_floats(Fingerprint& fp, const std::string& key, const std::vector<float>& v) {
  fp[key] = Record{'f', {}, v};
}

void put_result(Fingerprint& fp, const std::string& name, const vcar::SegmentationResult& r,
                const vcar::GaussianScene& scene, const vcar::Camera& view, vcar::cpu::TiledRenderer& renderer) {
  put_ints(fp, name + ".indices", std::vector<std::int64_t>(r.indices.begin(), r.indices.end()));
  put_ints(fp, name + ".sss_triggered", {r.diagnostics.sss_triggered ? 1 : 0});
  const vcar::Diagnostics& d = r.diagnostics;
  put_ints(fp, name + ".stage_sizes", {static_cast<std::int64_t>(d.n_coarse), static_cast<std::int64_t>(d.n_fine),
                                       static_cast<std::int64_t>(d.valid_cameras),
                                       static_cast<std::int64_t>(d.abr_flagged),
                                       static_cast<std::int64_t>(d.abr_compressed)});
  std::vector<float> sampled;
  for (const vcar::Camera& c : d.sampled_cameras)
    for (int k = 0; k < 3; ++k) sampled.push_back(c.t_w[k]);
  put_floats(fp, name + ".sampled_camera_t", sampled);
  put_floats(fp, name + ".scores", r.scores);
  for (int d = 0; d < 3; ++d) put_floats(fp, name + ".log_scale" + std::to_string(d), r.log_scale[d]);
  put_floats(fp, name + ".max_gap_deg", {static_cast<float>(r.diagnostics.max_gap_deg)});
  vcar::RenderRequest q;
  q.scene = &scene;
  q.camera = &view;
  q.subset = &r.indices;
  q.log_scale = &r.log_scale;
  put_floats(fp, name + ".selection_alpha", renderer.render(q).alpha.data);
}

vcar::VcarParams all_stages(vcar::VcarParams p) {
  p.force_sss = true;  // every stage runs, whatever the gap
  p.K = 500;
  p.S1 = 2;
  return p;
}

void synthetic_scene(Fingerprint& fp) {
  vcar::synth::WorldParams wp;
  wp.seed = 7;
  wp.n_gaussians = 12000;
  const vcar::synth::World world = vcar::synth::generate_world(wp);
  vcar::synth::RigParams rp;
  rp.intrinsics = vcar::synth::make_intrinsics(96, 72);
  rp.n_train = 6;
  rp.n_eval = 1;
  const vcar::synth::Rig rig = vcar::synth::make_rig("forward", world, rp);
  vcar::cpu::TiledRenderer renderer;
  vcar::synth::OracleSegmenter oracle(world, {}, renderer);
  vcar::Prompt prompt;
  prompt.reference_view = rig.reference;
  const auto r = vcar::segment(world.scene, rig.train, prompt, renderer, oracle, all_stages(vcar::VcarParams::nvos()));
  put_result(fp, "synth.nvos", r, world.scene, rig.eval.front(), renderer);
  // The default preset (vcar::segment without parameters) as well.
  const auto d = vcar::segment(world.scene, rig.train, prompt, renderer, oracle, all_stages(vcar::VcarParams::robust()));
  put_result(fp, "synth.robust", d, world.scene, rig.eval.front(), renderer);

  vcar::RenderRequest q;
  q.scene = &world.scene;
  q.camera = &rig.train.front();
  q.want_depth = true;
  const vcar::RenderOutput out = renderer.render(q);
  put_floats(fp, "synth.render.rgb", out.rgb.data);
  put_floats(fp, "synth.render.alpha", out.alpha.data);
  put_floats(fp, "synth.render.depth", out.depth.data);
}

// A real scene: orbit cameras around the median of the means; the target is the half of the
// scene with x above the median; its masks are its own render (alpha > 0.5).
void real_scene(Fingerprint& fp, const std::string& name, const std::string& file) {
  const vcar::GaussianScene scene = vcar::io::read_ply(file);
  const std::size_t n = scene.size();
  auto median = [&](int d) {
    std::vector<float> v(scene.mean[d].begin(), scene.mean[d].end());
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2), v.end());
    return v[n / 2];
  };
  const Eigen::Vector3f c(median(0), median(1), median(2));
  std::vector<float> dist(n);
  for (std::size_t i = 0; i < n; ++i)
    dist[i] = (Eigen::Vector3f(scene.mean[0][i], scene.mean[1][i], scene.mean[2][i]) - c).norm();
  std::nth_element(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(n / 2), dist.end());
  const float radius = 3.f * dist[n / 2];
  std::vector<vcar::Index> target;
  for (std::size_t i = 0; i < n; ++i)
    if (scene.mean[0][i] > c.x()) target.push_back(static_cast<vcar::Index>(i));

  const int W = 128, H = 96;
  const vcar::Intrinsics k{W, H, 110.f, 110.f, W / 2.f, H / 2.f};
  std::vector<vcar::Camera> cams;
  for (int v = 0; v < 10; ++v) {
    const float a = 2.f * std::numbers::pi_v<float> * static_cast<float>(v) / 10.f, e = 0.5f;
    const Eigen::Vector3f eye = c + radius * Eigen::Vector3f(std::cos(a) * std::cos(e), -std::sin(e), std::sin(a) * std::cos(e));
    cams.push_back(vcar::Camera::look_at(eye, c, {0.f, -1.f, 0.f}, k, "orbit_" + std::to_string(v)));
  }
  vcar::cpu::TiledRenderer renderer;
  vcar::cpu::TiledRenderer mask_renderer;
  auto segmenter = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> masks(f.size());
    for (std::size_t j = 0; j < f.size(); ++j) {
      vcar::RenderRequest q;
      q.scene = &scene;
      q.camera = &f.cameras[j];
      q.subset = &target;
      const vcar::ImageF alpha = mask_renderer.render(q).alpha;
      vcar::Mask m(alpha.width, alpha.height);
      for (std::size_t p = 0; p < m.data.size(); ++p) m.data[p] = alpha.data[p] > 0.5f ? 255 : 0;
      masks[j] = std::move(m);
    }
    return masks;
  });
  vcar::Prompt prompt;
  prompt.reference_view = 0;
  const auto r = vcar::segment(scene, cams, prompt, renderer, segmenter, all_stages(vcar::VcarParams::nvos()));
  put_result(fp, name + ".nvos", r, scene, cams[3], renderer);
  const auto d = vcar::segment(scene, cams, prompt, renderer, segmenter, all_stages(vcar::VcarParams::robust()));
  put_result(fp, name + ".robust", d, scene, cams[3], renderer);

  vcar::RenderRequest q;
  q.scene = &scene;
  q.camera = &cams[1];
  q.want_depth = true;
  const vcar::RenderOutput out = renderer.render(q);
  put_floats(fp, name + ".render.rgb", out.rgb.data);
  put_floats(fp, name + ".render.alpha", out.alpha.data);
  put_floats(fp, name + ".render.depth", out.depth.data);
}

void write(const Fingerprint& fp, const std::string& path) {
  std::ofstream out(path);
  out << "isa " << vcar::simd::isa_name() << " " << vcar::simd::width << "\n";
  for (const auto& [key, rec] : fp) {
    out << key << ' ' << rec.kind << ' ' << (rec.kind == 'i' ? rec.ints.size() : rec.floats.size());
    char buf[32];
    if (rec.kind == 'i')
      for (auto v : rec.ints) out << ' ' << v;
    else
      for (float v : rec.floats) {
        std::snprintf(buf, sizeof buf, " %a", static_cast<double>(v));
        out << buf;
      }
    out << '\n';
  }
  if (!out) throw vcar::Error("cannot write", path);
}

Fingerprint read(const std::string& path, std::string& isa) {
  std::ifstream in(path);
  if (!in) throw vcar::Error("cannot read", path);
  Fingerprint fp;
  std::string line;
  std::getline(in, isa);
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string key, tok;
    Record rec;
    std::size_t n = 0;
    s >> key >> rec.kind >> n;
    for (std::size_t k = 0; k < n && (s >> tok); ++k) {
      if (rec.kind == 'i') rec.ints.push_back(std::stoll(tok));
      else rec.floats.push_back(std::strtof(tok.c_str(), nullptr));
    }
    fp[key] = std::move(rec);
  }
  return fp;
}

// Selections and counts must match; floats: largest absolute difference, largest difference
// relative to max(|a|, |b|) over elements with max(|a|, |b|) >= 1e-3, and how many differ.
int compare(const std::string& ref_path, const std::string& path) {
  std::string isa_ref, isa;
  const Fingerprint a = read(ref_path, isa_ref), b = read(path, isa);
  std::printf("reference: %s\ncompared:  %s\n", isa_ref.c_str(), isa.c_str());
  int failures = 0;
  for (const auto& [key, ra] : a) {
    const auto it = b.find(key);
    if (it == b.end()) {
      std::printf("MISSING  %s\n", key.c_str());
      ++failures;
      continue;
    }
    const Record& rb = it->second;
    if (ra.kind == 'i') {
      const bool same = ra.ints == rb.ints;
      std::printf("%-8s %-34s %zu values\n", same ? "same" : "DIFFERS", key.c_str(), ra.ints.size());
      failures += same ? 0 : 1;
      continue;
    }
    if (ra.floats.size() != rb.floats.size()) {
      std::printf("DIFFERS  %-34s size %zu vs %zu\n", key.c_str(), ra.floats.size(), rb.floats.size());
      ++failures;
      continue;
    }
    double max_abs = 0, max_rel = 0;
    std::size_t differ = 0;
    for (std::size_t k = 0; k < ra.floats.size(); ++k) {
      const double x = ra.floats[k], y = rb.floats[k];
      if (std::memcmp(&ra.floats[k], &rb.floats[k], sizeof(float)) == 0) continue;
      ++differ;
      const double d = std::abs(x - y), m = std::max(std::abs(x), std::abs(y));
      max_abs = std::max(max_abs, d);
      if (m >= 1e-3) max_rel = std::max(max_rel, d / m);
    }
    std::printf("%-8s %-34s %zu of %zu differ, max abs %.3g, max rel %.3g\n", differ ? "floats" : "same",
                key.c_str(), differ, ra.floats.size(), max_abs, max_rel);
  }
  std::printf("%s\n", failures ? "FAILED: selections differ" : "selections identical");
  return failures ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> args(argv + 1, argv + argc);
    if (args.size() == 3 && args[0] == "--compare") return compare(args[1], args[2]);
    if (args.size() == 2 && args[0] == "--out") {
      Fingerprint fp;
      synthetic_scene(fp);
      real_scene(fp, "donut", std::string(VCAR_TEST_DATA_DIR) + "/donut.ply");
      real_scene(fp, "train1000", std::string(VCAR_TEST_DATA_DIR) + "/train-1000.ply");
      write(fp, args[1]);
      std::printf("%s: %zu records (%s, %zu float lanes)\n", args[1].c_str(), fp.size(), vcar::simd::isa_name(),
                  vcar::simd::width);
      return 0;
    }
    std::fprintf(stderr, "usage: vcar_arch_fingerprint --out FILE | --compare REF FILE\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vcar_arch_fingerprint: %s\n", e.what());
    return 1;
  }
}
