#include <catch2/catch.hpp>

#include "io_test_util.hpp"
#include "vcar/io/cameras_json.hpp"

using vcar_test::TempDir;
using vcar_test::require_error;
using vcar_test::write_bytes;

TEST_CASE("Inria cameras.json: rows of camera-to-world rotation and the centre") {
  TempDir tmp;
  // Camera at (0,0,5) looking down -z: camera-to-world rotation diag(1,-1,-1) (hand-made).
  write_bytes(tmp / "cameras.json", R"([{"id": 0, "img_name": "top", "width": 800, "height": 600,
    "position": [0, 0, 5], "rotation": [[1, 0, 0], [0, -1, 0], [0, 0, -1]], "fy": 410, "fx": 400}])");
  const auto c = vcar::io::read_cameras_json(tmp / "cameras.json");
  REQUIRE(c.size() == 1);
  CHECK(c[0].name == "top");
  CHECK(c[0].cx == 400.f); CHECK(c[0].cy == 300.f);  // image centre
  CHECK(c[0].fx == 400.f); CHECK(c[0].fy == 410.f);
  CHECK((c[0].position() - Eigen::Vector3f(0, 0, 5)).norm() < 1e-6f);
  // World (1, 1, 0) is 5 ahead, right of and (world +y = image up) above the image centre.
  const Eigen::Vector3f t = c[0].to_camera({1, 1, 0});
  CHECK(t.z() == Approx(5));
  CHECK(400.f * t.x() / t.z() + 400.f == Approx(480));
  CHECK(410.f * t.y() / t.z() + 300.f == Approx(218));
}

TEST_CASE("cameras.json round trip is lossless to 1e-5, off-centre principal point included") {
  TempDir tmp;
  std::vector<vcar::Camera> cams;
  cams.push_back(vcar::Camera::look_at({1, 2, 3}, {0, 0, 0}, {0, 0, 1}, {640, 480, 500.5f, 501.f, 320.f, 240.f}, "a"));
  cams.push_back(vcar::Camera::look_at({-3, 1, 0.5f}, {0, 0.3f, 0}, {0, 1, 0}, {641, 479, 700.f, 700.f, 300.25f, 250.75f}, "b"));
  vcar::io::write_cameras_json(tmp / "c.json", cams);
  const auto back = vcar::io::read_cameras_json(tmp / "c.json");
  REQUIRE(back.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(back[i].name == cams[i].name);
    CHECK(back[i].width == cams[i].width); CHECK(back[i].height == cams[i].height);
    CHECK(back[i].fx == cams[i].fx); CHECK(back[i].fy == cams[i].fy);
    CHECK(back[i].cx == cams[i].cx); CHECK(back[i].cy == cams[i].cy);
    CHECK((back[i].R_w - cams[i].R_w).cwiseAbs().maxCoeff() < 1e-5f);
    CHECK((back[i].t_w - cams[i].t_w).cwiseAbs().maxCoeff() < 1e-5f);
  }
  const std::string text = vcar_test::read_bytes(tmp / "c.json");
  CHECK(text.find("\"cx\"") != std::string::npos);  // only b is off-centre
  CHECK(text.find("\"cx\"") == text.rfind("\"cx\""));
}

TEST_CASE("cameras.json bad input names the file") {
  TempDir tmp;
  write_bytes(tmp / "bad.json", "[{\"img_name\": \"a\", ");
  require_error([&] { vcar::io::read_cameras_json(tmp / "bad.json"); }, {"bad.json", "malformed JSON"});
  write_bytes(tmp / "bad.json", R"([{"img_name": "a", "width": 10, "height": 10, "position": [0,0,0], "fx": 5, "fy": 5}])");
  require_error([&] { vcar::io::read_cameras_json(tmp / "bad.json"); }, {"bad.json", "entry 0", "rotation"});
  write_bytes(tmp / "bad.json", R"([{"img_name": "a", "width": "ten", "height": 10, "position": [0,0,0],
    "rotation": [[1,0,0],[0,1,0],[0,0,1]], "fx": 5, "fy": 5}])");
  require_error([&] { vcar::io::read_cameras_json(tmp / "bad.json"); }, {"bad.json", "entry 0"});
  write_bytes(tmp / "bad.json", R"([{"img_name": "a", "width": 10, "height": 10, "position": [0,0,0],
    "rotation": [[2,0,0],[0,1,0],[0,0,1]], "fx": 5, "fy": 5}])");
  require_error([&] { vcar::io::read_cameras_json(tmp / "bad.json"); }, {"bad.json", "camera 'a'", "rotation"});
  write_bytes(tmp / "bad.json", R"({"frames": []})");
  require_error([&] { vcar::io::read_cameras_json(tmp / "bad.json"); }, {"bad.json", "array"});
  require_error([&] { vcar::io::read_cameras_json(tmp / "none.json"); }, {"none.json"});
}
