#pragma once
// One row of the evidence CSV (one run = one method on one world, rig and failure setting),
// with the column order written once here so the header and the rows cannot drift apart.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace vcar::evidence {

// Stage times are NaN when a method has no such stage (written as an empty CSV field).
struct RunRecord {
  std::string method, variant, rig, preset, failure;
  std::string target = "seed";  // the target's shape: seed (drawn), sphere, torus, cylinder, box, donut (trained)
  int seed = 0;
  std::size_t gaussians = 0, object_gaussians = 0;
  double level = 0;
  int width = 0, height = 0, n_train = 0, n_eval = 0;
  // Accuracy on the held-out views (alpha > 0.5 unless named _01) and in 3D.
  double miou = 0, macc = 0, miou_01 = 0, macc_01 = 0, boundary_iou = 0, boundary_f1 = 0, trimap_iou = 0;
  double f1_3d = 0, precision_3d = 0, recall_3d = 0;
  std::size_t selected = 0;
  // Seconds per stage; t_method = the method without segmenter calls; time_s = everything.
  double t_render = NAN, t_segment = NAN, t_vote = NAN, t_vca = NAN, t_sss = NAN, t_abr = NAN;
  double t_method = 0, time_s = 0;
  int frames_segmented = 0;  // frames the segmenter was asked for (SAM calls in a real run)
  double peak_mib = 0, peak_delta_mib = 0;
  // VCAR diagnostics (-1 for the peers).
  long n_coarse = -1, n_fine = -1, abr_flagged = -1, abr_compressed = -1, valid_cameras = -1;
  double max_gap_deg = NAN;
  int sss_triggered = -1;
};

inline const char* csv_header() {
  return "method,variant,rig,preset,seed,gaussians,object_gaussians,failure,level,width,height,n_train,n_eval,"
         "miou,macc,miou_01,macc_01,boundary_iou,boundary_f1,trimap_iou,f1_3d,precision_3d,recall_3d,selected,"
         "t_render,t_segment,t_vote,t_vca,t_sss,t_abr,t_method,time_s,frames_segmented,peak_mib,peak_delta_mib,"
         "n_coarse,n_fine,abr_flagged,abr_compressed,valid_cameras,max_gap_deg,sss_triggered,target";
}

inline std::string fmt(double v, const char* f = "%.6g") {
  if (std::isnan(v)) return "";
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

inline std::string csv_row(const RunRecord& r) {
  std::string s;
  auto add = [&](const std::string& v) { s += s.empty() ? v : "," + v; };
  auto num = [&](double v) { add(fmt(v)); };
  auto opt = [&](long v) { add(v < 0 ? std::string() : std::to_string(v)); };
  add(r.method); add(r.variant); add(r.rig); add(r.preset); add(std::to_string(r.seed));
  add(std::to_string(r.gaussians)); add(std::to_string(r.object_gaussians)); add(r.failure); num(r.level);
  add(std::to_string(r.width)); add(std::to_string(r.height)); add(std::to_string(r.n_train)); add(std::to_string(r.n_eval));
  num(r.miou); num(r.macc); num(r.miou_01); num(r.macc_01); num(r.boundary_iou); num(r.boundary_f1); num(r.trimap_iou);
  num(r.f1_3d); num(r.precision_3d); num(r.recall_3d); add(std::to_string(r.selected));
  num(r.t_render); num(r.t_segment); num(r.t_vote); num(r.t_vca); num(r.t_sss); num(r.t_abr);
  num(r.t_method); num(r.time_s); add(std::to_string(r.frames_segmented));
  add(fmt(r.peak_mib, "%.1f")); add(fmt(r.peak_delta_mib, "%.1f"));
  opt(r.n_coarse); opt(r.n_fine); opt(r.abr_flagged); opt(r.abr_compressed); opt(r.valid_cameras);
  num(r.max_gap_deg); opt(r.sss_triggered); add(r.target);
  return s;
}

}  // namespace vcar::evidence
