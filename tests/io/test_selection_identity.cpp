#include <catch2/catch.hpp>

#include <algorithm>
#include <numeric>

#include "io_test_util.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/selection_identity.hpp"

using vcar::io::gaussian_identities;
using vcar::io::locate_selection;
using vcar::io::selection_identity;
using vcar_test::require_error;

namespace {

vcar::GaussianScene four() {
  vcar::GaussianScene s;
  s.resize(4, 0);
  for (std::size_t i = 0; i < 4; ++i) s.set(i, {float(i), 1, 2}, {-1, -2, -3}, {1, 0, 0, 0}, 0.1f * float(i));
  return s;
}

}  // namespace

TEST_CASE("identity: FNV-1a 64 of the float bits, by hand for the empty and a one-float input") {
  // FNV-1a of the 4 bytes of 0.0f (all zero): offset basis times the prime, four times.
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (int b = 0; b < 4; ++b) h = (h ^ 0u) * 0x100000001b3ull;
  CHECK(vcar::io::detail::fnv1a(0xcbf29ce484222325ull, 0.f) == h);
  CHECK(vcar::io::detail::fnv1a(0xcbf29ce484222325ull, -0.f) == h);  // -0 is +0
  CHECK(vcar::io::detail::fnv1a(0xcbf29ce484222325ull, 1.f) != h);
  CHECK(vcar::io::identity_hex(0x0123456789abcdefull) == "0123456789abcdef");
  CHECK(vcar::io::identity_from_hex("0123456789ABCDEF", "t") == 0x0123456789abcdefull);
  require_error([] { vcar::io::identity_from_hex("xyz", "sel.json"); }, {"sel.json", "16 hexadecimal"});
}

TEST_CASE("identity: every rendered value counts; the fingerprint sees order only in `ordered`") {
  const vcar::GaussianScene s = four();
  const auto ids = gaussian_identities(s);
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j) CHECK(ids[i] != ids[j]);
  vcar::GaussianScene t = s;
  t.sh[5] += 1e-6f;  // Gaussian 1's DC blue
  CHECK(gaussian_identities(t)[1] != ids[1]);
  CHECK(gaussian_identities(t)[0] == ids[0]);
  t = s;
  t.rotation[2][3] = 1e-3f;
  CHECK(gaussian_identities(t)[3] != ids[3]);

  auto shuffled = ids;
  std::swap(shuffled[0], shuffled[3]);
  const auto a = vcar::io::scene_fingerprint(ids), b = vcar::io::scene_fingerprint(shuffled);
  CHECK(a.gaussians == 4);
  CHECK(a.unordered == b.unordered);
  CHECK(a.ordered != b.ordered);
}

TEST_CASE("locate_selection: same scene, re-sorted copy, other scene") {
  const vcar::GaussianScene s = four();
  const auto ids = gaussian_identities(s);
  const std::vector<vcar::Index> sel = {1, 3};
  const auto id = selection_identity(ids, sel);

  SECTION("the same scene: indices unchanged") {
    const auto r = locate_selection(ids, sel, id, "sel.json");
    CHECK(r.index == sel);
    CHECK_FALSE(r.reordered);
  }
  SECTION("a re-sorted copy: the same Gaussians at their new indices") {
    const std::vector<vcar::Index> order = {2, 3, 0, 1};  // new i holds old order[i]
    const vcar::GaussianScene r = s.subset(order);
    const auto loc = locate_selection(gaussian_identities(r), sel, id, "sel.json");
    CHECK(loc.reordered);
    CHECK(loc.index == std::vector<vcar::Index>{3, 1});  // old 1 is new 3, old 3 is new 1
    for (std::size_t k = 0; k < sel.size(); ++k) CHECK(r.mean[0][loc.index[k]] == s.mean[0][sel[k]]);
  }
  SECTION("a scene of another size, or an edited copy, is refused") {
    require_error([&] { locate_selection(gaussian_identities(s.subset({0, 1, 2})), sel, id, "sel.json"); },
                  {"sel.json", "4 Gaussians", "has 3"});
    vcar::GaussianScene e = s.subset({3, 2, 1, 0});
    e.opacity_logit[0] += 0.5f;  // old Gaussian 3, selected, edited
    require_error([&] { locate_selection(gaussian_identities(e), sel, id, "sel.json"); },
                  {"sel.json", "not the one the selection was made on", "1 of the 2", "refusing"});
  }
  SECTION("an index that does not match its recorded identity") {
    require_error([&] { locate_selection(ids, {0, 3}, id, "sel.json"); }, {"sel.json", "entry 0", "index 0"});
  }
}

TEST_CASE("locate_selection: identical Gaussians are interchangeable, each taken once") {
  vcar::GaussianScene s = four();
  s.mean[0][2] = s.mean[0][1];
  s.opacity_logit[2] = s.opacity_logit[1];  // Gaussians 1 and 2 are identical
  const auto ids = gaussian_identities(s);
  REQUIRE(ids[1] == ids[2]);
  const auto id = selection_identity(ids, {1, 2});
  const vcar::GaussianScene r = s.subset({1, 0, 3, 2});
  auto loc = locate_selection(gaussian_identities(r), {1, 2}, id, "t").index;
  std::sort(loc.begin(), loc.end());
  CHECK(loc == std::vector<vcar::Index>{0, 3});
}

TEST_CASE("identity survives a PLY round trip of a real scene") {
  vcar_test::TempDir tmp;
  const vcar::GaussianScene s = vcar::io::read_ply(std::filesystem::path(VCAR_TEST_DATA_DIR) / "train-1000.ply");
  std::vector<vcar::Index> rev(s.size());
  std::iota(rev.rbegin(), rev.rend(), vcar::Index{0});
  vcar::io::write_ply(tmp / "rev.ply", s, rev);
  const auto ids = gaussian_identities(s);
  const std::vector<vcar::Index> sel = {0, 10, 999};
  const auto loc = locate_selection(gaussian_identities(vcar::io::read_ply(tmp / "rev.ply")), sel, selection_identity(ids, sel), "t");
  CHECK(loc.index == std::vector<vcar::Index>{999, 989, 0});
}
