#pragma once
// What one vcar::segment call did (SegmentationResult::diagnostics): the sizes of G_coarse,
// G_fine and G*, the view completeness (Eq. 6) and its sphere (Eq. 4-5), the sampled views
// (Eq. 7-8), ABR's counts (Eq. 9-14), what the rules beyond the paper changed, and the stage
// timings. Diagnostics::for_each_field names every field once, for every writer (report.json:
// io/diagnostics_json.hpp; the Python module's dict).
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "vcar/algo/robust_sphere.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace vcar {

struct Diagnostics {
  std::size_t n_scene = 0;          // Gaussians in the scene
  std::size_t n_coarse = 0;         // |G_coarse|
  std::size_t n_fine = 0;           // |G_fine| (= n_coarse when SSS did not run)
  std::size_t n_final = 0;          // selected after ABR (ABR changes scales, not membership)
  std::size_t valid_cameras = 0;    // |V_valid| (A.1)
  double max_gap_deg = 0;           // Delta_max (Eq. 6)
  Eigen::Vector3f gap_direction = Eigen::Vector3f::Zero();
  bool sss_triggered = false;
  float tau_fine_applied = 0.f;     // the fine round's threshold (Eq. 3, R14, R7: tau_fine, the vote's valley or tau_strict); 0: no fine round
  bool undershoot_applied = false;  // Eq. R6 shaped the fine vote (on, and its gate R6c found the vote without it split)
  bool fine_split = false;          // the fine vote read as split (Eq. R7 found it so, or R14's threshold < tau_fine): R8 on
  std::vector<Camera> sampled_cameras;  // V_sampled
  ObjectSphere sphere{};
  std::size_t abr_flagged = 0, abr_compressed = 0;
  std::size_t abr_retraced = 0;     // flagged candidates refined once more, alone (BoundaryRefinement::defer_tracing)
  std::size_t abr_masks_widened = 0; // training masks ABR read widened by their undershoot (Eq. R8)
  std::size_t overshoot_eroded = 0;  // masks voted eroded by their measured overshoot (Eq. R11), every round
  std::size_t masks_grown = 0;       // coarse-round masks voted grown to the render's occlusion edges (Eq. R12)
  std::size_t masks_missing = 0;    // frames the segmenter answered with "no mask"
  std::size_t mask_store_bytes = 0; // run-length bytes held for ABR
  std::string note;                 // why the pipeline stopped early, or kept G_coarse (a fine round without masks)
  std::vector<std::pair<std::string, double>> timings_s;  // stage -> seconds, in order

  // Calls f(name, key, field) for every field: `name` as declared (the Python dict's keys),
  // `key` its place in report.json ("counts.coarse": {"counts": {"coarse": ...}}).
  template <class Self, class F>
  static void for_each_field(Self& d, F&& f) {
    f("n_scene", "counts.scene", d.n_scene);
    f("n_coarse", "counts.coarse", d.n_coarse);
    f("n_fine", "counts.fine", d.n_fine);
    f("n_final", "counts.final", d.n_final);
    f("valid_cameras", "valid_cameras", d.valid_cameras);
    f("max_gap_deg", "max_gap_deg", d.max_gap_deg);
    f("gap_direction", "gap_direction", d.gap_direction);
    f("sss_triggered", "sss_triggered", d.sss_triggered);
    f("tau_fine_applied", "tau_fine_applied", d.tau_fine_applied);
    f("undershoot_applied", "undershoot_applied", d.undershoot_applied);
    f("fine_split", "fine_split", d.fine_split);
    f("sampled_cameras", "sampled_positions", d.sampled_cameras);
    f("sphere", "sphere", d.sphere);
    f("abr_flagged", "abr.flagged", d.abr_flagged);
    f("abr_compressed", "abr.compressed", d.abr_compressed);
    f("abr_retraced", "abr.retraced", d.abr_retraced);
    f("abr_masks_widened", "abr.masks_widened", d.abr_masks_widened);
    f("overshoot_eroded", "overshoot_eroded", d.overshoot_eroded);
    f("masks_grown", "masks_grown", d.masks_grown);
    f("masks_missing", "masks_missing", d.masks_missing);
    f("mask_store_bytes", "mask_store_bytes", d.mask_store_bytes);
    f("note", "note", d.note);
    f("timings_s", "timings_s", d.timings_s);
  }
};

// What vcar::segment returns (one object of vcar::segment_objects likewise).
struct SegmentationResult {
  std::vector<Index> indices;  // G*, ascending scene indices
  std::vector<float> scores;   // R_i of the last vote, aligned with indices
  LogScales log_scale;         // refined log-scales, aligned with indices
  Diagnostics diagnostics;
};

}  // namespace vcar
