#pragma once
// Per-run peak memory without fork(): Linux lets a process reset its own peak resident set
// (write "5" to /proc/self/clear_refs) and read it back (VmHWM in /proc/self/status). So
// peak_mib = the process peak during one run (the world and caches held by the driver included)
// and the delta = that peak minus the resident set just before the run. fork() is avoided
// because OpenMP's thread pool does not survive it. Returns 0 where /proc is unavailable.
#include <fstream>
#include <string>

namespace vcar::evidence {

inline double proc_status_mib(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(in, line))
    if (line.rfind(k, 0) == 0) return std::stod(line.substr(k.size())) / 1024.0;  // kB -> MiB
  return 0.0;
}

// Resets the peak to the current resident set; returns that resident set in MiB.
inline double reset_peak() {
  std::ofstream("/proc/self/clear_refs") << "5";
  return proc_status_mib("VmRSS");
}

inline double peak_mib() { return proc_status_mib("VmHWM"); }

}  // namespace vcar::evidence
