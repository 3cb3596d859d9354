// Uses the installed umbrella header: projects one Gaussian and checks the pixel mean.
#include <vcar/vcar.hpp>
#include <cmath>
#include <cstdio>

int main() {
  vcar::Intrinsics k{64, 48, 50.f, 50.f, 32.f, 24.f};
  const auto cam = vcar::Camera::look_at({0, 0, -2}, {0, 0, 0}, {0, -1, 0}, k, "c");
  const auto g = vcar::project_gaussian(cam, {0, 0, 0}, Eigen::Matrix3f::Identity(),
                                        {0.1f, 0.1f, 0.1f}, 0.9f);
  const bool ok = g.valid && std::abs(g.mean.x() - 32.f) < 1e-4f && std::abs(g.mean.y() - 24.f) < 1e-4f;
  std::printf("consumer: %s\n", ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
