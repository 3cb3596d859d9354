#pragma once
// One allocation for many per-element columns (structure of arrays). A state of n elements x
// b bytes faults in one page per 4 KiB on first touch: 100k ABR candidates (10 MB) cost about
// 2,500 page faults, 4 ms, more than the arithmetic that fills them. A block of 2 MiB or more
// is aligned to 2 MiB and advised to transparent huge pages where the OS has them
// (core/huge_pages.hpp), so the same state faults in five times instead.
#include <cstddef>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <utility>

#include "vcar/core/huge_pages.hpp"

namespace vcar {

namespace detail {
struct BlockDelete {
  std::size_t bytes = 0;
  void operator()(std::byte* p) const noexcept { huge_pages::release(p, bytes); }
};
}  // namespace detail

class ColumnBlock {
 public:
  static constexpr std::size_t align = huge_pages::line;  // a cache line: SIMD loads never split

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
    data_ = std::unique_ptr<std::byte[], detail::BlockDelete>(static_cast<std::byte*>(huge_pages::allocate(bytes)),
                                                              detail::BlockDelete{bytes});
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
  std::unique_ptr<std::byte[], detail::BlockDelete> data_;
  std::size_t size_ = 0, used_ = 0;
};

}  // namespace vcar
