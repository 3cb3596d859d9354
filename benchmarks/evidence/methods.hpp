#pragma once
// The pieces the evidence drivers share (bench_evidence on the synthetic world, bench_field on
// stages of trained objects): VCAR's run record from its diagnostics, the peers run on one mask
// provider, and the evaluation of a selection (conventions §6).
//
// Evaluation: the selected Gaussians alone (refined scales for VCAR, decomposed geometry for
// SAGD) are rendered from the held-out views; alpha > 0.5 (and > 0.1) is compared with the
// target's full silhouette there; the selected ids are scored against the target's true ids.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "vcar/algo/pipeline.hpp"
#include "vcar/baselines/flashsplat.hpp"
#include "vcar/baselines/gaussian_cut.hpp"
#include "vcar/baselines/lbg.hpp"
#include "vcar/baselines/ludvig.hpp"
#include "vcar/baselines/naive_voting.hpp"
#include "vcar/baselines/sagd.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/error.hpp"
#include "vcar/eval/aggregate.hpp"
#include "vcar/eval/mask_metrics.hpp"
#include "vcar/eval/selection_metrics.hpp"

#include "evidence/run_record.hpp"

namespace vcar::evidence {

// The peers of docs/results.md, in their table order.
inline const std::vector<std::string> kPeers = {"naive", "sagd", "flashsplat", "gaussiancut", "ludvig", "lbg"};

// Everything but the forward-facing rig is a 360-degree capture (preset lerf, the peers' 360 settings).
inline bool is_360(const std::string& rig) { return rig != "forward"; }

// VCAR's stage times and diagnostics into r, from a run of vcar::segment that took wall_s
// seconds on n_train training views: t_segment = the rounds' segmenter seconds, t_method =
// wall_s without them, time_s = wall_s.
inline void record_vcar(RunRecord& r, const Diagnostics& d, double wall_s, std::size_t n_train) {
  double seg = 0, ren = 0, vote = 0, vca = 0, abr = 0, fine = 0;
  for (const auto& [name, s] : d.timings_s) {
    if (name.find("_segment") != std::string::npos) seg += s;
    else if (name.find("_render") != std::string::npos) ren += s;
    else if (name.find("_voting") != std::string::npos) vote += s;
    else if (name == "vca") vca += s;
    else if (name == "abr") abr += s;
    if (name == "fine_render" || name == "fine_voting") fine += s;
  }
  r.time_s = wall_s;
  r.t_render = ren; r.t_segment = seg; r.t_vote = vote; r.t_vca = vca;
  r.t_sss = d.sss_triggered ? fine : 0.0;
  r.t_abr = abr;
  r.t_method = wall_s - seg;
  r.frames_segmented = static_cast<int>(n_train + (d.sss_triggered ? n_train + d.sampled_cameras.size() : 0));
  r.n_coarse = static_cast<long>(d.n_coarse); r.n_fine = static_cast<long>(d.n_fine);
  r.abr_flagged = static_cast<long>(d.abr_flagged); r.abr_compressed = static_cast<long>(d.abr_compressed);
  r.valid_cameras = static_cast<long>(d.valid_cameras); r.max_gap_deg = d.max_gap_deg;
  r.sss_triggered = d.sss_triggered ? 1 : 0;
}

// A peer's selection, and SAGD's decomposed geometry (render that instead of the scene).
struct PeerSelection {
  std::vector<Index> selected;
  std::optional<GaussianScene> own_scene;
};

// The peer `name` (one of kPeers) on the training views' masks; `tau` overrides its threshold
// (the tau sweep). Settings per rig as in conventions §8. Throws vcar::Error for another name.
template <Renderer R>
PeerSelection run_peer(const std::string& name, R& renderer, const GaussianScene& scene,
                       const std::vector<Camera>& train, const baselines::MaskProvider& provider, bool rig_360,
                       std::optional<float> tau = std::nullopt) {
  PeerSelection out;
  baselines::Result res;
  if (name == "naive") {
    baselines::NaiveVotingParams p;
    if (tau) p.tau = *tau;
    res = baselines::naive_voting(scene, train, provider, p);
  } else if (name == "sagd") {
    baselines::SagdParams p;
    if (tau) p.share_min = *tau;
    baselines::SagdResult s = baselines::sagd(scene, train, provider, p);
    out.own_scene = s.scene_of(scene);
    res = std::move(s);
  } else if (name == "flashsplat") {
    res = baselines::flashsplat(renderer, scene, train, provider);
  } else if (name == "gaussiancut") {
    baselines::GaussianCutParams p;
    p.tau_w = rig_360 ? 0.3f : 0.9f;  // CONVENTIONS 8
    if (tau) p.tau_w = *tau;
    res = baselines::gaussian_cut(renderer, scene, train, provider, p);
  } else if (name == "ludvig") {
    baselines::LudvigParams p;
    if (tau) p.threshold = *tau;
    res = baselines::ludvig(renderer, scene, train, provider, p);
  } else if (name == "lbg") {
    res = baselines::lbg(scene, train, provider);
  } else {
    throw Error("unknown method '" + name + "'", "--methods");
  }
  out.selected = std::move(res.selected);
  return out;
}

// Held-out and 3D metrics of a selection into r (see the top of the file): `scales` the refined
// log-scales aligned with `sel` (VCAR), `own` a scene to render instead (SAGD); gt[v] is the
// target's silhouette in eval[v], truth its Gaussians.
template <Renderer R>
void evaluate(RunRecord& r, R& renderer, const GaussianScene& scene, const std::vector<Camera>& eval,
              const std::vector<Mask>& gt, const std::vector<Index>& truth, const std::vector<Index>& sel,
              const LogScales* scales, const GaussianScene* own) {
  std::vector<eval::ViewMetrics> m05, m01;
  for (std::size_t v = 0; v < eval.size(); ++v) {
    const Camera& cam = eval[v];
    ImageF alpha(cam.width, cam.height, 1);
    if (!sel.empty()) {
      RenderRequest q;
      q.camera = &cam;
      if (own) {
        q.scene = own;
      } else {
        q.scene = &scene;
        q.subset = &sel;
        q.log_scale = scales;
      }
      alpha = renderer.render(q).alpha;
    }
    m05.push_back(eval::evaluate_alpha(alpha, gt[v], eval::alpha_default, 0, cam.name));
    m01.push_back(eval::evaluate_alpha(alpha, gt[v], eval::alpha_released, 0, cam.name));
  }
  const eval::ViewMetrics a = eval::mean(std::span<const eval::ViewMetrics>(m05));
  const eval::ViewMetrics b = eval::mean(std::span<const eval::ViewMetrics>(m01));
  r.miou = a.iou; r.macc = a.accuracy; r.boundary_iou = a.boundary_iou; r.boundary_f1 = a.boundary_f1;
  r.trimap_iou = a.trimap_iou; r.miou_01 = b.iou; r.macc_01 = b.accuracy;
  const eval::SelectionScores s = eval::selection_scores(sel, truth, scene.size());
  r.f1_3d = s.f1; r.precision_3d = s.precision; r.recall_3d = s.recall;
  r.selected = sel.size();
}

}  // namespace vcar::evidence
