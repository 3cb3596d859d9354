#include <catch2/catch.hpp>

#include <cstdint>

#include "io_test_util.hpp"
#include "vcar/core/rotation.hpp"
#include "vcar/io/colmap.hpp"

using vcar_test::TempDir;
using vcar_test::append_le;
using vcar_test::require_error;
using vcar_test::write_bytes;

namespace {

struct Img { std::int32_t id; double q[4]; double t[3]; std::int32_t cam; std::string name; };

std::string cameras_bin(const std::vector<std::tuple<std::int32_t, std::int32_t, std::uint64_t, std::uint64_t, std::vector<double>>>& cams) {
  std::string s;
  append_le(s, std::uint64_t(cams.size()));
  for (const auto& [id, model, w, h, params] : cams) {
    append_le(s, id); append_le(s, model); append_le(s, w); append_le(s, h);
    for (double p : params) append_le(s, p);
  }
  return s;
}

std::string images_bin(const std::vector<Img>& imgs) {
  std::string s;
  append_le(s, std::uint64_t(imgs.size()));
  for (const auto& im : imgs) {
    append_le(s, im.id);
    for (double v : im.q) append_le(s, v);
    for (double v : im.t) append_le(s, v);
    append_le(s, im.cam);
    s += im.name; s.push_back('\0');
    append_le(s, std::uint64_t(2));  // two 2D points
    for (int k = 0; k < 2; ++k) { append_le(s, 1.5); append_le(s, 2.5); append_le(s, std::int64_t(-1)); }
  }
  return s;
}

const std::vector<Img> two_images = {
    {1, {0.9, 0.1, -0.3, 0.2}, {1, 2, 3}, 7, "b.png"},
    {2, {1, 0, 0, 0}, {-1, 0, 0.5}, 3, "a.png"}};

void check_two(const std::vector<vcar::Camera>& c) {
  REQUIRE(c.size() == 2);
  CHECK(c[0].name == "a.png");  // ordered by name
  CHECK(c[1].name == "b.png");
  // a.png: SIMPLE_PINHOLE f=500, cx=320, cy=240, 640 x 480; identity rotation.
  CHECK(c[0].width == 640); CHECK(c[0].height == 480);
  CHECK(c[0].fx == 500.f); CHECK(c[0].fy == 500.f); CHECK(c[0].cx == 320.f); CHECK(c[0].cy == 240.f);
  CHECK(c[0].R_w.isApprox(Eigen::Matrix3f::Identity()));
  CHECK(c[0].t_w == Eigen::Vector3f(-1, 0, 0.5f));
  // b.png: PINHOLE 600 610 300.5 200.25, 601 x 401; R from the normalised quaternion.
  CHECK(c[1].fx == 600.f); CHECK(c[1].fy == 610.f); CHECK(c[1].cx == 300.5f); CHECK(c[1].cy == 200.25f);
  CHECK(c[1].width == 601);
  const Eigen::Matrix3f R = vcar::rotation_from_quaternion(0.9f, 0.1f, -0.3f, 0.2f);
  CHECK((c[1].R_w - R).cwiseAbs().maxCoeff() < 1e-6f);
  CHECK(c[1].t_w == Eigen::Vector3f(1, 2, 3));
  for (const auto& cam : c) CHECK_NOTHROW(cam.validate());
}

const auto good_cameras = std::vector<std::tuple<std::int32_t, std::int32_t, std::uint64_t, std::uint64_t, std::vector<double>>>{
    {3, 0, 640, 480, {500, 320, 240}}, {7, 1, 601, 401, {600, 610, 300.5, 200.25}}};

const char* good_cameras_txt =
    "# Camera list\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
    "3 SIMPLE_PINHOLE 640 480 500 320 240\n7 PINHOLE 601 401 600 610 300.5 200.25\n";
const char* good_images_txt =
    "# Image list\n"
    "1 0.9 0.1 -0.3 0.2 1 2 3 7 b.png\n1.5 2.5 -1 1.5 2.5 -1\n"
    "2 1 0 0 0 -1 0 0.5 3 a.png\n\n";

}  // namespace

TEST_CASE("COLMAP binary model") {
  TempDir tmp;
  write_bytes(tmp / "cameras.bin", cameras_bin(good_cameras));
  write_bytes(tmp / "images.bin", images_bin(two_images));
  check_two(vcar::io::read_colmap(tmp.path));
}

TEST_CASE("COLMAP text model") {
  TempDir tmp;
  write_bytes(tmp / "cameras.txt", good_cameras_txt);
  write_bytes(tmp / "images.txt", good_images_txt);
  check_two(vcar::io::read_colmap(tmp.path));
}

TEST_CASE("COLMAP text write / read round trip is lossless to 1e-5") {
  TempDir tmp;
  std::vector<vcar::Camera> cams;
  const vcar::Intrinsics k{800, 600, 700.25f, 690.5f, 401.3f, 299.7f};
  cams.push_back(vcar::Camera::look_at({1, 2, 3}, {0, 0, 0}, {0, 0, 1}, k, "img_001.jpg"));
  cams.push_back(vcar::Camera::look_at({-4, 0.5f, 1}, {0.2f, 0.1f, 0}, {0, 1, 0}, k, "img_002.jpg"));
  vcar::io::write_colmap_text(tmp / "sparse" / "0", cams);
  const auto back = vcar::io::read_colmap(tmp / "sparse" / "0");
  REQUIRE(back.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(back[i].name == cams[i].name);
    CHECK(back[i].intrinsics().fx == cams[i].fx);
    CHECK(back[i].cx == cams[i].cx); CHECK(back[i].cy == cams[i].cy); CHECK(back[i].width == 800);
    CHECK((back[i].R_w - cams[i].R_w).cwiseAbs().maxCoeff() < 1e-5f);
    CHECK((back[i].t_w - cams[i].t_w).cwiseAbs().maxCoeff() < 1e-5f);
  }
  CHECK(std::filesystem::exists(tmp / "sparse" / "0" / "points3D.txt"));
  vcar::Camera spaced = cams[0];
  spaced.name = "has space.jpg";
  require_error([&] { vcar::io::write_colmap_text(tmp / "s2", {spaced}); }, {"has space.jpg"});
}

TEST_CASE("COLMAP bad input") {
  TempDir tmp;
  SECTION("distorted models name the camera id and model") {
    write_bytes(tmp / "cameras.txt", "3 OPENCV 640 480 500 500 320 240 0.1 0 0 0\n");
    write_bytes(tmp / "images.txt", good_images_txt);
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"camera 3", "OPENCV", "undistortion"});
    write_bytes(tmp / "cameras.bin", cameras_bin({{5, 3, 640, 480, {500, 320, 240, 0.1, 0.2}}}));
    write_bytes(tmp / "images.bin", images_bin(two_images));
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"camera 5", "RADIAL", "undistortion"});
  }
  SECTION("an image referencing an unknown camera id") {
    write_bytes(tmp / "cameras.bin", cameras_bin({good_cameras[0]}));
    write_bytes(tmp / "images.bin", images_bin(two_images));
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"b.png", "camera id 7"});
  }
  SECTION("missing image files when an images folder is given") {
    write_bytes(tmp / "cameras.txt", good_cameras_txt);
    write_bytes(tmp / "images.txt", good_images_txt);
    std::filesystem::create_directories(tmp / "images");
    write_bytes(tmp / "images" / "a.png", "x");
    require_error([&] { vcar::io::read_colmap(tmp.path, tmp / "images"); }, {"b.png", "does not exist"});
    write_bytes(tmp / "images" / "b.png", "x");
    CHECK(vcar::io::read_colmap(tmp.path, tmp / "images").size() == 2);
  }
  SECTION("truncated binary files and huge counts") {
    write_bytes(tmp / "cameras.bin", cameras_bin(good_cameras).substr(0, 60));
    write_bytes(tmp / "images.bin", images_bin(two_images));
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"cameras.bin", "truncated"});
    write_bytes(tmp / "cameras.bin", cameras_bin(good_cameras));
    std::string huge;
    append_le(huge, std::uint64_t(4000000000ull));
    write_bytes(tmp / "images.bin", huge + "tiny");
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"images.bin", "4000000000"});
    write_bytes(tmp / "images.bin", images_bin(two_images).substr(0, 200));
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"images.bin", "truncated"});
  }
  SECTION("malformed text, zero quaternion, missing files") {
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"cameras.bin or cameras.txt"});
    write_bytes(tmp / "cameras.txt", "3 PINHOLE 640 480 500 320\n");
    write_bytes(tmp / "images.txt", good_images_txt);
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"camera 3", "needs 4 parameters"});
    write_bytes(tmp / "cameras.txt", good_cameras_txt);
    write_bytes(tmp / "images.txt", "1 0 0 0 0 1 2 3 7 z.png\n\n");
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"z.png", "zero"});
    write_bytes(tmp / "images.txt", "1 0.5 nope 0 0 1 2 3 7 z.png\n\n");
    require_error([&] { vcar::io::read_colmap(tmp.path); }, {"images.txt", "line 1"});
  }
}
