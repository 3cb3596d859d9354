#include <catch2/catch.hpp>

#include "vcar/core/camera.hpp"


TEST_CASE("look_at puts the target on the principal point and keeps up upward") {
  vcar::Intrinsics k{100, 80, 90.f, 90.f, 50.f, 40.f};
  const Eigen::Vector3f eye(1, 2, 3), target(0, 0.5f, 0), up(0, 0, 1);
  const auto cam = vcar::Camera::look_at(eye, target, up, k, "v");
  const Eigen::Vector3f t = cam.to_camera(target);
  CHECK(t.x() == Approx(0).margin(1e-5));
  CHECK(t.y() == Approx(0).margin(1e-5));
  CHECK(t.z() == Approx((target - eye).norm()).epsilon(1e-5));
  CHECK((cam.position() - eye).norm() == Approx(0).margin(1e-5));
  // A point above the target appears above the image centre (smaller v: y is down).
  const Eigen::Vector3f above = cam.to_camera(target + up * 0.1f);
  CHECK(above.y() < 0.f);
  CHECK(cam.up().dot(up) > 0.f);
  CHECK_NOTHROW(cam.validate());
}

TEST_CASE("camera validation names the camera") {
  vcar::Camera c;
  c.name = "IMG_7";
  c.width = 10; c.height = 10; c.fx = 0; c.fy = 5;
  try {
    c.validate();
    FAIL("expected an error");
  } catch (const vcar::Error& e) {
    CHECK(std::string(e.what()).find("IMG_7") != std::string::npos);
  }
}
