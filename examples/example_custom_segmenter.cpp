// example_custom_segmenter: a host that brings its own mask source and its own renderer, plugged
// in through lambdas (no inheritance, no vcar types to derive from).
//
//  - "batch" segmenter (make_segmenter): returns every frame's mask at once, as a host that
//    posts all frames to a SAM server and waits would;
//  - "streaming" segmenter (make_streaming_segmenter): answers frame by frame through the sink,
//    looks at the rendered pixels (frames.image(k)) and skips frames that show nothing;
//  - renderer (make_renderer / make_contribution_renderer): wraps vcar::cpu::TiledRenderer
//    exactly as a CUDA host would wrap its own splatter, and counts what it is asked for.
// Both segmenters answer from the synthetic world's ground truth, so the two runs must agree.
#include <cstdio>
#include <optional>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

int main() try {
  vcar::synth::WorldParams wp;
  wp.seed = 3;
  wp.n_gaussians = 20000;
  const vcar::synth::World world = vcar::synth::generate_world(wp);
  const vcar::synth::Rig rig = vcar::synth::make_rig("hemisphere", world);

  // ---- The host's renderer: any callable RenderOutput(const RenderRequest&). ----------------
  vcar::cpu::TiledRenderer splatter;  // stands in for the host's own (e.g. CUDA) rasteriser
  std::size_t renders = 0, drawn = 0;
  auto renderer = vcar::make_renderer([&](const vcar::RenderRequest& q) {
    ++renders;
    drawn += q.subset ? q.subset->size() : q.scene->size();
    return splatter.render(q);  // must honour subset, log_scale, background, want_depth
  });
  static_assert(vcar::Renderer<decltype(renderer)>);
  // The peers' methods also need per-Gaussian contributions: a second callable provides them.
  auto contrib = vcar::make_contribution_renderer(
      [&](const vcar::RenderRequest& q) { return splatter.render(q); },
      [&](const vcar::RenderRequest& q, const vcar::Mask& m, vcar::Contributions& c) {
        splatter.accumulate_contributions(q, m, c);
      });
  static_assert(vcar::ContributionRenderer<decltype(contrib)>);

  // The host's mask source for one camera. A real host runs SAM here; this one asks the
  // world's ground truth: visible target for training views, the whole target for the views
  // that the pipeline renders from the coarse selection only (named sss_*).
  auto host_mask = [&](const vcar::Camera& cam) {
    const bool sampled = cam.name.rfind("sss_", 0) == 0;
    return sampled ? vcar::synth::silhouette_mask(world, cam, world.target_id)
                   : vcar::synth::visible_mask(world, cam, world.target_id);
  };

  // ---- Segmenter 1: all masks at once. ------------------------------------------------------
  std::size_t batch_calls = 0;
  auto batch = vcar::make_segmenter([&](const vcar::FrameSequence& f, const vcar::Prompt&) {
    ++batch_calls;  // one call per segmentation round (coarse, then fine if the spiral ran)
    std::vector<std::optional<vcar::Mask>> masks(f.size());
    for (std::size_t k = 0; k < f.size(); ++k) masks[k] = host_mask(f.cameras[k]);
    return masks;  // an empty optional would mean "no mask" for that frame
  });
  static_assert(vcar::Segmenter<decltype(batch)>);

  // ---- Segmenter 2: streamed, one mask at a time, looking at the rendered frame. ------------
  std::size_t images = 0, skipped = 0;
  auto streaming = vcar::make_streaming_segmenter(
      [&](const vcar::FrameSequence& f, const vcar::Prompt& prompt, const vcar::MaskSink& sink) {
        for (std::size_t k = 0; k < f.size(); ++k) {
          // Frame 0 is the prompt view (conventions §4); a video model would start its memory here.
          const vcar::ImageRGB8 rgb = f.image(k);  // rendered on demand, with the background of params
          ++images;
          std::size_t lit = 0;
          for (std::uint8_t v : rgb.data) lit += v != 0;
          if (k != 0 && lit == 0) {  // nothing drawn: a segmenter could only guess
            ++skipped;
            sink(k, nullptr);
            continue;
          }
          (void)prompt;  // points / box / text, unchanged from the caller
          const vcar::Mask m = host_mask(f.cameras[k]);
          sink(k, &m);  // the pipeline copies what it needs: m may die right after
        }
      });
  static_assert(vcar::Segmenter<decltype(streaming)>);

  vcar::Prompt prompt;
  prompt.reference_view = rig.reference;
  prompt.text = "the target";  // passed through unchanged
  const vcar::VcarParams params = vcar::VcarParams::nvos();

  const vcar::SegmentationResult a = vcar::segment(world.scene, rig.train, prompt, renderer, batch, params);
  const std::size_t renders_batch = renders;
  const vcar::SegmentationResult b = vcar::segment(world.scene, rig.train, prompt, renderer, streaming, params);

  std::printf("scene: %zu Gaussians, %zu training views (hemisphere capture), target %zu Gaussians\n",
              world.scene.size(), rig.train.size(), world.gaussians_of(world.target_id).size());
  std::printf("batch segmenter:     %zu rounds, selected %zu (coarse %zu), spiral %s, %zu renders\n",
              batch_calls, a.indices.size(), a.diagnostics.n_coarse,
              a.diagnostics.sss_triggered ? "sampled" : "skipped", renders_batch);
  std::printf("streaming segmenter: %zu frames rendered (%zu skipped as empty), selected %zu, %zu renders\n",
              images, skipped, b.indices.size(), renders - renders_batch);
  std::printf("renderer drew %zu Gaussians in total over %zu renders\n", drawn, renders);

  // Contributions of the reference view (what FlashSplat-like peers accumulate).
  vcar::RenderRequest q;
  q.scene = &world.scene;
  q.camera = &rig.train[rig.reference];
  vcar::Contributions c;
  contrib.accumulate_contributions(q, host_mask(*q.camera), c);
  double w = 0, wfg = 0;
  for (std::size_t i = 0; i < c.weight.size(); ++i) { w += c.weight[i]; wfg += c.weight_fg[i]; }
  std::printf("reference view: sum alpha T = %.1f px, inside the mask %.1f px\n", w, wfg);

  // Same masks for every frame that was not skipped: with nothing skipped, the same selection.
  const bool same = a.indices == b.indices;
  std::printf("%s\n", same ? "the two segmenters agree" : "the two segmenters differ");
  return !a.indices.empty() && (same || skipped > 0) ? 0 : 1;
} catch (const vcar::Error& e) {
  std::fprintf(stderr, "error: %s\n", e.what());  // what() already names e.where()
  return 1;
}
