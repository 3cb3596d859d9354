#pragma once
// COLMAP targets: the input is "<cameras bytes>\x00\xff<images bytes>" (split at the first such
// pair; without it, all bytes are images and cameras is empty), written as cameras.<ext> and
// images.<ext> in a folder read by io::read_colmap.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_input.hpp"
#include "vcar/io/colmap.hpp"

namespace vcar::fuzz {

inline int fuzz_colmap(const std::uint8_t* data, std::size_t size, const std::string& ext) {
  std::size_t cut = size;
  for (std::size_t k = 0; k + 1 < size; ++k)
    if (data[k] == 0x00 && data[k + 1] == 0xff) { cut = k; break; }
  const auto dir = work_dir() / ("colmap_" + ext);
  std::filesystem::create_directories(dir);
  for (const char* other : {".bin", ".txt"}) {  // only this extension's pair may exist
    std::filesystem::remove(dir / (std::string("cameras") + other));
    std::filesystem::remove(dir / (std::string("images") + other));
  }
  const std::size_t img0 = cut < size ? cut + 2 : 0, cam_n = cut < size ? cut : 0;
  write_input("colmap_" + ext + "/cameras." + ext, data, cam_n);
  write_input("colmap_" + ext + "/images." + ext, data + img0, size - img0);
  try {
    (void)io::read_colmap(dir);
  } catch (const Error&) {
  }
  return 0;
}

}  // namespace vcar::fuzz
