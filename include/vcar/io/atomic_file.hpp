#pragma once
// atomic_write: a file is either the old one or the complete new one, never half-written.
// The content goes to a temporary file in the same directory (same file system, so the
// final rename is atomic on POSIX), which replaces the target only after a successful flush.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <ostream>
#include <string>
#include <system_error>
#include <thread>

#include "vcar/core/error.hpp"

namespace vcar::io {

namespace detail {
// A name no other writer in this or another process picks: time, thread and a counter.
inline std::filesystem::path temporary_sibling(const std::filesystem::path& target) {
  static std::atomic<unsigned long long> counter{0};
  const auto ticks = std::chrono::steady_clock::now().time_since_epoch().count();
  const auto tid = std::hash<std::thread::id>{}(std::this_thread::get_id());
  std::filesystem::path tmp = target;
  tmp += ".tmp-" + std::to_string(ticks) + "-" + std::to_string(tid % 100000) + "-" +
         std::to_string(counter.fetch_add(1));
  return tmp;
}
}  // namespace detail

// Calls `write(stream)` on a temporary file next to `path`, then renames it onto `path`.
// Any exception from `write`, or a stream failure, removes the temporary file and leaves
// `path` untouched; failures are reported as vcar::Error naming `path`.
inline void atomic_write(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write) {
  const std::string where = path.string();
  const std::filesystem::path tmp = detail::temporary_sibling(path);
  auto discard = [&] { std::error_code ec; std::filesystem::remove(tmp, ec); };
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      std::error_code ec;
      const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
      if (!std::filesystem::exists(dir, ec)) throw Error("the directory " + dir.string() + " does not exist", where);
      if (!std::filesystem::is_directory(dir, ec)) throw Error(dir.string() + " is not a directory", where);
      throw Error("cannot create a temporary file in the target directory (permissions? disk full?)", where);
    }
    try {
      write(out);
      out.flush();
    } catch (...) {
      out.close();
      discard();
      throw;
    }
    if (!out) { out.close(); discard(); throw Error("write failed (disk full?)", where); }
    out.close();
    if (out.fail()) { discard(); throw Error("write failed when closing the file", where); }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) { discard(); throw Error("cannot replace the file: " + ec.message(), where); }
}

}  // namespace vcar::io
