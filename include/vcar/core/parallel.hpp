#pragma once
// The one place where loops go parallel (OpenMP when the build has it, serial otherwise).
// Every caller writes results per index or per fixed chunk and combines chunks in chunk order,
// so results are identical for any thread count.
#include <algorithm>
#include <cstdint>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace vcar {

inline int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

inline void set_num_threads(int n) {
#ifdef _OPENMP
  omp_set_num_threads(std::max(1, n));
#else
  (void)n;
#endif
}

// f(i) for i in [0, n), static schedule.
template <class F>
void parallel_for(std::int64_t n, F&& f) {
#ifdef _OPENMP
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < n; ++i) f(i);
#else
  for (std::int64_t i = 0; i < n; ++i) f(i);
#endif
}

// f(i) for i in [0, n), dynamic schedule in units of `grain` (for uneven work such as tiles).
template <class F>
void parallel_for_dynamic(std::int64_t n, F&& f, int grain = 1) {
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, grain)
  for (std::int64_t i = 0; i < n; ++i) f(i);
#else
  (void)grain;
  for (std::int64_t i = 0; i < n; ++i) f(i);
#endif
}

// Splits [0, n) into fixed chunks of `chunk` (independent of the thread count) and calls
// f(chunk_index, begin, end); returns the number of chunks, so callers can keep one partial
// result per chunk and reduce them in order.
template <class F>
std::int64_t parallel_chunks(std::int64_t n, std::int64_t chunk, F&& f) {
  const std::int64_t chunks = n <= 0 ? 0 : (n + chunk - 1) / chunk;
  parallel_for_dynamic(chunks, [&](std::int64_t c) {
    f(c, c * chunk, std::min(n, (c + 1) * chunk));
  });
  return chunks;
}

}  // namespace vcar
