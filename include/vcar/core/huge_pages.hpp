#pragma once
// Large arrays on transparent huge pages where the OS has them (Linux madvise), plain aligned
// memory elsewhere. An array of 2 MiB or more is aligned to 2 MiB and advised before its first
// touch, so it faults in one page per 2 MiB instead of one per 4 KiB, and reading it at random
// misses the TLB far less (the renderer's 64-byte splats: 64 MB at 1M, read in tile order).
// Smaller arrays get cache-line alignment only.
#include <cstddef>
#include <new>

#if defined(__linux__) && !defined(__EMSCRIPTEN__)
#include <sys/mman.h>
#endif

namespace vcar {

namespace huge_pages {

inline constexpr std::size_t page = std::size_t{2} << 20;
inline constexpr std::size_t line = 64;

// The alignment an array of `bytes` gets: a huge page from one page up, else a cache line.
constexpr std::size_t alignment(std::size_t bytes) noexcept { return bytes >= page ? page : line; }

// `bytes` rounded up to whole units of alignment(bytes), uninitialised; advised to huge pages
// when that alignment is a huge page (advice only: where it fails, 4 KiB pages). Throws
// std::bad_alloc. Free with release(p, bytes).
inline void* allocate(std::size_t bytes) {
  const std::size_t a = alignment(bytes);
  const std::size_t total = (bytes + a - 1) / a * a;
  void* p = ::operator new(total, std::align_val_t(a));
#if defined(__linux__) && !defined(__EMSCRIPTEN__) && defined(MADV_HUGEPAGE)
  if (a == page) ::madvise(p, total, MADV_HUGEPAGE);
#endif
  return p;
}
inline void release(void* p, std::size_t bytes) noexcept { ::operator delete(p, std::align_val_t(alignment(bytes))); }

}  // namespace huge_pages

// A standard allocator over huge_pages (std::vector<T, HugePageAllocator<T>>): T must not need
// more than 64-byte alignment.
template <class T>
struct HugePageAllocator {
  static_assert(alignof(T) <= huge_pages::line);
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(huge_pages::allocate(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { huge_pages::release(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

}  // namespace vcar
