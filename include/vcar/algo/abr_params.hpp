#pragma once
// The parameters of axis-aware boundary refinement (Eq. 9-14, supplementary B.3): their own
// header, so that what holds parameters (algo/params.hpp) needs none of ABR's code.
#include <cmath>
#include <string>

#include "vcar/core/error.hpp"
#include "vcar/core/projection.hpp"

namespace vcar {

struct AbrParams {
  float sigma_c = 3.f;           // ellipse cutoff in standard deviations (Eq. 9), default 3
  float rho = 0.6f;              // overflow-ratio gate, update when gamma > rho (B.3), default 0.6
  float f_min = 0.1f;            // lower bound of the compression factor (Eq. 13, B.3), default 0.1
  int boundary_samples = 129;    // samples from centre to endpoint for l_u (B.3), default 129
  bool reference_code_rules = false;  // conventions §7: the released code's compression rules
  ProjectionParams projection;   // near/far plane, eps2d, Jacobian clamp (conventions §3)

  // Throws vcar::Error naming the parameter out of range.
  void validate() const {
    const std::string where = "AbrParams";
    if (!(sigma_c > 0.f) || !std::isfinite(sigma_c)) throw Error("sigma_c must be positive", where + ".sigma_c");
    if (!(rho >= 0.f && rho < 1.f)) throw Error("rho must be in [0, 1)", where + ".rho");
    if (!(f_min > 0.f && f_min <= 1.f)) throw Error("f_min must be in (0, 1]", where + ".f_min");
    if (boundary_samples < 2) throw Error("boundary_samples must be at least 2", where + ".boundary_samples");
    if (!(projection.eps2d >= 0.f)) throw Error("eps2d must be non-negative", where + ".projection.eps2d");
  }
};

}  // namespace vcar
