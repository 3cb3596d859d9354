#pragma once
// Debian's emscripten 3.1.6 ships an older libc++ than the C++20 that vcar is written against:
// no std::bit_cast, no std::atomic_ref, no floating-point std::to_chars / from_chars. This header, included
// first in the WebAssembly build only (-include), supplies the three, each guarded by its
// feature-test macro so that a newer emscripten uses its own. Single-threaded builds only
// (no -pthread): atomic_ref is then a plain reference.
#include <version>
#include <atomic>
#include <bit>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <type_traits>

#if defined(__EMSCRIPTEN__)
namespace std {

#if !defined(__cpp_lib_bit_cast)
template <class To, class From>
constexpr To bit_cast(const From& from) noexcept {
  static_assert(sizeof(To) == sizeof(From) && is_trivially_copyable_v<To> && is_trivially_copyable_v<From>);
  return __builtin_bit_cast(To, from);
}
#endif

#if !defined(__cpp_lib_atomic_ref)
#if defined(__EMSCRIPTEN_PTHREADS__)
#error "libcxx_compat.hpp: this libc++ has no std::atomic_ref and the build is multi-threaded"
#endif
template <class T>
class atomic_ref {  // one thread: loads and stores are plain
public:
  explicit atomic_ref(T& v) noexcept : v_(&v) {}
  T load(memory_order = memory_order_seq_cst) const noexcept { return *v_; }
  void store(T x, memory_order = memory_order_seq_cst) const noexcept { *v_ = x; }
  bool compare_exchange_strong(T& expected, T desired, memory_order = memory_order_seq_cst) const noexcept {
    if (*v_ == expected) { *v_ = desired; return true; }
    expected = *v_;
    return false;
  }
  T fetch_add(T x, memory_order = memory_order_seq_cst) const noexcept { T o = *v_; *v_ += x; return o; }

private:
  T* v_;
};
#endif

#if !defined(__cpp_lib_to_chars)
// Round-trip precision (9 / 17 significant digits), not the shortest form; vcar's browser flow
// writes binary PLY only, these serve the text writers that are compiled along.
inline to_chars_result to_chars(char* first, char* last, double v) {
  const int n = snprintf(first, static_cast<size_t>(last - first), "%.17g", v);
  if (n < 0 || n >= last - first) return {last, errc::value_too_large};
  return {first + n, errc{}};
}
inline to_chars_result to_chars(char* first, char* last, float v) {
  const int n = snprintf(first, static_cast<size_t>(last - first), "%.9g", static_cast<double>(v));
  if (n < 0 || n >= last - first) return {last, errc::value_too_large};
  return {first + n, errc{}};
}
#endif

#if !defined(__cpp_lib_to_chars)
// Parses the longest prefix strtod accepts (no leading whitespace or '+', as from_chars).
template <class F>
inline from_chars_result vcar_compat_from_chars(const char* first, const char* last, F& value) {
  char buf[128];
  const size_t n = static_cast<size_t>(last - first) < sizeof buf - 1 ? static_cast<size_t>(last - first) : sizeof buf - 1;
  if (n == 0 || first[0] == ' ' || first[0] == '\t' || first[0] == '\n' || first[0] == '+') return {first, errc::invalid_argument};
  memcpy(buf, first, n);
  buf[n] = '\0';
  char* end = nullptr;
  const double v = strtod(buf, &end);
  if (end == buf) return {first, errc::invalid_argument};
  value = static_cast<F>(v);
  return {first + (end - buf), errc{}};
}
inline from_chars_result from_chars(const char* first, const char* last, double& value, chars_format = chars_format::general) {
  return vcar_compat_from_chars(first, last, value);
}
inline from_chars_result from_chars(const char* first, const char* last, float& value, chars_format = chars_format::general) {
  return vcar_compat_from_chars(first, last, value);
}
#endif

}  // namespace std
#endif
