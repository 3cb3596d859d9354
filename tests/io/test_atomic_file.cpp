#include <catch2/catch.hpp>

#include <stdexcept>

#include "io_test_util.hpp"
#include "vcar/io/atomic_file.hpp"

using vcar_test::TempDir;
using vcar_test::read_bytes;

namespace {
std::size_t count_files(const std::filesystem::path& d) {
  std::size_t n = 0;
  for (auto& e : std::filesystem::directory_iterator(d)) { (void)e; ++n; }
  return n;
}
}  // namespace

TEST_CASE("atomic_write replaces the file only on success") {
  TempDir tmp;
  const auto p = tmp / "f.txt";
  vcar::io::atomic_write(p, [](std::ostream& o) { o << "first"; });
  CHECK(read_bytes(p) == "first");
  vcar::io::atomic_write(p, [](std::ostream& o) { o << "second"; });
  CHECK(read_bytes(p) == "second");
  CHECK_THROWS_AS(vcar::io::atomic_write(p, [](std::ostream& o) {
    o << "half";
    throw std::runtime_error("writer failed");
  }), std::runtime_error);
  CHECK(read_bytes(p) == "second");
  CHECK(count_files(tmp.path) == 1);  // the temporary file is gone
  CHECK_THROWS_AS(vcar::io::atomic_write(tmp / "missing_dir" / "g.txt", [](std::ostream& o) { o << "x"; }),
                  vcar::Error);
  CHECK(count_files(tmp.path) == 1);
}
