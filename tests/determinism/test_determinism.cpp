// Determinism: the full pipeline (CPU backend, oracle segmenter, synthetic world, SSS and ABR
// forced on) gives bit-identical selections, scores, refined log-scales, renders and written
// PLY bytes across repeated runs and across thread counts 1, 2 and 5.
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

namespace fs = std::filesystem;

struct Run {
  std::vector<vcar::Index> indices;
  std::vector<float> scores;
  vcar::LogScales log_scale;
  std::vector<float> alpha;   // render of the selection with refined scales
  std::string ply;            // bytes of the written selection
  bool sss = false;
  std::size_t compressed = 0;
};

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Fixture {
  vcar::synth::World world;
  vcar::synth::Rig rig;
  Fixture() {
    vcar::synth::WorldParams wp;
    wp.seed = 7;
    wp.n_gaussians = 12000;
    world = vcar::synth::generate_world(wp);
    vcar::synth::RigParams rp;
    rp.intrinsics = vcar::synth::make_intrinsics(96, 72);
    rp.n_train = 6;
    rp.n_eval = 1;
    rig = vcar::synth::make_rig("forward", world, rp);
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

Run run_pipeline(int threads, const fs::path& out_ply) {
  const Fixture& f = fixture();
  vcar::set_num_threads(threads);
  vcar::cpu::TiledRenderer renderer;
  vcar::synth::OracleSegmenter oracle(f.world, {}, renderer);
  vcar::Prompt prompt;
  prompt.reference_view = f.rig.reference;
  vcar::VcarParams params = vcar::VcarParams::nvos();
  params.force_sss = true;  // exercise every stage, whatever the gap
  params.K = 500;
  params.S1 = 2;
  const vcar::SegmentationResult r = vcar::segment(f.world.scene, f.rig.train, prompt, renderer, oracle, params);
  Run run;
  run.indices = r.indices;
  run.scores = r.scores;
  run.log_scale = r.log_scale;
  run.sss = r.diagnostics.sss_triggered;
  run.compressed = r.diagnostics.abr_compressed;
  vcar::RenderRequest q;
  q.scene = &f.world.scene;
  q.camera = &f.rig.eval.front();
  q.subset = &run.indices;
  q.log_scale = &run.log_scale;
  run.alpha = renderer.render(q).alpha.data;
  vcar::io::write_ply(out_ply, f.world.scene, run.indices, &run.log_scale);
  run.ply = slurp(out_ply);
  vcar::set_num_threads(vcar::max_threads());
  return run;
}

}  // namespace

TEST_CASE("pipeline output is bit-identical across runs and thread counts", "[determinism]") {
  const fs::path dir = fs::temp_directory_path() / "vcar_test_determinism";
  fs::create_directories(dir);
  const int original = vcar::max_threads();
  const Run base = run_pipeline(1, dir / "t1.ply");
  vcar::set_num_threads(original);
  // The run must be non-trivial for the comparison to mean anything.
  REQUIRE(base.sss);
  REQUIRE(!base.indices.empty());
  REQUIRE(base.log_scale[0].size() == base.indices.size());
  REQUIRE(base.ply.size() > 200);

  for (int threads : {1, 2, 5}) {
    for (int repeat = 0; repeat < (threads == 2 ? 2 : 1); ++repeat) {
      INFO("threads " << threads << ", repeat " << repeat);
      const Run r = run_pipeline(threads, dir / ("t" + std::to_string(threads) + ".ply"));
      CHECK(r.indices == base.indices);
      CHECK(same_bits(r.scores, base.scores));
      for (int d = 0; d < 3; ++d) CHECK(same_bits(r.log_scale[d], base.log_scale[d]));
      CHECK(r.compressed == base.compressed);
      CHECK(same_bits(r.alpha, base.alpha));
      CHECK(r.ply == base.ply);
    }
  }
  vcar::set_num_threads(original);
  fs::remove_all(dir);
}

TEST_CASE("CPU renderer is bit-identical across thread counts", "[determinism]") {
  const Fixture& f = fixture();
  const int original = vcar::max_threads();
  vcar::cpu::TiledRenderer renderer;
  std::vector<float> rgb1, alpha1, depth1;
  for (int threads : {1, 2, 5}) {
    vcar::set_num_threads(threads);
    vcar::RenderRequest q;
    q.scene = &f.world.scene;
    q.camera = &f.rig.train.front();
    q.want_depth = true;
    const vcar::RenderOutput out = renderer.render(q);
    if (threads == 1) {
      rgb1 = out.rgb.data;
      alpha1 = out.alpha.data;
      depth1 = out.depth.data;
      REQUIRE(!rgb1.empty());
      continue;
    }
    INFO("threads " << threads);
    CHECK(same_bits(out.rgb.data, rgb1));
    CHECK(same_bits(out.alpha.data, alpha1));
    CHECK(same_bits(out.depth.data, depth1));
  }
  vcar::set_num_threads(original);
}
