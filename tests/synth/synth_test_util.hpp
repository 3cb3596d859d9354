#pragma once
// Helpers shared by the synth tests (one unity translation unit: file-scope names must be unique).
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

namespace vcar_test {

// Bit-for-bit equality of two float columns (NaN-safe, unlike ==).
inline bool same_bytes(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// An empty folder <tmp>/vcar_synth_<name>_<pid>, emptied first if it exists.
inline std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path d =
      std::filesystem::temp_directory_path() / ("vcar_synth_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace vcar_test
