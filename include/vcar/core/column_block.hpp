#pragma once
// One allocation for many per-element columns (structure of arrays). A state of n elements x
// b bytes faults in one page per 4 KiB on first touch: 100k ABR candidates (10 MB) cost about
// 2,500 page faults, 4 ms, more than the arithmetic that fills them. A block of 2 MiB or more
// is aligned to 2 MiB and advised to transparent huge pages where the OS has them (Linux
// madvise), so the same state faults in five times instead; elsewhere it is plain memory.
#include <cstddef>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <utility>

#if defined(__linux__) && !defined(__EMSCRIPTEN__)
#include <sys/mman.h>
#endif

namespace vcar {

namespace detail {
struct AlignedDelete {
  std::size_t alignment = 64;
  void operator()(std::byte* p) const noexcept { ::operator delete(p, std::align_val_t(alignment)); }
};
}  // namespace detail

class ColumnBlock {
 public:
  static constexpr std::size_t align = 64;                     // a cache line: SIMD loads never split
  static constexpr std::size_t huge_page = std::size_t{2} << 20;

  // Bytes one column of n elements of T takes in a block (whole cache lines).
  template <class T>
  static constexpr std::size_t room(std::size_t n) noexcept {
    return (n * sizeof(T) + align - 1) / align * align;
  }

  ColumnBlock() = default;
  ColumnBlock(ColumnBlock&& o) noexcept
      : data_(std::move(o.data_)), size_(std::exchange(o.size_, 0)), used_(std::exchange(o.used_, 0)) {}
  ColumnBlock& operator=(ColumnBlock&& o) noexcept {
    data_ = std::move(o.data_);
    size_ = std::exchange(o.size_, 0);
    used_ = std::exchange(o.used_, 0);
    return *this;
  }
  // A block of `bytes` (the sum of room() over its columns); contents uninitialised.
  // Throws std::bad_alloc when the memory is not there.
  explicit ColumnBlock(std::size_t bytes) : size_(bytes) {
    if (bytes == 0) return;
    const bool huge = bytes >= huge_page;
    const std::size_t alignment = huge ? huge_page : align;
    const std::size_t total = (bytes + alignment - 1) / alignment * alignment;  // whole huge pages
    data_ = std::unique_ptr<std::byte[], detail::AlignedDelete>(
        static_cast<std::byte*>(::operator new(total, std::align_val_t(alignment))), detail::AlignedDelete{alignment});
#if defined(__linux__) && !defined(__EMSCRIPTEN__) && defined(MADV_HUGEPAGE)
    if (huge) ::madvise(data_.get(), total, MADV_HUGEPAGE);  // advice only: failure leaves 4 KiB pages
#endif
  }

  // The next column of n elements of T, uninitialised (T trivial: the block never constructs
  // or destroys). Throws std::bad_alloc past the block's size: the caller's room() sum was short.
  template <class T>
  std::span<T> take(std::size_t n) {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
    static_assert(alignof(T) <= align);
    const std::size_t r = room<T>(n);
    if (r > size_ - used_) throw std::bad_alloc();
    T* p = reinterpret_cast<T*>(data_.get() + used_);
    used_ += r;
    return {p, n};
  }

  std::size_t size() const noexcept { return size_; }

 private:
  std::unique_ptr<std::byte[], detail::AlignedDelete> data_;
  std::size_t size_ = 0, used_ = 0;
};

}  // namespace vcar
