#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "vcar/core/scratch_vector.hpp"

TEST_CASE("scratch_vector: resize does not zero trivial elements, values and fills are std::vector's") {
  // The memory a resize reuses keeps what it held (std::vector would write zeros over it).
  vcar::scratch_vector<unsigned char> v;
  v.assign(1000, 7);
  const unsigned char* before = v.data();
  v.clear();
  v.resize(1000);
  REQUIRE(v.data() == before);  // the same storage (capacity kept)
  std::size_t sevens = 0;
  for (unsigned char c : v) sevens += c == 7;
  CHECK(sevens == 1000);
  // Values survive growth; explicit fills and copies behave as std::vector's.
  vcar::scratch_vector<int> a;
  for (int k = 0; k < 5000; ++k) a.push_back(k);
  a.resize(6000, -1);
  CHECK(a[4999] == 4999);
  CHECK(a[5000] == -1);
  CHECK(a[5999] == -1);
  const vcar::scratch_vector<int> b(3, 4);
  CHECK(std::vector<int>(b.begin(), b.end()) == std::vector<int>{4, 4, 4});
}

TEST_CASE("scratch_vector: types with constructors are still constructed") {
  vcar::scratch_vector<std::string> s(3);  // default-initialisation of a class: its constructor
  CHECK(s[2].empty());
  s.emplace_back(4, 'x');                 // arguments are forwarded
  CHECK(s.back() == "xxxx");
  struct WithDefault {
    int value = 5;
  };
  vcar::scratch_vector<WithDefault> c(4);
  CHECK(c[3].value == 5);
}
