#pragma once
// Helpers shared by the io tests: a scratch directory and raw file writers.
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "vcar/core/error.hpp"

namespace vcar_test {

// A fresh directory removed at the end of the test.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::random_device rd;
    path = std::filesystem::temp_directory_path() /
           ("vcar_io_test_" + std::to_string(rd()) + "_" + std::to_string(rd()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::error_code ec; std::filesystem::remove_all(path, ec); }
  std::filesystem::path operator/(const std::string& name) const { return path / name; }
};

inline void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

template <class T>
void append_le(std::string& s, T v) {  // the test machine is little-endian (x86-64)
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// Runs f, expects a vcar::Error whose message contains every string in `needles`.
template <class F>
void require_error(F&& f, const std::vector<std::string>& needles) {
  try {
    f();
    FAIL("expected vcar::Error");
  } catch (const vcar::Error& e) {
    const std::string msg = e.what();
    INFO("message: " << msg);
    for (const auto& n : needles) CHECK(msg.find(n) != std::string::npos);
  }
}

}  // namespace vcar_test
