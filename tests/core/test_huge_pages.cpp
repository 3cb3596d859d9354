#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

#include "vcar/core/huge_pages.hpp"

namespace {
std::uintptr_t address_of(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }
}  // namespace

TEST_CASE("huge_pages: alignment is a huge page from 2 MiB up, a cache line below") {
  CHECK(vcar::huge_pages::alignment(1) == 64);
  CHECK(vcar::huge_pages::alignment(vcar::huge_pages::page - 1) == 64);
  CHECK(vcar::huge_pages::alignment(vcar::huge_pages::page) == vcar::huge_pages::page);
  for (std::size_t bytes : {std::size_t{1}, std::size_t{4096}, vcar::huge_pages::page, 3 * vcar::huge_pages::page + 5}) {
    void* p = vcar::huge_pages::allocate(bytes);
    CHECK(address_of(p) % vcar::huge_pages::alignment(bytes) == 0);
    static_cast<unsigned char*>(p)[bytes - 1] = 7;  // the whole size is usable
    CHECK(static_cast<unsigned char*>(p)[bytes - 1] == 7);
    vcar::huge_pages::release(p, bytes);
  }
}

TEST_CASE("HugePageAllocator: a vector keeps its values across growth, large ones start on a huge page") {
  struct alignas(64) Line {
    float v[16];
  };
  std::vector<Line, vcar::HugePageAllocator<Line>> a(10);
  CHECK(address_of(a.data()) % 64 == 0);
  for (std::size_t k = 0; k < a.size(); ++k) a[k].v[15] = static_cast<float>(k);
  const std::size_t big = vcar::huge_pages::page / sizeof(Line) + 3;  // past 2 MiB
  a.resize(big);
  CHECK(address_of(a.data()) % vcar::huge_pages::page == 0);
  std::size_t wrong = 0;
  for (std::size_t k = 0; k < 10; ++k) wrong += a[k].v[15] != static_cast<float>(k);
  CHECK(wrong == 0);
  CHECK(a.back().v[0] == 0.f);  // value-initialised
  std::vector<Line, vcar::HugePageAllocator<Line>> b = a;  // copies allocate their own
  CHECK(b.data() != a.data());
  CHECK(b[9].v[15] == 9.f);
  CHECK(vcar::HugePageAllocator<Line>() == vcar::HugePageAllocator<float>());
}
