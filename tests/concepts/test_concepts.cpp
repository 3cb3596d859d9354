// The minimal models of docs/concepts.md, compiled and exercised: a host application satisfies
// Renderer, ContributionRenderer and Segmenter with lambdas, no inheritance.
#include <catch2/catch.hpp>

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"

namespace {

// docs/concepts.md, "A renderer from a lambda"
auto flat_renderer() {
  return vcar::make_renderer([](const vcar::RenderRequest& q) {
    vcar::RenderOutput out;
    out.rgb = vcar::ImageF(q.camera->width, q.camera->height, 3, 0.5f);
    out.alpha = vcar::ImageF(q.camera->width, q.camera->height, 1, 1.f);
    return out;
  });
}
static_assert(vcar::Renderer<decltype(flat_renderer())>);
static_assert(!vcar::ContributionRenderer<decltype(flat_renderer())>);

// A struct model: any type with the member works.
struct CountingRenderer {
  int calls = 0;
  vcar::RenderOutput render(const vcar::RenderRequest&) { ++calls; return {}; }
  void accumulate_contributions(const vcar::RenderRequest& q, const vcar::Mask&, vcar::Contributions& c) {
    c.weight.assign(q.scene->size(), 1.0);
  }
};
static_assert(vcar::ContributionRenderer<CountingRenderer>);

// docs/concepts.md, "A segmenter from a lambda": masks a fixed box in every frame but the last.
auto box_segmenter() {
  return vcar::make_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> masks(f.size());
    for (std::size_t k = 0; k + 1 < f.size(); ++k) {
      vcar::Mask m(f.cameras[k].width, f.cameras[k].height, 1);
      m(1, 1) = 255;
      masks[k] = std::move(m);
    }
    return masks;
  });
}
static_assert(vcar::Segmenter<decltype(box_segmenter())>);

struct NotASegmenter {};
static_assert(!vcar::Segmenter<NotASegmenter>);
static_assert(!vcar::Renderer<NotASegmenter>);

}  // namespace

TEST_CASE("lambda segmenters stream one answer per frame, null for no mask") {
  std::vector<vcar::Camera> cams(3);
  for (auto& c : cams) { c.width = 4; c.height = 3; }
  int rendered = 0;
  vcar::FrameSequence f{cams, [&](std::size_t) { ++rendered; return vcar::ImageRGB8(4, 3, 3); }, false, {}};
  auto seg = box_segmenter();
  std::vector<int> answers(3, -1);
  seg.segment(f, {}, [&](std::size_t k, const vcar::Mask* m) { answers[k] = m ? (*m)(1, 1) : 0; });
  CHECK(answers == std::vector<int>{255, 255, 0});
  CHECK(rendered == 0);  // this segmenter never asked for pixels, so nothing was rendered
  const auto all = vcar::segment_all(seg, f, {});
  CHECK(all[0].has_value());
  CHECK_FALSE(all[2].has_value());
}

TEST_CASE("lambda renderers answer with the camera's size") {
  vcar::GaussianScene scene;
  vcar::Camera cam;
  cam.width = 5; cam.height = 2;
  vcar::RenderRequest q;
  q.scene = &scene;
  q.camera = &cam;
  auto r = flat_renderer();
  const auto out = r.render(q);
  CHECK(out.rgb.width == 5);
  CHECK(out.alpha.height == 2);
  CHECK(out.rgb.data.size() == 5 * 2 * 3);
}
