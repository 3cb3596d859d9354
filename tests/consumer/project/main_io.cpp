// Uses the installed <vcar/io.hpp>: reads the donut fixture and writes its first view's mask.
#include <vcar/io.hpp>
#include <cstdio>
#include <filesystem>

#ifndef VCAR_TEST_PLY
#error "compile with -DVCAR_TEST_PLY=\"path/to/donut.ply\""
#endif

int main() {
  const vcar::GaussianScene scene = vcar::io::read_ply(VCAR_TEST_PLY);
  vcar::Mask m(8, 4);
  m(3, 2) = 255;
  const auto png = std::filesystem::temp_directory_path() / "vcar_consumer_io.png";
  vcar::io::write_png(png, m);
  const vcar::Mask back = vcar::io::read_mask(png, 8, 4);
  std::filesystem::remove(png);
  const bool ok = scene.size() == 45624 && back(3, 2) != 0 && back(2, 2) == 0;
  std::printf("consumer_io: %zu Gaussians, %s\n", scene.size(), ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
