#pragma once
// A std::vector whose resize leaves new elements of a trivial type uninitialised (default-
// initialisation) instead of zeroing them: for large arrays that a parallel loop then writes
// whole. std::vector's value-initialising resize would first zero them serially on the calling
// thread (voting's sorted means, counters and Morton keys: 36 MB per call at 1M Gaussians,
// while the other threads wait).
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace vcar {

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  // No arguments: default-initialise (trivial types keep whatever the memory held).
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// resize(n) and vector(n) leave trivial elements uninitialised; assign, push_back and
// resize(n, value) behave as std::vector's.
template <class T>
using scratch_vector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace vcar
