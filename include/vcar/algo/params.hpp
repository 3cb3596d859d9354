#pragma once
// Every parameter of VCAR (paper Sec. 4.2, supplementary A.1, conventions §5) with its paper
// name, plus the switches that reach the released reference code (conventions §7) and the
// extensions beyond the paper (off in the paper presets; VcarParams::robust() is the default).
// Text forms (`--set key=value`, JSON) live in io/params_text.hpp.
#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>
#include <utility>

#include <Eigen/Core>

#include "vcar/algo/abr_params.hpp"
#include "vcar/core/error.hpp"

namespace vcar {

// Where the spiral positions live (Eq. 8). Paper: the frame whose third axis is the estimated
// scene up. ReferenceCode: the world axes as given (third axis world +z), as the released code.
enum class SpiralVariant { Paper, ReferenceCode };
// Intrinsics of the sampled views: the reference view's, or the reference code's 45 degree
// field of view on the short side with a centred principal point (same image size).
enum class SampledIntrinsics { ReferenceView, ReferenceCode45Fov };
// ABR compression rule (Eq. 12-13). ReferenceCode: compress only when (l/3)^2 < lambda and
// take the dominant share of lambda in proportion w_d / sum w (conventions §7).
enum class AbrVariant { Paper, ReferenceCode };

struct VcarParams {
  // --- Stage 1 and 2: visibility-based weighted voting ----------------------------------
  float tau_coarse = 0.5f;   // Eq. 3: coarse threshold on R_i (nvos 0.5, lerf 0.4)
  float tau_fine = 0.8f;     // Eq. 3: fine threshold on R_i (nvos 0.8, lerf 0.6, code 0.9)
  // --- Stage 2: object sphere, view completeness, spiral --------------------------------
  float eta = 1.2f;          // Eq. 5: sphere radius factor (paper 1.2, code 1.1)
  float rho_min = 0.2f;      // A.1: valid-camera visible fraction rho^(j) >= rho_min (code 0.01)
  int K = 2000;              // Eq. 6, A.3: Fibonacci probe directions
  float Delta_th_deg = 90.f; // Eq. 6: SSS runs when Delta_max > Delta_th (degrees)
  int S1 = 4;                // Eq. 7: spiral revolutions
  int S2 = 8;                // Eq. 7: points per revolution (N_s = S1 S2)
  float phi_s_deg = -60.f;   // Eq. 7: first elevation (degrees; code +60)
  float phi_e_deg = 60.f;    // Eq. 7: last elevation (degrees; code -10)
  // --- Stage 3: axis-aware boundary refinement -------------------------------------------
  float sigma_c = 3.f;       // Eq. 9: ellipse cutoff, semi-axes sigma_c sqrt(lambda) (default 3)
  float rho = 0.6f;          // B.3: overflow-ratio gate, refine when ratio > rho (strict) (0.6)
  float f_min = 0.1f;        // Eq. 13: lower clamp of the compression factor, in (0, 1] (0.1)
  int boundary_samples = 129;  // B.3: samples from the centre to each endpoint for l_u (129)
  // --- Switches ---------------------------------------------------------------------------
  bool enable_sss = true;    // Sec. 3.3: run view completeness + spiral sampling
  bool enable_abr = true;    // Sec. 3.4: run ABR
  bool force_sss = false;    // ablation: sample the spiral whatever Delta_max is
  // Beyond the paper: a Gaussian counts as visible only when not behind the rendered surface,
  // z <= (depth / alpha)(pixel) * (1 + depth_tolerance) (see visibility_voting.hpp).
  bool occlusion_aware = false;
  float depth_tolerance = 0.05f;
  // Beyond the paper: instead of the full spiral, a few views in a cone around the largest
  // gap direction (spiral_sampler.hpp gap_directed_cameras).
  bool gap_directed = false;
  int gap_directed_views = 8;
  float gap_directed_cone_deg = 30.f;  // half-angle of the cone around the gap direction
  SpiralVariant spiral_variant = SpiralVariant::Paper;
  SampledIntrinsics sampled_intrinsics = SampledIntrinsics::ReferenceView;
  float sampled_fov_deg = 45.f;  // field of view on the short side for ReferenceCode45Fov
  // Background (RGB in [0,1]) of the renders handed to the segmenter (paper: black; code white).
  Eigen::Vector3f background = Eigen::Vector3f::Zero();
  // --- Reference-code differences (conventions §7), off in the paper presets ----------------
  AbrVariant abr_variant = AbrVariant::Paper;
  // Frames whose fraction of non-background pixels is under this are not segmented (the
  // prompt frame is always kept). 0 = off (paper); code 0.005.
  float min_frame_content = 0.f;
  // A mask whose foreground fraction is <= this counts as no mask. 0 = off (paper); code 0.001.
  float min_mask_fraction = 0.f;
  // The released NVOS protocol re-renders the training views from G_coarse and votes them
  // again (tau_fine) even when SSS does not trigger (its force_round2). Off in the paper.
  bool force_fine_round = false;
  // Eq. 9-13 read Sigma2D with the renderer's eps2d low-pass (conventions §3, true) or the
  // Gaussian's own footprint (false: overflow within ~1.6 px no longer forces f_min). Eq. R8
  // reads the own footprint after a split fine vote whatever this says.
  bool abr_lowpass = true;
  // --- Beyond the paper: vcar's mechanisms (docs/robust.md), one group each, every one off in
  // the paper presets. Their text keys (`--set`, JSON, Python) are flat: for_each_field below.
  // Eq. R2-R3, the evidence levels. R3: a Gaussian behind the view's rendered surface,
  // z > (depth / alpha)(p) (1 + depth_tolerance) where alpha(p) >= 0.5, is occluded there
  // (evidence of the lower "plain" level only), in both rounds: the coarse round against renders
  // of the scene, the fine round against renders of G_coarse. R2: kappa, the prior weight in
  // views that ties each level's ratio to the one below.
  struct Evidence {
    bool occlusion = false;
    float kappa = 2.f;
  } evidence;
  // Eq. R6, R6c and R8, the undershoot correction (band 0 = off). R6: in the fine round,
  // background pixels within band e_j px of the mask are no evidence, e_j the mask's undershoot
  // measured against the render of G_coarse (R6a); R6c: only where the vote without it is split
  // (Eq. R7), so a decisive vote without it is the result. R8: when the fine vote is split, ABR
  // reads each training view's mask widened by e_j, and the Gaussians' own footprints (no
  // low-pass). R6c and R8 need R7.
  struct Undershoot {
    float band = 0.f;
  } undershoot;
  // Eq. R14, the fine round's threshold read from its own vote where the round's masks
  // measurably undershoot (the median of R6a's e_j over its masked frames is positive; R6a runs
  // where undershoot.band > 0): the emptiest bin of the fine vote's ratio histogram between
  // tau_coarse and its fullest bin (vote_valley.hpp), in place of tau_fine; R8 reads the
  // vote as split where R14's threshold is applied below tau_fine. robust: on (it replaced R6d's
  // fixed 0.7 on 2026-12-06).
  struct Valley {
    bool enabled = false;
  } valley;
  // Eq. R7, the strict threshold: the fine round keeps tau instead of its threshold (tau_fine, or
  // R14's) when the vote is decisive, i.e. when at most a fraction 0.1 (split_fraction,
  // decisive_threshold.hpp) of the Gaussians kept at that threshold fall below tau, for the
  // candidates seen unoccluded in at least a fifth of their views (seen_fraction); tau <= that
  // threshold (0) = off.
  struct Strict {
    float tau = 0.f;
  } strict;
  // Eq. R11-R12, the signed snap of each mask to the occlusion edges of the view's render (depth
  // steps over depth_tolerance; the render is asked for depth), one estimate and one switch: o_j,
  // the contour's median signed distance outside those edges, and its quartiles q1_j, q3_j
  // (Eq. R11b). R11: o_j >= o_min and q1_j >= 0, the mask is eroded by o_j + m before it is
  // voted and kept for ABR: in the coarse round, and in the fine round once the coarse round
  // eroded a mask (o_min = max(1 px, 0.005 |diag|), m = max(1.5 px, 0.0075 |diag|), |diag| the
  // image diagonal: 1 and 1.5 px at 160 x 120, 4 and 6 px at 640 x 480). R12: q3_j < 1 px
  // (coarse round), the mask grows by the covered,
  // depth-continuous pixels between its contour and the edges, by at most min(-o_j + 1 px,
  // 0.1 |image diagonal|, r_M), r_M = sqrt(|M| / pi) the mask's radius. A contour on both sides
  // of the edges (a mask shifted off the object) is left as it is.
  // (The constants: overshoot.hpp, occlusion_growth.hpp. Until 2026-12-03 four fields,
  // overshoot_min, overshoot_margin, grow_max and grow_margin.)
  struct Snap {
    bool enabled = false;
  } snap;
  // Eq. R13: after each round's vote, every view is weighted by how its mask agrees with the
  // round's consensus (Jaccard on the candidates it sees, unoccluded by R3 where that is on), and
  // the vote is taken again with the weights (view_reliability.hpp).
  struct Reliability {
    bool enabled = false;
  } reliability;

  // Paper defaults for NVOS (Sec. 4.2).
  static VcarParams nvos() { return VcarParams{}; }
  // Paper defaults for LERF: lower thresholds for small objects (Sec. 4.2; tau_fine in 0.5-0.7).
  static VcarParams lerf() {
    VcarParams p;
    p.tau_coarse = 0.4f;
    p.tau_fine = 0.6f;
    return p;
  }
  // The released reference code's values (conventions §7), NVOS thresholds. The spiral frame
  // stays the scene-up frame (conventions §7 fixes the code's z-up/y-up mix); set
  // spiral_variant=ReferenceCode for the code's world-axis positions.
  static VcarParams reference_code() {
    VcarParams p;
    p.tau_fine = 0.9f;
    p.rho_min = 0.01f;
    p.phi_s_deg = 60.f;
    p.phi_e_deg = -10.f;
    p.eta = 1.1f;
    p.sampled_intrinsics = SampledIntrinsics::ReferenceCode45Fov;
    p.background = Eigen::Vector3f::Ones();
    p.abr_variant = AbrVariant::ReferenceCode;
    p.min_frame_content = 0.005f;
    p.min_mask_fraction = 0.001f;
    p.force_fine_round = true;
    return p;
  }
  // vcar's default (beyond the paper, docs/robust.md): the paper's thresholds (tau_coarse 0.5,
  // tau_fine 0.8), the evidence levels (R2) with the occlusion test in both rounds (R3), the fine
  // round's band as wide as the masks' measured undershoot (R6) where the vote without it splits
  // (R6c), the fine threshold at the valley of the fine vote's ratios (R14), the strict threshold
  // 0.85 when the fine vote is decisive against it (R7), ABR on masks widened by their undershoot
  // when it is split, on their own footprints (R8), each mask snapped to the render's occlusion
  // edges where three quarters of its contour agree: eroded where it reaches 1 px or more past
  // them (R11), grown to them where it stops short (R12), and each view weighted by how its mask
  // agrees with the round's consensus (R13);
  // the spiral's elevations from -10 degrees, the released code's lowest, not the paper's -60
  // (below the floor the piece of it in G_coarse hides the object's underside from the
  // segmenter: docs/notes/field-spiral-2026-12-04.md). What vcar::segment uses when given no
  // parameters. Chosen on the field's tuning seeds and the synthetic suite
  // (docs/notes/default-2026-12-02.md; the snap's conditions on SAM-like drift,
  // docs/notes/default-2026-12-03.md; R14, docs/notes/field-valley-2026-12-06.md), R13 on
  // (SAM-like drift). (R1, R4, R5, R9, R6d and R10 were removed: inert in every preset, never better
  // on the field, or replaced; docs/robust.md, appendix.)
  static VcarParams robust() {
    VcarParams p;
    p.phi_s_deg = -10.f;  // Eq. 7's first elevation: the released code's lowest
    p.evidence.occlusion = true;
    p.undershoot.band = 1.5f;
    p.valley.enabled = true;
    p.strict.tau = 0.85f;
    p.snap.enabled = true;
    p.reliability.enabled = true;
    return p;
  }
  // A preset by name: robust, nvos, lerf, reference_code; vcar::Error otherwise.
  static VcarParams preset(std::string_view name) {
    if (name == "robust") return robust();
    if (name == "nvos") return nvos();
    if (name == "lerf") return lerf();
    if (name == "reference_code") return reference_code();
    throw Error("unknown preset '" + std::string(name) + "'; valid: robust, nvos, lerf, reference_code", "preset");
  }

  // ABR's parameters (Eq. 9-14, B), derived: the one place they are read from VcarParams.
  AbrParams abr() const {
    AbrParams a;
    a.sigma_c = sigma_c;
    a.rho = rho;
    a.f_min = f_min;
    a.boundary_samples = boundary_samples;
    a.reference_code_rules = abr_variant == AbrVariant::ReferenceCode;
    if (!abr_lowpass) a.projection.eps2d = 0.f;  // the Gaussian's own footprint
    return a;
  }

  // True when a mechanism beyond the paper changes the vote (RobustVoting, Eq. R2-R13).
  bool robust_vote() const {
    return evidence.occlusion || undershoot.band > 0.f || reliability.enabled;
  }

  // Calls f(name, field) for every field, names exactly as declared (const and non-const).
  template <class Self, class F>
  static void for_each_field(Self& p, F&& f) {
    f("tau_coarse", p.tau_coarse); f("tau_fine", p.tau_fine); f("eta", p.eta);
    f("rho_min", p.rho_min); f("K", p.K); f("Delta_th_deg", p.Delta_th_deg);
    f("S1", p.S1); f("S2", p.S2); f("phi_s_deg", p.phi_s_deg); f("phi_e_deg", p.phi_e_deg);
    f("sigma_c", p.sigma_c); f("rho", p.rho); f("f_min", p.f_min);
    f("boundary_samples", p.boundary_samples);
    f("enable_sss", p.enable_sss); f("enable_abr", p.enable_abr); f("force_sss", p.force_sss);
    f("occlusion_aware", p.occlusion_aware); f("depth_tolerance", p.depth_tolerance);
    f("gap_directed", p.gap_directed); f("gap_directed_views", p.gap_directed_views);
    f("gap_directed_cone_deg", p.gap_directed_cone_deg); f("spiral_variant", p.spiral_variant);
    f("sampled_intrinsics", p.sampled_intrinsics); f("sampled_fov_deg", p.sampled_fov_deg);
    f("background", p.background); f("abr_variant", p.abr_variant);
    f("min_frame_content", p.min_frame_content); f("min_mask_fraction", p.min_mask_fraction);
    f("force_fine_round", p.force_fine_round);
    f("occlusion", p.evidence.occlusion); f("kappa", p.evidence.kappa);
    f("undershoot_band", p.undershoot.band); f("valley", p.valley.enabled);
    f("tau_strict", p.strict.tau); f("abr_lowpass", p.abr_lowpass);
    f("snap", p.snap.enabled);
    f("view_reliability", p.reliability.enabled);
  }

  // Throws vcar::Error naming the first parameter outside its range.
  void validate() const {
    auto bad = [](const char* name, const std::string& why) { throw Error(why, name); };
    auto unit = [&](const char* name, float v) {
      if (!(v >= 0.f && v <= 1.f)) bad(name, "must be in [0, 1], got " + std::to_string(v));
    };
    unit("tau_coarse", tau_coarse);
    unit("tau_fine", tau_fine);
    unit("rho_min", rho_min);
    if (!(eta > 0.f && std::isfinite(eta))) bad("eta", "must be positive");
    if (K < 1) bad("K", "must be >= 1, got " + std::to_string(K));
    if (!(Delta_th_deg >= 0.f && Delta_th_deg <= 180.f)) bad("Delta_th_deg", "must be in [0, 180]");
    if (S1 < 1) bad("S1", "must be >= 1, got " + std::to_string(S1));
    if (S2 < 1) bad("S2", "must be >= 1, got " + std::to_string(S2));
    if (!(std::abs(phi_s_deg) <= 90.f)) bad("phi_s_deg", "must be in [-90, 90]");
    if (!(std::abs(phi_e_deg) <= 90.f)) bad("phi_e_deg", "must be in [-90, 90]");
    try {  // sigma_c, rho, f_min, boundary_samples: AbrParams owns their ranges
      abr().validate();
    } catch (const Error& e) {
      const std::string prefix = "AbrParams.";
      const std::string key = e.where().rfind(prefix, 0) == 0 ? e.where().substr(prefix.size()) : e.where();
      const std::string what = e.what();
      bad(key.c_str(), what.substr(std::min(what.size(), e.where().size() + 2)));
    }
    if (!(depth_tolerance >= 0.f && std::isfinite(depth_tolerance))) bad("depth_tolerance", "must be >= 0");
    if (gap_directed_views < 1) bad("gap_directed_views", "must be >= 1");
    if (!(gap_directed_cone_deg >= 0.f && gap_directed_cone_deg < 180.f))
      bad("gap_directed_cone_deg", "must be in [0, 180)");
    if (!(sampled_fov_deg > 0.f && sampled_fov_deg < 180.f)) bad("sampled_fov_deg", "must be in (0, 180)");
    if (!((background.array() >= 0.f).all() && (background.array() <= 1.f).all()))
      bad("background", "each channel must be in [0, 1]");
    unit("min_frame_content", min_frame_content);
    unit("min_mask_fraction", min_mask_fraction);
    if (!(evidence.kappa >= 0.f && std::isfinite(evidence.kappa))) bad("kappa", "must be >= 0, got " + std::to_string(evidence.kappa));
    if (!(undershoot.band >= 0.f && undershoot.band <= 100.f))
      bad("undershoot_band", "must be in [0, 100] (0 = off), got " + std::to_string(undershoot.band));
    unit("tau_strict", strict.tau);
  }

};

}  // namespace vcar
