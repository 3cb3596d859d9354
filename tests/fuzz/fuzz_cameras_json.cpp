// libFuzzer target: io::read_cameras_json (Inria cameras.json) on arbitrary bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "vcar/io/cameras_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = vcar::fuzz::write_input("cameras.json", data, size);
  try {
    (void)vcar::io::read_cameras_json(path);
  } catch (const vcar::Error&) {
  }
  return 0;
}
