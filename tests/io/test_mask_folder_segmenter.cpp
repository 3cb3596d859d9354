#include <catch2/catch.hpp>

#include "io_test_util.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"

using vcar_test::TempDir;
using vcar_test::require_error;

static_assert(vcar::Segmenter<vcar::io::MaskFolderSegmenter>);

TEST_CASE("MaskFolderSegmenter answers each frame with the mask named after its camera") {
  TempDir tmp;
  const vcar::Intrinsics k{4, 3, 5.f, 5.f, 2.f, 1.5f};
  std::vector<vcar::Camera> cams;
  for (const char* n : {"IMG_02.jpg", "IMG_01.jpg", "sub/IMG_03.JPG", "IMG_04.jpg"})
    cams.push_back(vcar::Camera::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, k, n));
  vcar::Mask m1(4, 3, 1), m2(4, 3, 1), m3(4, 3, 1);
  m1(1, 2) = 255;
  m2(3, 0) = 200;  // foreground: >= 128 (io/image_file.hpp)
  m3.data.assign(12, 0);
  vcar::io::write_png(tmp / "IMG_01.png", m1);
  vcar::io::write_png(tmp / "IMG_02.png", m2);
  vcar::Mask other(4, 3, 1, 255);
  vcar::io::write_png(tmp / "IMG_02.jpeg", other);  // .png wins over .jpeg
  vcar::io::write_png(tmp / "IMG_03.png", m3);
  vcar::io::write_png(tmp / "notes.txt", m3);  // ignored: not an image extension

  vcar::io::MaskFolderSegmenter seg(tmp.path);
  vcar::FrameSequence frames{cams, [](std::size_t) -> vcar::ImageRGB8 { FAIL("must not render"); return {}; }, false, {}};
  const auto masks = vcar::segment_all(seg, frames, vcar::Prompt{});
  REQUIRE(masks.size() == 4);
  REQUIRE(masks[0]);
  CHECK(masks[0]->data == std::vector<std::uint8_t>{0, 0, 0, 255, 0, 0, 0, 0, 0, 0, 0, 0});
  REQUIRE(masks[1]);
  CHECK((*masks[1])(1, 2) == 255);
  CHECK(std::count(masks[1]->data.begin(), masks[1]->data.end(), 255) == 1);
  REQUIRE(masks[2]);  // stem match ignores folders in the camera name
  CHECK(std::count(masks[2]->data.begin(), masks[2]->data.end(), 0) == 12);
  CHECK(!masks[3]);   // no file: no evidence

  // Renders of a subset (the fine round's renders of G_coarse) are not the captures the files
  // are masks of: every frame gets "no mask".
  vcar::FrameSequence subset{cams, [](std::size_t) -> vcar::ImageRGB8 { FAIL("must not render"); return {}; }, true, {}};
  CHECK_FALSE(vcar::io::MaskFolderSegmenter::has_masks_of(subset));
  CHECK(vcar::io::MaskFolderSegmenter::has_masks_of(frames));
  const auto none = vcar::segment_all(seg, subset, vcar::Prompt{});
  REQUIRE(none.size() == 4);
  CHECK(std::none_of(none.begin(), none.end(), [](const auto& m) { return m.has_value(); }));

  vcar::MaskFolderSegmenter alias(tmp.path);  // the name the Segmenter docs use
  cams[0].width = 5;
  vcar::FrameSequence wrong{cams, {}, false, {}};
  require_error([&] { vcar::segment_all(alias, wrong, vcar::Prompt{}); }, {"IMG_02.png", "4 x 3", "5 x 3"});
  require_error([&] { vcar::io::MaskFolderSegmenter bad(tmp / "nope"); }, {"nope"});
}
