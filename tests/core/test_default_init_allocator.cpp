#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include "vcar/core/default_init_allocator.hpp"

// UninitVector is a std::vector in every way but value-initialisation: what is written is kept,
// constructors with values construct them, and non-scalar elements are still constructed.
TEST_CASE("UninitVector keeps every value it is given, as std::vector does") {
  vcar::UninitVector<float> v;
  v.resize(1000);
  std::iota(v.begin(), v.end(), 0.f);
  v.resize(1500);  // grows (reallocates): the first 1000 move over
  for (std::size_t i = 0; i < 1000; ++i) REQUIRE(v[i] == static_cast<float>(i));
  v.resize(2000, 7.f);  // with a value: constructed from it
  for (std::size_t i = 1500; i < 2000; ++i) REQUIRE(v[i] == 7.f);
  v.push_back(-1.f);
  CHECK(v.back() == -1.f);
  CHECK(v.size() == 2001);

  const vcar::UninitVector<std::uint16_t> filled(300, 65535);
  CHECK(std::all_of(filled.begin(), filled.end(), [](std::uint16_t x) { return x == 65535; }));
  vcar::UninitVector<std::uint16_t> copy = filled;
  CHECK(copy == filled);

  vcar::UninitVector<std::string> s;  // a class type: default-initialised means constructed
  s.resize(3);
  CHECK(s[0].empty());
  s[2] = "kept";
  s.resize(10);
  CHECK(s[2] == "kept");
  CHECK(s[9].empty());
}
