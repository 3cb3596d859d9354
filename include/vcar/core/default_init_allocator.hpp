#pragma once
// An allocator adaptor whose value-initialisation is default-initialisation: a
// std::vector<float, DefaultInitAllocator<float>> grows by resize() without writing its new
// floats. For buffers that a parallel loop fills at once: nothing is written twice, and each
// page is first touched (faulted in) by a thread that writes it, not by one serial memset.
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace vcar {

template <class T, class A = std::allocator<T>>
class DefaultInitAllocator : public A {
  using traits = std::allocator_traits<A>;

 public:
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename traits::template rebind_alloc<U>>;
  };
  using A::A;
  DefaultInitAllocator() = default;

  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;  // default-initialised: a scalar is left as it is
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    traits::construct(static_cast<A&>(*this), p, std::forward<Args>(args)...);
  }
};

// A vector whose resize() leaves new scalars unwritten.
template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace vcar
