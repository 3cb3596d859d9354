#pragma once
// The 3DGS scene as structure-of-arrays (conventions §1). Algorithms read only the columns they
// need: voting reads `mean`, ABR reads `mean`, `log_scale` and `rotation`, rendering reads all.
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vcar/core/error.hpp"
#include "vcar/core/rotation.hpp"

namespace vcar {

using Index = std::uint32_t;  // a Gaussian's index into its scene

// Per-axis log-scales for a set of Gaussians: column d holds log s_d.
using LogScales = std::array<std::vector<float>, 3>;

// How many opacity logits of +inf (fully opaque) and -inf (fully transparent) a scene had
// before GaussianScene::settle_infinite_opacities made them finite.
struct InfiniteOpacities {
  std::size_t opaque = 0, transparent = 0;
  std::size_t total() const noexcept { return opaque + transparent; }
  // "N Gaussians had infinite opacity logits: read as fully opaque/transparent" (empty if none).
  std::string message() const {
    if (total() == 0) return {};
    std::string what = opaque && transparent ? "fully opaque (" + std::to_string(opaque) + ") or transparent (" +
                                                   std::to_string(transparent) + ")"
                       : opaque              ? std::string("fully opaque")
                                             : std::string("fully transparent");
    return std::to_string(total()) + (total() == 1 ? " Gaussian had an infinite opacity logit" : " Gaussians had infinite opacity logits") +
           ": read as " + what;
  }
};

struct GaussianScene {
  std::array<std::vector<float>, 3> mean;       // mu: x, y, z (world units)
  std::array<std::vector<float>, 3> log_scale;  // log s_d
  std::array<std::vector<float>, 4> rotation;   // q = (w, x, y, z), unnormalised
  std::vector<float> opacity_logit;             // o; opacity = sigmoid(o)
  // Spherical-harmonics colour, degree 0-3, gsplat layout [i][k][c]: coefficient k of channel c
  // of Gaussian i at sh[(i * sh_coeffs() + k) * 3 + c]; k = 0 is the DC term (f_dc).
  int sh_degree = 0;
  std::vector<float> sh;
  // Properties the library does not interpret (normals, custom fields), kept so that a PLY
  // round trip loses nothing: extra[i * extra_names.size() + e] is property e of Gaussian i.
  std::vector<std::string> extra_names;
  std::vector<float> extra;

  std::size_t size() const noexcept { return opacity_logit.size(); }
  bool empty() const noexcept { return size() == 0; }
  int sh_coeffs() const noexcept { return (sh_degree + 1) * (sh_degree + 1); }

  // Allocates n Gaussians: identity rotations, zero everything else.
  void resize(std::size_t n, int degree = 0) {
    sh_degree = degree;
    for (auto& c : mean) c.assign(n, 0.f);
    for (auto& c : log_scale) c.assign(n, 0.f);
    rotation[0].assign(n, 1.f);
    for (int k = 1; k < 4; ++k) rotation[k].assign(n, 0.f);
    opacity_logit.assign(n, 0.f);
    sh.assign(n * static_cast<std::size_t>(sh_coeffs()) * 3, 0.f);
    extra.assign(n * extra_names.size(), 0.f);
  }

  Eigen::Vector3f mu(std::size_t i) const { return {mean[0][i], mean[1][i], mean[2][i]}; }
  Eigen::Vector3f scale(std::size_t i) const {
    return {std::exp(log_scale[0][i]), std::exp(log_scale[1][i]), std::exp(log_scale[2][i])};
  }
  Eigen::Matrix3f R(std::size_t i) const {
    return rotation_from_quaternion(rotation[0][i], rotation[1][i], rotation[2][i], rotation[3][i]);
  }
  float opacity(std::size_t i) const { return 1.f / (1.f + std::exp(-opacity_logit[i])); }
  // Sigma = R S S^T R^T (B.6).
  Eigen::Matrix3f Sigma(std::size_t i) const {
    const Eigen::Matrix3f M = R(i) * scale(i).asDiagonal();
    return M * M.transpose();
  }

  // Sets Gaussian i from ordinary values (convenience for tests and generators).
  void set(std::size_t i, const Eigen::Vector3f& mu_i, const Eigen::Vector3f& log_s,
           const Eigen::Vector4f& q_wxyz, float opacity_logit_i) {
    for (int d = 0; d < 3; ++d) { mean[d][i] = mu_i[d]; log_scale[d][i] = log_s[d]; }
    for (int k = 0; k < 4; ++k) rotation[k][i] = q_wxyz[k];
    opacity_logit[i] = opacity_logit_i;
  }
  // Sets the DC colour so that the degree-0 colour is `rgb` (inverse of rgb = 0.5 + C0 f_dc).
  void set_rgb(std::size_t i, const Eigen::Vector3f& rgb) {
    constexpr float C0 = 0.28209479177387814f;
    for (int c = 0; c < 3; ++c)
      sh[(i * static_cast<std::size_t>(sh_coeffs())) * 3 + c] = (rgb[c] - 0.5f) / C0;
  }

  // The Gaussians `indices` (in that order) as a new scene, every column included.
  GaussianScene subset(const std::vector<Index>& indices) const {
    GaussianScene out;
    out.extra_names = extra_names;
    out.resize(indices.size(), sh_degree);
    const std::size_t B3 = static_cast<std::size_t>(sh_coeffs()) * 3, E = extra_names.size();
    for (std::size_t k = 0; k < indices.size(); ++k) {
      const std::size_t i = indices[k];
      if (i >= size()) throw Error("subset index " + std::to_string(i) + " out of range", "subset");
      for (int d = 0; d < 3; ++d) { out.mean[d][k] = mean[d][i]; out.log_scale[d][k] = log_scale[d][i]; }
      for (int c = 0; c < 4; ++c) out.rotation[c][k] = rotation[c][i];
      out.opacity_logit[k] = opacity_logit[i];
      for (std::size_t b = 0; b < B3; ++b) out.sh[k * B3 + b] = sh[i * B3 + b];
      for (std::size_t e = 0; e < E; ++e) out.extra[k * E + e] = extra[i * E + e];
    }
    return out;
  }

  // The finite logits that stand for +inf / -inf: in float, sigmoid(100) is exactly 1 and
  // sigmoid(-100) exactly 0 (exp(100) overflows), so opacities are those the file meant.
  static constexpr float opaque_logit = 100.f, transparent_logit = -100.f;

  // Opacity logits of +inf / -inf (converters write them for opacity 1 / 0: splat-transform
  // 2.7.1 does) replaced by opaque_logit / transparent_logit; returns how many of each. NaN
  // logits and infinities in any other column stay, for validate to refuse.
  InfiniteOpacities settle_infinite_opacities() {
    InfiniteOpacities n;
    for (float& o : opacity_logit) {
      if (o == INFINITY) { o = opaque_logit; ++n.opaque; }
      else if (o == -INFINITY) { o = transparent_logit; ++n.transparent; }
    }
    return n;
  }

  // Throws vcar::Error naming the first bad Gaussian: column sizes that disagree, NaN/Inf in any
  // value, or a zero quaternion.
  void validate(const std::string& where = "scene") const {
    const std::size_t n = size();
    auto same = [&](const std::vector<float>& c, const char* what, std::size_t per) {
      if (c.size() != n * per)
        throw Error(std::string("column '") + what + "' has " + std::to_string(c.size()) +
                    " values, expected " + std::to_string(n * per), where);
    };
    for (auto& c : mean) same(c, "mean", 1);
    for (auto& c : log_scale) same(c, "log_scale", 1);
    for (auto& c : rotation) same(c, "rotation", 1);
    if (sh_degree < 0 || sh_degree > 3) throw Error("SH degree must be 0..3", where);
    same(sh, "sh", static_cast<std::size_t>(sh_coeffs()) * 3);
    same(extra, "extra", extra_names.size());
    const std::size_t B3 = static_cast<std::size_t>(sh_coeffs()) * 3;
    for (std::size_t i = 0; i < n; ++i) {
      bool finite = std::isfinite(opacity_logit[i]);
      for (int d = 0; d < 3; ++d) finite = finite && std::isfinite(mean[d][i]) && std::isfinite(log_scale[d][i]);
      float qq = 0.f;
      for (int c = 0; c < 4; ++c) { finite = finite && std::isfinite(rotation[c][i]); qq += rotation[c][i] * rotation[c][i]; }
      for (std::size_t b = 0; b < B3; ++b) finite = finite && std::isfinite(sh[i * B3 + b]);
      if (!finite) throw Error("Gaussian " + std::to_string(i) + " has a NaN or infinite value", where);
      if (!(qq > 0.f)) throw Error("Gaussian " + std::to_string(i) + " has a zero quaternion", where);
    }
  }
};

}  // namespace vcar
