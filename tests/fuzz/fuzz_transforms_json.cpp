// libFuzzer target: io::read_transforms_json (nerfstudio / Blender) on arbitrary bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "vcar/io/transforms_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = vcar::fuzz::write_input("transforms.json", data, size);
  try {
    (void)vcar::io::read_transforms_json(path);
  } catch (const vcar::Error&) {
  }
  return 0;
}
