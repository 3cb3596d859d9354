// libFuzzer target: io::read_colmap on cameras.txt + images.txt (see fuzz_colmap.hpp).
#include "fuzz_colmap.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return vcar::fuzz::fuzz_colmap(data, size, "txt");
}
