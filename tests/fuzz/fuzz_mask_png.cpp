// libFuzzer target: io::read_mask (PNG and every other format stb decodes) on arbitrary bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "vcar/io/image_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = vcar::fuzz::write_input("mask.png", data, size);
  try {
    const vcar::Mask m = vcar::io::read_mask(path);
    for (std::uint8_t v : m.data)
      if (v != 0 && v != 255) __builtin_trap();  // a mask is binary
  } catch (const vcar::Error&) {
  }
  return 0;
}
