// libFuzzer target: io::read_spz on arbitrary bytes (SPZ v2/v3 gzip and v4 NGSP + zstd). A
// lying count or stream size must fail before allocating (-malloc_limit_mb). vcar::Error is the
// expected answer to bad input; any other exception, crash, leak or huge allocation is a bug.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "vcar/io/spz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = vcar::fuzz::write_input("scene.spz", data, size);
  try {
    const vcar::GaussianScene s = vcar::io::read_spz(path);
    try {  // positions beyond +-2048 cannot be written: an Error, not a bug
      vcar::io::write_spz(vcar::fuzz::work_dir() / "back.spz", s);
    } catch (const vcar::Error&) {
      return 0;
    }
    if (vcar::io::read_spz(vcar::fuzz::work_dir() / "back.spz").size() != s.size()) __builtin_trap();
  } catch (const vcar::Error&) {
  }
  return 0;
}
