#pragma once
// What identifies a selection's Gaussians across files: editors re-sort splats on load and save
// (SuperSplat and splat-transform write Morton order), so an index names a Gaussian only in the
// file it came from. A Gaussian's identity is a 64-bit FNV-1a hash of the float32 bits of
// everything the scene model renders (mean, log-scale, rotation, opacity logit, every SH
// coefficient; -0 hashed as +0); a scene's fingerprint is its size, an order-dependent hash and an
// order-independent one (the sum of mixed identities) of those identities. A selection carries the
// fingerprint of the scene it was made on and the identity of each selected Gaussian, so applying
// it to a scene either finds the very same Gaussians (same order, or the same multiset re-sorted)
// or throws vcar::Error saying why: it never silently picks others. Two Gaussians with the same
// identity are identical in every rendered value, so which of them a selection takes is moot.
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace vcar::io {

namespace detail {
inline std::uint64_t fnv1a(std::uint64_t h, float v) {
  if (v == 0.f) v = 0.f;  // -0 and +0 are the same value
  std::uint32_t u;
  std::memcpy(&u, &v, 4);
  for (int b = 0; b < 4; ++b) {
    h ^= (u >> (8 * b)) & 0xffu;
    h *= 0x100000001b3ull;
  }
  return h;
}
// splitmix64's finaliser: spreads an identity over all 64 bits before it is summed.
inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
}  // namespace detail

inline std::uint64_t gaussian_identity(const GaussianScene& s, std::size_t i) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (int d = 0; d < 3; ++d) h = detail::fnv1a(h, s.mean[d][i]);
  for (int d = 0; d < 3; ++d) h = detail::fnv1a(h, s.log_scale[d][i]);
  for (int k = 0; k < 4; ++k) h = detail::fnv1a(h, s.rotation[k][i]);
  h = detail::fnv1a(h, s.opacity_logit[i]);
  const std::size_t B3 = static_cast<std::size_t>(s.sh_coeffs()) * 3;
  for (std::size_t b = 0; b < B3; ++b) h = detail::fnv1a(h, s.sh[i * B3 + b]);
  return h;
}

inline std::vector<std::uint64_t> gaussian_identities(const GaussianScene& s) {
  std::vector<std::uint64_t> ids(s.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = gaussian_identity(s, i);
  return ids;
}

struct SceneFingerprint {
  std::uint64_t gaussians = 0;
  std::uint64_t ordered = 0;    // changes when the Gaussians are re-sorted
  std::uint64_t unordered = 0;  // the same for every order of the same Gaussians
  bool operator==(const SceneFingerprint&) const = default;
};

inline SceneFingerprint scene_fingerprint(const std::vector<std::uint64_t>& ids) {
  SceneFingerprint f;
  f.gaussians = ids.size();
  f.ordered = 0xcbf29ce484222325ull;
  for (std::uint64_t id : ids) {
    f.ordered = detail::mix64(f.ordered ^ id);
    f.unordered += detail::mix64(id);
  }
  return f;
}

inline std::string identity_hex(std::uint64_t v) {
  static const char* digits = "0123456789abcdef";
  std::string s(16, '0');
  for (int k = 15; k >= 0; --k, v >>= 4) s[static_cast<std::size_t>(k)] = digits[v & 0xf];
  return s;
}

inline std::uint64_t identity_from_hex(const std::string& s, const std::string& where) {
  if (s.size() != 16) throw Error("identity '" + s + "' is not 16 hexadecimal digits", where);
  std::uint64_t v = 0;
  for (char c : s) {
    const int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
    if (d < 0) throw Error("identity '" + s + "' is not 16 hexadecimal digits", where);
    v = v << 4 | static_cast<std::uint64_t>(d);
  }
  return v;
}

// What a selection knows about the scene it was made on: the fingerprint, and the identity of
// each selected Gaussian (aligned with the selection's indices).
struct SelectionIdentity {
  SceneFingerprint scene;
  std::vector<std::uint64_t> gaussians;
};

inline SelectionIdentity selection_identity(const std::vector<std::uint64_t>& scene_ids, const std::vector<Index>& indices) {
  SelectionIdentity s;
  s.scene = scene_fingerprint(scene_ids);
  s.gaussians.reserve(indices.size());
  for (Index i : indices) {
    if (i >= scene_ids.size()) throw Error("index " + std::to_string(i) + " out of range", "selection");
    s.gaussians.push_back(scene_ids[i]);
  }
  return s;
}

// Where the selected Gaussians are in a scene with identities `scene_ids`: entry k of the
// selection is Gaussian result.index[k]. Throws when the scene is not the selection's scene.
struct LocatedSelection {
  std::vector<Index> index;
  bool reordered = false;  // the scene is a re-sorted copy: indices differ from the file's
};

inline LocatedSelection locate_selection(const std::vector<std::uint64_t>& scene_ids, const std::vector<Index>& indices,
                                         const SelectionIdentity& id, const std::string& where) {
  if (id.gaussians.size() != indices.size())
    throw Error("the selection has " + std::to_string(indices.size()) + " indices but " + std::to_string(id.gaussians.size()) +
                " Gaussian identities", where);
  const SceneFingerprint here = scene_fingerprint(scene_ids);
  LocatedSelection out;
  if (here.gaussians != id.scene.gaussians)
    throw Error("the selection was made on a scene of " + std::to_string(id.scene.gaussians) + " Gaussians, this scene has " +
                std::to_string(here.gaussians), where);
  if (here == id.scene) {  // the same Gaussians in the same order
    for (std::size_t k = 0; k < indices.size(); ++k)
      if (indices[k] >= scene_ids.size() || scene_ids[indices[k]] != id.gaussians[k])
        throw Error("entry " + std::to_string(k) + " (index " + std::to_string(indices[k]) +
                    ") does not match the identity recorded for it (edited selection file?)", where);
    out.index = indices;
    return out;
  }
  // Every Gaussian of the scene by identity; equal identities are taken in ascending order.
  std::unordered_map<std::uint64_t, std::vector<Index>> where_is;
  where_is.reserve(scene_ids.size());
  for (std::size_t i = scene_ids.size(); i-- > 0;) where_is[scene_ids[i]].push_back(static_cast<Index>(i));
  std::size_t found = 0;
  out.index.resize(indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    auto it = where_is.find(id.gaussians[k]);
    if (it == where_is.end() || it->second.empty()) continue;
    out.index[k] = it->second.back();
    it->second.pop_back();
    ++found;
  }
  if (here.unordered != id.scene.unordered)
    throw Error("this scene is not the one the selection was made on (same size, other Gaussians: edited, re-quantised "
                "or another scene); " + std::to_string(found) + " of the " + std::to_string(indices.size()) +
                " selected Gaussians are in it, refusing to apply it", where);
  if (found != indices.size())  // cannot happen for equal multisets short of a hash collision
    throw Error(std::to_string(indices.size() - found) + " selected Gaussians are missing from a scene with the same fingerprint", where);
  out.reordered = true;
  return out;
}

}  // namespace vcar::io
