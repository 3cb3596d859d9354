#include <catch2/catch.hpp>

#include <cstdint>
#include <new>
#include <utility>

#include "vcar/core/column_block.hpp"

namespace {
std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }
}  // namespace

TEST_CASE("ColumnBlock: room is whole cache lines") {
  CHECK(vcar::ColumnBlock::room<float>(0) == 0);
  CHECK(vcar::ColumnBlock::room<float>(1) == 64);
  CHECK(vcar::ColumnBlock::room<float>(16) == 64);
  CHECK(vcar::ColumnBlock::room<float>(17) == 128);
  CHECK(vcar::ColumnBlock::room<std::uint16_t>(33) == 128);
  CHECK(vcar::ColumnBlock::room<double>(1000) == 8000);
}

TEST_CASE("ColumnBlock: columns are aligned, disjoint and hold what is written") {
  const std::size_t n = 1001;
  vcar::ColumnBlock block(vcar::ColumnBlock::room<float>(n) + vcar::ColumnBlock::room<std::uint16_t>(n) +
                          vcar::ColumnBlock::room<std::uint8_t>(3));
  auto a = block.take<float>(n);
  auto b = block.take<std::uint16_t>(n);
  auto c = block.take<std::uint8_t>(3);
  REQUIRE(a.size() == n);
  REQUIRE(b.size() == n);
  REQUIRE(c.size() == 3);
  for (const void* p : {static_cast<const void*>(a.data()), static_cast<const void*>(b.data()),
                        static_cast<const void*>(c.data())})
    CHECK(address(p) % vcar::ColumnBlock::align == 0);
  CHECK(address(a.data() + n) <= address(b.data()));
  CHECK(address(b.data() + n) <= address(c.data()));
  for (std::size_t k = 0; k < n; ++k) a[k] = static_cast<float>(k) + 0.5f, b[k] = static_cast<std::uint16_t>(3 * k);
  for (auto& v : c) v = 7;
  std::size_t wrong = 0;
  for (std::size_t k = 0; k < n; ++k) wrong += a[k] != static_cast<float>(k) + 0.5f || b[k] != 3 * k;
  CHECK(wrong == 0);
  // The block is full: one more column is a bad_alloc, not memory past its end.
  CHECK_THROWS_AS(block.take<std::uint8_t>(1), std::bad_alloc);
}

TEST_CASE("ColumnBlock: a block of 2 MiB or more starts on a huge-page boundary") {
  vcar::ColumnBlock block(vcar::huge_pages::page + 64);
  auto a = block.take<float>(vcar::huge_pages::page / sizeof(float) + 16);
  CHECK(address(a.data()) % vcar::huge_pages::page == 0);
  a.back() = 1.f;  // the last element is inside the block
  CHECK(a.back() == 1.f);
}

TEST_CASE("ColumnBlock: a move keeps the columns where they are") {
  vcar::ColumnBlock block(vcar::ColumnBlock::room<int>(100));
  auto a = block.take<int>(100);
  for (int k = 0; k < 100; ++k) a[static_cast<std::size_t>(k)] = k * k;
  vcar::ColumnBlock moved(std::move(block));
  CHECK(moved.size() == vcar::ColumnBlock::room<int>(100));
  CHECK(block.size() == 0);  // NOLINT(bugprone-use-after-move): the moved-from block is empty
  CHECK_THROWS_AS(block.take<int>(1), std::bad_alloc);
  CHECK(a[99] == 99 * 99);
  vcar::ColumnBlock assigned;
  assigned = std::move(moved);
  CHECK(a[50] == 2500);
  CHECK_THROWS_AS(assigned.take<int>(1), std::bad_alloc);  // still full
}
