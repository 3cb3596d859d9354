// Bad input, one case per row of docs/errors.md that no other test file covers: what the
// library throws (vcar::Error naming the file / view / parameter) or which documented fallback
// it takes. Fuzzer finds are replayed from tests/regression/inputs/.
#include <catch2/catch.hpp>

#include <sys/resource.h>

#include <csignal>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/cameras_json.hpp"
#include "vcar/io/colmap.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/transforms_json.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path inputs = fs::path(VCAR_TEST_DATA_DIR) / ".." / "regression" / "inputs";

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / "vcar_test_bad_input";
  fs::create_directories(d);
  return d / name;
}

fs::path write_text(const std::string& name, const std::string& text) {
  const fs::path p = scratch(name);
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

// The message of the vcar::Error that f throws ("" when it throws nothing).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const vcar::Error& e) {
    return e.what();
  }
  return "";
}

// Minimal binary PLY with one Gaussian whose values are given (x y z scale_0..2 rot_0..3 opacity f_dc).
std::string one_gaussian_ply(float x, float s0, float q0, float q1) {
  std::string h = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n";
  for (const char* n : {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1",
                        "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    h += std::string("property float ") + n + "\n";
  h += "end_header\n";
  const float v[14] = {x, 0, 0, 0, 0, 0, 1, s0, 0, 0, q0, q1, 0, 0};
  h.append(reinterpret_cast<const char*>(v), sizeof v);
  return h;
}

// A blob of Gaussians at the origin and a forward rig at z = -4 (small images).
struct Blob {
  vcar::GaussianScene scene;
  std::vector<vcar::Camera> cams;
  Blob() {
    scene.resize(64);
    for (int i = 0; i < 64; ++i)
      scene.set(static_cast<std::size_t>(i),
                {0.05f * static_cast<float>(i % 4 - 2), 0.05f * static_cast<float>(i / 4 % 4 - 2), 0.05f * static_cast<float>(i / 16 - 2)},
                Eigen::Vector3f::Constant(std::log(0.02f)), {1, 0, 0, 0}, 2.f);
    for (int k = 0; k < 4; ++k)
      cams.push_back(vcar::Camera::look_at({0.3f * static_cast<float>(k) - 0.45f, 0.f, -4.f}, {0, 0, 0}, {0, -1, 0},
                                           {64, 48, 60.f, 60.f, 32.f, 24.f}, "view_" + std::to_string(k)));
  }
};

vcar::Mask filled(const vcar::Camera& c, std::uint8_t v) { return vcar::Mask(c.width, c.height, 1, v); }

template <class MaskOf>
auto segmenter_of(MaskOf mask_of) {
  return vcar::make_segmenter([mask_of](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> out(f.size());
    for (std::size_t k = 0; k < f.size(); ++k) out[k] = mask_of(k, f.cameras[k]);
    return out;
  });
}

vcar::VcarParams no_sss() {
  vcar::VcarParams p;
  p.enable_sss = false;
  return p;
}

}  // namespace

// ---- scenes (PLY) -------------------------------------------------------------------------

TEST_CASE("PLY: a lying vertex count fails before allocating", "[regression][ply]") {
  // 4e9 vertices of 12 bytes declared in a file of ~150 bytes (tests/fuzz/corpus/ply/lying_count.ply).
  std::string h = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n";
  for (const char* n : {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1",
                        "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    h += std::string("property float ") + n + "\n";
  h += "end_header\n" + std::string(24, '\0');
  CHECK_THAT(error_of([&] { vcar::io::read_ply(write_text("lying.ply", h)); }),
             Catch::Contains("declares 4000000000 vertices") && Catch::Contains("lying.ply"));
  std::string a = h;
  a.replace(a.find("binary_little_endian"), 20, "ascii");
  CHECK_THAT(error_of([&] { vcar::io::read_ply(write_text("lying_ascii.ply", a)); }),
             Catch::Contains("declares 4000000000 vertices"));
}

TEST_CASE("PLY: NaN, Inf and zero quaternions are rejected naming the Gaussian", "[regression][ply]") {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  CHECK_THAT(error_of([&] { vcar::io::read_ply(write_text("nan.ply", one_gaussian_ply(nan, 0, 1, 0))); }),
             Catch::Contains("Gaussian 0 has a NaN or infinite value"));
  CHECK_THAT(error_of([&] { vcar::io::read_ply(write_text("inf.ply", one_gaussian_ply(0, inf, 1, 0))); }),
             Catch::Contains("Gaussian 0 has a NaN or infinite value"));
  CHECK_THAT(error_of([&] { vcar::io::read_ply(write_text("zeroq.ply", one_gaussian_ply(0, 0, 0, 0))); }),
             Catch::Contains("Gaussian 0 has a zero quaternion"));
  CHECK(error_of([&] { vcar::io::read_ply(write_text("ok.ply", one_gaussian_ply(0, 0, 0, 1))); }).empty());
}

TEST_CASE("PLY: zero vertices read as an empty scene (fuzz find: UB with a null column)", "[regression][ply]") {
  // fuzz_ply under UBSan: `element vertex 0` made the reader compute null + offset.
  const vcar::GaussianScene s = vcar::io::read_ply(inputs / "ply_ubsan_zero_vertices_null_offset.ply");
  CHECK(s.size() == 0);
  CHECK_NOTHROW(s.validate("empty"));
}

TEST_CASE("PLY: a scene built in memory with NaN is refused by the writer", "[regression][ply]") {
  vcar::GaussianScene s;
  s.resize(2);
  s.mean[1][1] = std::numeric_limits<float>::quiet_NaN();
  const fs::path p = scratch("nan_write.ply");
  fs::remove(p);
  CHECK_THAT(error_of([&] { vcar::io::write_ply(p, s); }), Catch::Contains("Gaussian 1"));
  CHECK_FALSE(fs::exists(p));
}

// ---- cameras ------------------------------------------------------------------------------

TEST_CASE("cameras.json: zero focal length and absurd sizes are errors", "[regression][cameras]") {
  const std::string cam = R"({"id":0,"img_name":"a","width":64,"height":48,"position":[0,0,0],)"
                          R"("rotation":[[1,0,0],[0,1,0],[0,0,1]],"fx":FX,"fy":50})";
  auto with = [&](const std::string& fx, const std::string& w) {
    std::string c = cam;
    c.replace(c.find("FX"), 2, fx);
    c.replace(c.find("64"), 2, w);
    return "[" + c + "]";
  };
  CHECK_THAT(error_of([&] { vcar::io::read_cameras_json(write_text("f0.json", with("0", "64"))); }),
             Catch::Contains("entry 0") && Catch::Contains("focal"));
  // Found in review while writing fuzz_cameras_json: a float or huge width went to int (UB).
  CHECK_THAT(error_of([&] { vcar::io::read_cameras_json(write_text("w1e20.json", with("50", "1e20"))); }),
             Catch::Contains("entry 0"));
  CHECK_THAT(error_of([&] { vcar::io::read_cameras_json(write_text("w-big.json", with("50", "-9999999999999"))); }),
             Catch::Contains("entry 0"));
  CHECK_THAT(error_of([&] { vcar::io::read_cameras_json(write_text("w2.5.json", with("50", "2.5"))); }),
             Catch::Contains("entry 0"));
}

TEST_CASE("transforms.json: absurd image sizes are errors", "[regression][cameras]") {
  const std::string t = R"({"fl_x":50,"w":W,"h":48,"frames":[{"file_path":"a","transform_matrix":)"
                        R"([[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}]})";
  for (const char* w : {"1e20", "-1e20", "nan", "3e9"}) {
    std::string s = t;
    s.replace(s.find("W"), 1, w);
    INFO(w);
    CHECK_FALSE(error_of([&] { vcar::io::read_transforms_json(write_text("tw.json", s)); }).empty());
  }
}

TEST_CASE("COLMAP: a lying image count fails before allocating", "[regression][cameras]") {
  const fs::path d = scratch("colmap_lying");
  fs::create_directories(d);
  {
    std::ofstream c(d / "cameras.bin", std::ios::binary);
    const std::uint64_t n = 1;
    const std::int32_t id = 1, model = 1;
    const std::uint64_t w = 64, h = 48;
    const double p[4] = {50, 50, 32, 24};
    c.write(reinterpret_cast<const char*>(&n), 8).write(reinterpret_cast<const char*>(&id), 4)
        .write(reinterpret_cast<const char*>(&model), 4).write(reinterpret_cast<const char*>(&w), 8)
        .write(reinterpret_cast<const char*>(&h), 8).write(reinterpret_cast<const char*>(p), 32);
    std::ofstream i(d / "images.bin", std::ios::binary);
    const std::uint64_t m = 1ull << 60;
    i.write(reinterpret_cast<const char*>(&m), 8);
  }
  CHECK_THAT(error_of([&] { vcar::io::read_colmap(d); }), Catch::Contains("more than the file holds"));
}

// ---- masks --------------------------------------------------------------------------------

TEST_CASE("mask PNGs whose header lies fail without a huge allocation (fuzz finds)", "[regression][mask]") {
  // fuzz_mask_png: 40 x 16449054 pixels claimed by a 150-byte PNG (the mask was allocated from
  // the header before decoding), and an IDAT chunk declaring 721 MB (stb reserves it first).
  CHECK_THAT(error_of([&] { vcar::io::read_mask(inputs / "mask_png_oom_lying_height.png"); }),
             Catch::Contains("mask_png_oom_lying_height.png"));
  CHECK_THAT(error_of([&] { vcar::io::read_mask(inputs / "mask_png_oom_lying_chunk_length.png"); }),
             Catch::Contains("more than the file holds"));
  CHECK_FALSE(error_of([&] { vcar::io::read_image_rgb8(inputs / "mask_png_oom_lying_chunk_length.png"); }).empty());
}

TEST_CASE("mask files: garbage and trailing bytes", "[regression][mask]") {
  CHECK_THAT(error_of([&] { vcar::io::read_mask(write_text("garbage.png", "not an image")); }),
             Catch::Contains("cannot read mask") && Catch::Contains("garbage.png"));
  // A valid PNG followed by junk still reads (the chunk walk stops at IEND).
  vcar::Mask m(5, 4, 1, 0);
  m.data[3] = 255;
  const fs::path p = scratch("trailing.png");
  vcar::io::write_png(p, m);
  std::ofstream(p, std::ios::binary | std::ios::app) << std::string(100, '\x7f');
  const vcar::Mask r = vcar::io::read_mask(p, 5, 4);
  CHECK(r.data == m.data);
}

// ---- pipeline -----------------------------------------------------------------------------

TEST_CASE("pipeline: all-empty masks give an empty selection and a note", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  auto s = segmenter_of([](std::size_t, const vcar::Camera& c) { return filled(c, 0); });
  const auto res = vcar::segment(b.scene, b.cams, {}, r, s, no_sss());
  CHECK(res.indices.empty());
  CHECK_THAT(res.diagnostics.note, Catch::Contains("coarse stage selected no Gaussian"));
}

TEST_CASE("pipeline: full masks select every Gaussian in view", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  auto s = segmenter_of([](std::size_t, const vcar::Camera& c) { return filled(c, 255); });
  const auto res = vcar::segment(b.scene, b.cams, {}, r, s, no_sss());
  CHECK(res.indices.size() == b.scene.size());
}

TEST_CASE("pipeline: a segmenter that answers fewer frames than asked", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  // Only frame 0 gets a (full) mask; the others are never answered: "no evidence" (label -1).
  auto s = vcar::make_streaming_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&, const vcar::MaskSink& sink) {
    const vcar::Mask m = filled(f.cameras[0], 255);
    sink(0, &m);
  });
  const auto res = vcar::segment(b.scene, b.cams, {}, r, s, no_sss());
  CHECK(res.diagnostics.masks_missing == b.cams.size() - 1);
  CHECK(res.indices.size() == b.scene.size());
}

TEST_CASE("pipeline: a segmenter returning a shorter mask vector", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  auto s = vcar::make_segmenter([](const vcar::FrameSequence& f, const vcar::Prompt&) {
    std::vector<std::optional<vcar::Mask>> out(1);
    out[0] = filled(f.cameras[0], 255);
    return out;
  });
  const std::string e = error_of([&] { (void)vcar::segment(b.scene, b.cams, {}, r, s, no_sss()); });
  const auto res = e.empty() ? vcar::segment(b.scene, b.cams, {}, r, s, no_sss()) : vcar::SegmentationResult{};
  // Either an error naming the round, or the missing frames count as "no evidence".
  CHECK((e.find("coarse round") != std::string::npos || res.diagnostics.masks_missing == b.cams.size() - 1));
}

TEST_CASE("pipeline: a reference view that does not exist", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  auto s = segmenter_of([](std::size_t, const vcar::Camera& c) { return filled(c, 255); });
  vcar::Prompt p;
  p.reference_view = b.cams.size();
  CHECK_THAT(error_of([&] { (void)vcar::segment(b.scene, b.cams, p, r, s, no_sss()); }),
             Catch::Contains("prompt") && Catch::Contains("out of range"));
}

TEST_CASE("pipeline: cameras with zero focal length, or behind everything", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  auto s = segmenter_of([](std::size_t, const vcar::Camera& c) { return filled(c, 255); });
  auto bad = b.cams;
  bad[2].fx = 0.f;
  CHECK_THAT(error_of([&] { (void)vcar::segment(b.scene, bad, {}, r, s, no_sss()); }),
             Catch::Contains("camera 'view_2'") && Catch::Contains("focal"));
  // Every camera looks away from the scene: nothing is visible, nothing is selected.
  std::vector<vcar::Camera> away;
  for (const auto& c : b.cams)
    away.push_back(vcar::Camera::look_at(c.position(), c.position() - Eigen::Vector3f(0, 0, 1), {0, -1, 0},
                                         {64, 48, 60.f, 60.f, 32.f, 24.f}, c.name));
  const auto res = vcar::segment(b.scene, away, {}, r, s, no_sss());
  CHECK(res.indices.empty());
  CHECK_FALSE(res.diagnostics.note.empty());
}

TEST_CASE("pipeline: zero valid cameras give a 180 degree gap and SSS", "[regression][pipeline]") {
  Blob b;
  vcar::cpu::TiledRenderer r;
  auto s = segmenter_of([](std::size_t, const vcar::Camera& c) { return filled(c, 255); });
  // Cameras look straight ahead (+z); half the blob sits at x = -2.4 (seen by view_0 only), half
  // at x = +2.4 (view_3 only): every camera sees at most half of the selection.
  std::vector<vcar::Camera> cams;
  for (const auto& c : b.cams)
    cams.push_back(vcar::Camera::look_at(c.position(), c.position() + Eigen::Vector3f(0, 0, 1), {0, -1, 0},
                                         {64, 48, 60.f, 60.f, 32.f, 24.f}, c.name));
  vcar::GaussianScene sc = b.scene;
  for (std::size_t i = 0; i < sc.size(); ++i) sc.mean[0][i] += i % 2 ? 2.4f : -2.4f;
  vcar::VcarParams p;
  p.rho_min = 0.6f;
  p.enable_abr = false;
  const auto res = vcar::segment(sc, cams, {}, r, s, p);
  REQUIRE(res.diagnostics.n_coarse == sc.size());
  CHECK(res.diagnostics.valid_cameras == 0);
  CHECK(res.diagnostics.max_gap_deg == Approx(180.0));
  CHECK(res.diagnostics.sss_triggered);
}

// ---- outputs ------------------------------------------------------------------------------

TEST_CASE("output directory that cannot be written", "[regression][output]") {
  const fs::path file = write_text("a_file", "x");
  vcar::GaussianScene s;
  s.resize(3);
  CHECK_THAT(error_of([&] { vcar::io::write_ply(file / "object.ply", s); }),
             Catch::Contains("is not a directory") && Catch::Contains("a_file"));
  CHECK_THAT(error_of([&] { vcar::io::write_ply(scratch("no_such_dir") / "sub" / "object.ply", s); }),
             Catch::Contains("no_such_dir/sub does not exist") && Catch::Contains("object.ply"));
}

TEST_CASE("disk full while writing: the target keeps its old content, no temporary is left", "[regression][output]") {
  const fs::path dir = scratch("full");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path p = dir / "object.ply";
  vcar::GaussianScene small, big;
  small.resize(2);
  big.resize(20000);
  vcar::io::write_ply(p, small);
  std::ifstream in0(p, std::ios::binary);
  const std::string before((std::istreambuf_iterator<char>(in0)), std::istreambuf_iterator<char>());

  SECTION("a stream that fails after N bytes") {
    const std::string e = error_of([&] {
      vcar::io::atomic_write(p, [](std::ostream& out) {
        out << std::string(1000, 'a');
        out.setstate(std::ios::badbit);  // what a full disk does to an ofstream
      });
    });
    CHECK_THAT(e, Catch::Contains("disk full") && Catch::Contains("object.ply"));
  }
  SECTION("a real file-size limit (RLIMIT_FSIZE, EFBIG like ENOSPC)") {
    rlimit old{};
    REQUIRE(getrlimit(RLIMIT_FSIZE, &old) == 0);
    auto* previous = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lim = old;
    lim.rlim_cur = 64 * 1024;
    REQUIRE(setrlimit(RLIMIT_FSIZE, &lim) == 0);
    const std::string e = error_of([&] { vcar::io::write_ply(p, big); });  // ~1.2 MB
    setrlimit(RLIMIT_FSIZE, &old);
    std::signal(SIGXFSZ, previous);
    CHECK_THAT(e, Catch::Contains("object.ply"));
  }
  std::ifstream in1(p, std::ios::binary);
  const std::string after((std::istreambuf_iterator<char>(in1)), std::istreambuf_iterator<char>());
  CHECK(after == before);
  std::size_t files = 0;
  for (const auto& f : fs::directory_iterator(dir)) { (void)f; ++files; }
  CHECK(files == 1);
}
