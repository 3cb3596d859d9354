// libFuzzer target: io::read_splat on arbitrary bytes (antimatter15 .splat). vcar::Error is the
// expected answer to bad input; any other exception, crash, leak or huge allocation is a bug.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "vcar/io/splat_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = vcar::fuzz::write_input("scene.splat", data, size);
  try {
    const vcar::GaussianScene s = vcar::io::read_splat(path);
    // A scene that reads must write and read back to the same size.
    vcar::io::write_splat(vcar::fuzz::work_dir() / "back.splat", s);
    if (vcar::io::read_splat(vcar::fuzz::work_dir() / "back.splat").size() != s.size()) __builtin_trap();
  } catch (const vcar::Error&) {
  }
  return 0;
}
