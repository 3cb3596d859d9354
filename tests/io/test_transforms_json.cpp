#include <catch2/catch.hpp>

#include <cmath>

#include "io_test_util.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/transforms_json.hpp"

using vcar_test::TempDir;
using vcar_test::require_error;
using vcar_test::write_bytes;

TEST_CASE("transforms.json: OpenGL camera-to-world, camera_angle_x, size from the image") {
  TempDir tmp;
  std::filesystem::create_directories(tmp / "train");
  vcar::io::write_png(tmp / "train" / "r_0.png", vcar::Image<std::uint8_t>(800, 600, 3));
  // Identity in OpenGL: at (0,0,5) looking down -z. camera_angle_x = pi/2 -> fx = 0.5 w = 400.
  write_bytes(tmp / "transforms.json", R"({"camera_angle_x": 1.5707963267948966, "frames": [
    {"file_path": "./train/r_0", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,5],[0,0,0,1]]}]})");
  const auto c = vcar::io::read_transforms_json(tmp / "transforms.json");
  REQUIRE(c.size() == 1);
  CHECK(c[0].name == "r_0");
  CHECK(c[0].width == 800); CHECK(c[0].height == 600);
  CHECK(c[0].fx == Approx(400)); CHECK(c[0].fy == Approx(400));
  CHECK(c[0].cx == 400.f); CHECK(c[0].cy == 300.f);
  // OpenCV: y down. World (1, 1, 0) is 5 ahead, right, and up -> v above the centre.
  const Eigen::Vector3f t = c[0].to_camera({1, 1, 0});
  CHECK(t.z() == Approx(5));
  CHECK(t.x() == Approx(1));
  CHECK(t.y() == Approx(-1));
}

TEST_CASE("transforms.json: per-frame intrinsics override the top level") {
  TempDir tmp;
  write_bytes(tmp / "t.json", R"({"fl_x": 500, "fl_y": 510, "cx": 320, "cy": 240, "w": 640, "h": 480,
    "k1": 0, "p1": 0, "frames": [
    {"file_path": "images/frame_00001.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
    {"file_path": "images/frame_00002.png", "fl_x": 600, "w": 700,
     "transform_matrix": [[1,0,0,1],[0,1,0,2],[0,0,1,3],[0,0,0,1]]}]})");
  const auto c = vcar::io::read_transforms_json(tmp / "t.json");
  REQUIRE(c.size() == 2);
  CHECK(c[0].name == "frame_00001");
  CHECK(c[0].fx == 500.f); CHECK(c[0].fy == 510.f); CHECK(c[0].width == 640);
  CHECK(c[1].fx == 600.f); CHECK(c[1].fy == 510.f); CHECK(c[1].width == 700); CHECK(c[1].cx == 320.f);
  CHECK((c[1].position() - Eigen::Vector3f(1, 2, 3)).norm() < 1e-6f);
}

TEST_CASE("transforms.json round trip is lossless to 1e-5") {
  TempDir tmp;
  for (bool same_intrinsics : {true, false}) {
    std::vector<vcar::Camera> cams;
    cams.push_back(vcar::Camera::look_at({1, 2, 3}, {0, 0, 0}, {0, 0, 1}, {640, 480, 500.5f, 501.f, 321.f, 239.f}, "a"));
    cams.push_back(vcar::Camera::look_at({-3, 1, 0.5f}, {0, 0.3f, 0}, {0, 1, 0},
                                         same_intrinsics ? cams[0].intrinsics() : vcar::Intrinsics{641, 479, 700.f, 701.f, 300.25f, 250.75f}, "b"));
    vcar::io::write_transforms_json(tmp / "t.json", cams);
    const auto back = vcar::io::read_transforms_json(tmp / "t.json");
    REQUIRE(back.size() == 2);
    for (std::size_t i = 0; i < 2; ++i) {
      CHECK(back[i].name == cams[i].name);
      CHECK(back[i].width == cams[i].width); CHECK(back[i].height == cams[i].height);
      CHECK(back[i].fx == cams[i].fx); CHECK(back[i].fy == cams[i].fy);
      CHECK(back[i].cx == cams[i].cx); CHECK(back[i].cy == cams[i].cy);
      CHECK((back[i].R_w - cams[i].R_w).cwiseAbs().maxCoeff() < 1e-5f);
      CHECK((back[i].t_w - cams[i].t_w).cwiseAbs().maxCoeff() < 1e-5f);
    }
  }
}

TEST_CASE("transforms.json bad input") {
  TempDir tmp;
  const auto p = tmp / "t.json";
  write_bytes(p, R"({"frames": [ {"file_path": "x"}, )");
  require_error([&] { vcar::io::read_transforms_json(p); }, {"t.json", "malformed JSON"});
  write_bytes(p, R"({"fl_x": 500, "w": 64, "h": 48, "k1": 0.1, "frames": [
    {"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  require_error([&] { vcar::io::read_transforms_json(p); }, {"t.json", "a.png", "k1", "undistort"});
  write_bytes(p, R"({"fl_x": 500, "frames": [
    {"file_path": "missing", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  require_error([&] { vcar::io::read_transforms_json(p); }, {"t.json", "frame 0", "w"});
  write_bytes(p, R"({"w": 64, "h": 48, "frames": [
    {"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  require_error([&] { vcar::io::read_transforms_json(p); }, {"t.json", "focal"});
  write_bytes(p, R"({"fl_x": 5, "w": 64, "h": 48, "frames": [
    {"file_path": "a.png", "transform_matrix": [[1,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  require_error([&] { vcar::io::read_transforms_json(p); }, {"t.json", "a.png", "rows"});
  write_bytes(p, R"([1, 2])");
  require_error([&] { vcar::io::read_transforms_json(p); }, {"t.json", "frames"});
}
