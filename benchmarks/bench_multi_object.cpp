// Several objects in one run (`vcar segment --prompts`, vcar::segment_objects, algo/segment_objects.hpp)
// against one vcar::segment run per object, on the demo's synthetic scene (target and its
// neighbour, forward capture, robust preset). Two mask sources:
//  - oracle: masks ray-cast from the ground truth, never looking at the frames (one cast per
//    frame for both objects where they see the same image: the coarse round's renders of the
//    whole scene, as an image model encodes a frame once for every prompt);
//  - pixels: the same masks, but the segmenter first asks for each frame's image, as SAM or any
//    image model must (the frame is rendered for it).
// Prints wall-clock medians and minima of `repeats` runs (singles and multi interleaved) and the
// ratio multi / (sum of singles), measured in the same process; the renders, masks and
// segmenter calls of each (the multi run: the shared coarse round, then every object's fine
// round in one batched call); checks that each object's selection matches its single run up to
// the Gaussians the other object won.
//   bench_multi_object [gaussians=30000] [repeats=3] [rig=forward|orbit|sparse|hemisphere]
// Each object's fine round (its training views rendered from its own G_coarse, its sampled
// views) is its own work by design; what the objects share is the coarse round and the calls.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "vcar/algo/segment_objects.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double minimum(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

// The oracle of one object; with `pixels`, it renders each frame before answering.
struct Source {
  const vcar::synth::OracleSegmenter* oracle;
  bool pixels;
  std::size_t* masks;
  std::size_t* calls;  // segmenter calls (an external segmenter: one program start each)
  void segment(const vcar::FrameSequence& f, const vcar::Prompt&, const vcar::MaskSink& sink) {
    ++*calls;
    for (std::size_t k = 0; k < f.size(); ++k) {
      if (pixels) (void)f.image(k);
      ++*masks;
      const std::optional<vcar::Mask> m = oracle->mask(f.cameras[k], k, f.subset);
      sink(k, m ? &*m : nullptr);
    }
  }
};

// Counts the renders (the work a load-independent comparison can count).
struct CountingRenderer {
  vcar::cpu::TiledRenderer* inner;
  std::size_t renders = 0;
  vcar::RenderOutput render(const vcar::RenderRequest& q) {
    ++renders;
    return inner->render(q);
  }
};

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 30000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  vcar::synth::WorldParams wp;
  wp.seed = 1;
  wp.n_gaussians = n;
  const vcar::synth::World world = vcar::synth::generate_world(wp);
  const char* rig_name = argc > 3 ? argv[3] : "forward";
  const vcar::synth::Rig rig = vcar::synth::make_rig(rig_name, world);
  const vcar::VcarParams params = vcar::VcarParams::robust();
  vcar::cpu::TiledRenderer cpu;
  CountingRenderer renderer{&cpu};
  std::vector<vcar::synth::OracleSegmenter> oracles;
  const int ids[2] = {world.target_id, world.neighbour_id};
  for (int id : ids) {
    vcar::synth::OracleParams op;
    op.target_id = id;
    oracles.emplace_back(world, op, cpu);
  }
  std::vector<vcar::ObjectPrompt> objects(2);
  objects[0].name = "target";
  objects[1].name = "neighbour";
  for (auto& o : objects) o.prompt.reference_view = rig.reference;

  std::printf("bench_multi_object: %zu Gaussians, %zu training views (%s), robust preset, %d threads, median of %d\n",
              world.scene.size(), rig.train.size(), rig.kind.c_str(), vcar::max_threads(), repeats);
  for (bool pixels : {false, true}) {
    std::vector<double> single_t, multi_t;
    std::size_t single_renders = 0, multi_renders = 0, single_masks = 0, multi_masks = 0, single_calls = 0, multi_calls = 0;
    std::vector<vcar::SegmentationResult> singles(2);
    vcar::MultiSegmentation multi;
    for (int r = 0; r < repeats; ++r) {
      auto t = Clock::now();
      renderer.renders = 0;
      single_masks = single_calls = 0;
      for (int o = 0; o < 2; ++o) {
        Source s{&oracles[o], pixels, &single_masks, &single_calls};
        singles[o] = vcar::segment(world.scene, rig.train, objects[o].prompt, renderer, s, params);
      }
      single_t.push_back(since(t));
      single_renders = renderer.renders;
      renderer.renders = 0;
      multi_masks = multi_calls = 0;
      auto fn = vcar::make_multi_segmenter([&](const vcar::FrameSequence& f, const std::vector<vcar::ObjectRequest>& req,
                                               const vcar::ObjectMaskSink& sink) {
        ++multi_calls;
        for (std::size_t k = 0; k < f.size(); ++k) {
          if (pixels) (void)f.image(k);  // one image per frame, whatever the number of objects
          vcar::synth::OracleSegmenter::FrameCasts casts;  // one ray cast per frame for the objects that see it whole
          for (std::size_t q = 0; q < req.size(); ++q) {
            if (!req[q].covers(k)) continue;  // the batched fine round: each object its own frames
            const std::optional<vcar::Mask> m =
                oracles[req[q].object].mask(f.cameras[k], k - req[q].first_frame, f.subset, casts);
            ++multi_masks;
            sink(k, q, m ? &*m : nullptr);
          }
        }
      });
      t = Clock::now();
      multi = vcar::segment_objects(world.scene, rig.train, objects, renderer, fn, params);
      multi_t.push_back(since(t));
      multi_renders = renderer.renders;
    }
    // Each object: its single run less what the other object won.
    bool same = true;
    for (int o = 0; o < 2; ++o) {
      const auto& a = singles[o].indices;
      const auto& b = multi.objects[o].indices;
      const auto& other = multi.objects[1 - o].indices;
      std::size_t missing = 0;
      for (vcar::Index i : a)
        if (!std::binary_search(b.begin(), b.end(), i) && !std::binary_search(other.begin(), other.end(), i)) ++missing;
      for (vcar::Index i : b) same = same && std::binary_search(a.begin(), a.end(), i);
      same = same && missing == 0 && a.size() == b.size() + multi.lost[o];
    }
    // On a shared machine other jobs slow some repeats down: the minimum is the least disturbed.
    const double ts = median(single_t), tm = median(multi_t), ts0 = minimum(single_t), tm0 = minimum(multi_t);
    std::printf("%-7s two single runs %.3f s, one run of two objects %.3f s: ratio %.2f (medians; minima %.3f s, %.3f s: "
                "ratio %.2f); shared coarse round: render %.3f s, segment %.3f s, voting %.3f s; %zu conflicts; results %s\n",
                pixels ? "pixels" : "oracle", ts, tm, tm / ts, ts0, tm0, tm0 / ts0, multi.timings_s[0].second,
                multi.timings_s[1].second, multi.timings_s[2].second, multi.conflicts,
                same ? "match the single runs" : "DIFFER from the single runs");
    std::printf("        renders: two single runs %zu, one run of two objects %zu (ratio %.2f); masks asked of the segmenter: %zu, %zu; "
                "segmenter calls (external: program starts): %zu, %zu\n",
                single_renders, multi_renders, static_cast<double>(multi_renders) / static_cast<double>(single_renders),
                single_masks, multi_masks, single_calls, multi_calls);
    auto stages = [](const vcar::Diagnostics& d) {
      std::string s;
      char buf[64];
      for (const auto& [name, t] : d.timings_s) {
        std::snprintf(buf, sizeof buf, " %s %.2f", name.c_str(), t);
        s += buf;
      }
      return s;
    };
    for (int o = 0; o < 2; ++o) {
      std::printf("        %-9s single %zu selected, multi %zu (+%zu lost to the other)\n", objects[o].name.c_str(),
                  singles[o].indices.size(), multi.objects[o].indices.size(), multi.lost[o]);
      std::printf("          single run, last repeat (s):%s\n", stages(singles[o].diagnostics).c_str());
      std::printf("          multi, after the shared round (s):%s\n", stages(multi.objects[o].diagnostics).c_str());
    }
    if (!same) return 1;
  }
  return 0;
}
