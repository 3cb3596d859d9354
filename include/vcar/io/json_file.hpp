#pragma once
// JSON files for the camera readers: parse errors and type errors become vcar::Error naming the
// file; floats are written by their shortest decimal form so that they read back bit-exact.
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

#include "vcar/core/error.hpp"
#include "vcar/io/atomic_file.hpp"

namespace vcar::io {

inline nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open file", path.string());
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("malformed JSON: ") + e.what(), path.string());
  }
}

// JSON from a file's bytes in memory; `name` stands for the file in errors.
inline nlohmann::json parse_json_bytes(std::span<const std::uint8_t> bytes, const std::string& name) {
  try {
    return nlohmann::json::parse(bytes.begin(), bytes.end());
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("malformed JSON: ") + e.what(), name);
  }
}

inline void write_json_file(const std::filesystem::path& path, const nlohmann::json& j) {
  const std::string text = j.dump(2) + "\n";
  atomic_write(path, [&](std::ostream& out) { out << text; });
}

// Reads one entry of a camera file: JSON type errors and vcar::Errors from `read` come out as
// vcar::Error naming the entry (e.g. "entry 3") and the file `where`.
template <class F>
void read_entry(const std::string& entry, const std::string& where, F&& read) {
  try {
    read();
  } catch (const nlohmann::json::exception& ex) {
    throw Error(entry + ": " + ex.what(), where);
  } catch (const Error& ex) {
    if (ex.where() == where) throw;
    throw Error(entry + ": " + ex.what(), where);
  }
}

// An image size from JSON: an integer number in 1 .. 2^30 (a float or a huge value would be
// undefined behaviour as an int).
inline int json_image_size(double v, const std::string& what) {
  if (!(v >= 1.0 && v <= static_cast<double>(1 << 30)) || v != static_cast<double>(static_cast<long long>(v)))
    throw Error(what + " must be an integer in 1 .. 2^30");
  return static_cast<int>(v);
}
inline int json_image_size(const nlohmann::json& v, const std::string& what) {
  if (!v.is_number()) throw Error(what + " must be a number");
  if (v.is_number_unsigned()) return json_image_size(v.get<std::uint64_t>() > (1u << 30) ? 0.0 : static_cast<double>(v.get<std::uint64_t>()), what);
  if (v.is_number_integer()) { const auto i = v.get<std::int64_t>(); return json_image_size(i < 1 || i > (1 << 30) ? 0.0 : static_cast<double>(i), what); }
  return json_image_size(v.get<double>(), what);
}

// A float as the double that prints shortest (0.1f -> 0.1, not 0.10000000149011612).
inline double json_float(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  double d = 0.0;
  std::from_chars(buf, r.ptr, d);
  return d;
}

}  // namespace vcar::io
