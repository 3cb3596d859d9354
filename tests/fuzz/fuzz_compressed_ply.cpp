// libFuzzer target: io::read_scene on arbitrary bytes named .ply, which dispatches on content to
// the PlayCanvas compressed PLY reader (element chunk + packed_*) or the Inria PLY reader.
// vcar::Error is the expected answer to bad input; any other exception, crash, leak or huge
// allocation is a bug.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "vcar/io/scene_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = vcar::fuzz::write_input("scene.compressed.ply", data, size);
  try {
    const vcar::GaussianScene s = vcar::io::read_scene(path);
    vcar::io::write_ply(vcar::fuzz::work_dir() / "back.ply", s);
    if (vcar::io::read_ply(vcar::fuzz::work_dir() / "back.ply").size() != s.size()) __builtin_trap();
  } catch (const vcar::Error&) {
  }
  return 0;
}
