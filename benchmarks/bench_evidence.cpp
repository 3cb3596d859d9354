// The evidence driver: methods x VCAR variants x rigs x scene sizes x oracle failure levels x
// seeds on the synthetic world, one tidy CSV row per run plus a JSON summary.
//
//   bench_evidence [--quick | --full] [--out DIR] [--seeds N] [--first-seed N] [--max-size N] [--only SWEEP]
//                  [--set key=value]... (VcarParams, every VCAR run) [--methods a,b] (keep only these)
//
// Evaluation (CONVENTIONS 6): the selected Gaussians alone (refined scales for VCAR, decomposed
// geometry for SAGD) are rendered from the rig's held-out views; alpha > 0.5 (and > 0.1) is
// compared with the target's full silhouette there. Every method sees the same oracle masks:
// the peers get the training masks the oracle gives in VCAR's frame order (reference first),
// which are the masks of VCAR's coarse round (the oracle is deterministic in (seed, frame, camera)).
// Times: t_method excludes the segmenter (the oracle stands in for SAM); time_s includes it.
// Peak memory: process peak during the run (see evidence/peak_memory.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vcar/algo/params.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/io/params_text.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

#include "evidence/methods.hpp"
#include "evidence/peak_memory.hpp"
#include "evidence/run_record.hpp"
#include "evidence/filter_cluster.hpp"

namespace {

using namespace vcar;
using evidence::RunRecord;
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ---------------------------------------------------------------------------------------------
// Worlds with the object fixed: the world is generated at `base` Gaussians and grown to `total`
// with background discs on the floor around the table (radius 1.3-3, id -1), so the target,
// its neighbour and the table keep the same Gaussians while the scene grows. The wedge behind
// the target as seen from the forward rig (front = -y) is left empty: centre voting would
// otherwise pick up floor behind the target and the coarse set would grow with the scene.
void pad_world(synth::World& w, std::size_t total, std::uint64_t seed) {
  GaussianScene& g = w.scene;
  const std::size_t n0 = g.size();
  if (total <= n0) return;
  const std::size_t n = total;
  for (auto& c : g.mean) c.resize(n);
  for (auto& c : g.log_scale) c.resize(n);
  for (auto& c : g.rotation) c.resize(n);
  g.opacity_logit.resize(n);
  g.sh.resize(n * static_cast<std::size_t>(g.sh_coeffs()) * 3, 0.f);
  g.extra.resize(n * g.extra_names.size(), 0.f);
  w.object_id.resize(n, -1);
  const float r0 = 1.3f, r1 = 3.f;
  const float area = 3.14159265f * (r1 * r1 - r0 * r0);
  const float spacing = std::sqrt(area / static_cast<float>(n - n0));
  for (std::size_t i = n0; i < n; ++i) {
    synth::Rng rng(seed, 0x9AD, i);
    Eigen::Vector3f p;
    do {  // rejection: outside the wedge |x| < 0.5 (y + 1.6) + 0.8 behind the target
      const float r = std::sqrt(rng.uniform(r0 * r0, r1 * r1)), a = 6.2831853f * rng.uniform();
      p = Eigen::Vector3f(r * std::cos(a), r * std::sin(a), 0.f);
    } while (p.y() > -1.6f && std::abs(p.x()) < 0.5f * (p.y() + 1.6f) + 0.8f);
    const Eigen::Vector3f nz(0.f, 0.f, 1.f);
    const float grey = rng.uniform(0.3f, 0.6f);
    synth::detail::put_gaussian(g, i, p, nz, synth::detail::random_tangent(nz, rng),
                                Eigen::Vector3f(0.8f * spacing, 0.8f * spacing, 0.05f * spacing), 0.9f,
                                Eigen::Vector3f(grey, grey, 0.9f * grey));
  }
}

// ---------------------------------------------------------------------------------------------
// The oracle as VCAR's segmenter. The pipeline renders sampled views from G_coarse only, so the
// segmenter sees the target alone there: the oracle answers those (named sss_...) with the
// silhouette. Each frame is rendered (and discarded) as SAM would need it, so t_render is the
// pipeline's real render cost.
class PipelineOracle {
public:
  explicit PipelineOracle(const synth::OracleSegmenter& oracle) : oracle_(&oracle) {}
  void segment(const FrameSequence& frames, const Prompt&, const MaskSink& sink) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
      (void)frames.image(k);  // a real segmenter needs the render: its cost is part of the method
      const std::optional<Mask> m = oracle_->mask(frames.cameras[k], k, frames.subset);
      sink(k, m ? &*m : nullptr);
    }
  }

private:
  const synth::OracleSegmenter* oracle_;
};
static_assert(Segmenter<PipelineOracle>);

// ---------------------------------------------------------------------------------------------
struct Experiment {
  int seed = 1;
  std::size_t object_size = 30000;  // Gaussians of the generated world (object fixed)
  std::size_t total = 30000;        // after padding
  std::string rig = "forward";
  std::string failure = "none";
  double level = 0;
  int width = 160, height = 120, n_train = 0;
  std::string target = "seed";       // seed (drawn), sphere, torus, cylinder, box, donut (trained)
  std::vector<std::string> methods;  // "vcar:<variant>" or a peer's name
};

struct Options {
  bool quick = false;
  std::filesystem::path out = "evidence-out";
  int seeds = 0;
  int first_seed = 1;                // --first-seed N: skip the seeds before N (resuming a run)
  std::size_t max_size = 0;
  std::string only;
  std::vector<std::string> set;      // --set key=value, applied to every VCAR run
  std::vector<std::string> methods;  // --methods a,b: keep only these (targeted experiments)
  std::vector<std::string> rigs;     // --rigs a,b: keep only these rigs
  std::vector<std::string> targets;  // --targets a,b: keep only these targets
};

using evidence::is_360;
using evidence::kPeers;
const std::vector<std::string> kVariants = {"coarse", "sss", "abr", "full", "occlusion", "gapdir", "robust"};
// The robust preset with one mechanism changed each (docs/robust.md ablation).
const std::vector<std::string> kRobustAblation = {"robust-nor3", "robust-nolowpass", "robust-novalley", "robust-tau07",
                                                  "robust-noundershoot", "robust-nostrict",
                                                  "robust-nosnap"};

std::vector<std::string> all_methods(bool variants = true) {
  std::vector<std::string> m = kPeers;
  if (variants) for (const auto& v : kVariants) m.push_back("vcar:" + v);
  else m.push_back("vcar:full");
  return m;
}

synth::OracleParams oracle_for(const Experiment& e) {
  synth::OracleParams o;
  o.seed = static_cast<std::uint64_t>(e.seed) * 7919u + 13u;
  const double L = e.level;
  const double diag = std::hypot(static_cast<double>(e.width), static_cast<double>(e.height));
  if (e.failure == "dilate_diag") o.dilate_px = static_cast<int>(std::lround(L / 100.0 * diag));
  else if (e.failure == "erode_diag") o.dilate_px = -static_cast<int>(std::lround(L / 100.0 * diag));
  else if (e.failure == "dilate") o.dilate_px = static_cast<int>(L);
  else if (e.failure == "erode") o.dilate_px = -static_cast<int>(L);
  else if (e.failure == "blobs") o.n_blobs = static_cast<int>(L);
  else if (e.failure == "drop") o.p_drop = L;
  else if (e.failure == "swap") o.p_swap = L;
  else if (e.failure == "jitter") o.jitter_px = static_cast<int>(L);
  return o;
}

// VCAR parameters per variant; preset nvos on forward-facing rigs, lerf on the others (Sec. 4.2).
VcarParams vcar_params(const std::string& variant, const Experiment& e, const std::vector<std::string>& set) {
  if (variant.rfind("robust", 0) == 0) {  // one preset for every rig: the library's default
    VcarParams p = VcarParams::robust();
    if (variant == "robust-nor3") p.evidence.occlusion = false;  // R3 in both rounds
    else if (variant == "robust-nolowpass") p.abr_lowpass = false;
    else if (variant == "robust-novalley") p.valley.enabled = false;  // Eq. R14 off: tau_fine 0.8
    else if (variant == "robust-tau07") {  // R14 off, always 0.7 (before R6d)
      p.valley.enabled = false;
      p.tau_fine = 0.7f;
    }
    else if (variant == "robust-noundershoot") p.undershoot.band = 0.f;
    else if (variant == "robust-nostrict") p.strict.tau = 0.f;
    else if (variant == "robust-nosnap") p.snap.enabled = false;
    else if (variant != "robust") throw Error("unknown variant '" + variant + "'", "--methods");
    if (e.failure == "tau") { p.tau_coarse = static_cast<float>(e.level); p.tau_fine = static_cast<float>(e.level); }
    for (const std::string& kv : set) io::set_parameter(p, kv);
    return p;
  }
  VcarParams p = is_360(e.rig) ? VcarParams::lerf() : VcarParams::nvos();
  p.enable_sss = variant != "coarse" && variant != "abr";
  p.enable_abr = variant != "coarse" && variant != "sss";
  p.occlusion_aware = variant == "occlusion";
  p.gap_directed = variant == "gapdir";
  if (e.failure == "tau") { p.tau_coarse = static_cast<float>(e.level); p.tau_fine = static_cast<float>(e.level); }
  for (const std::string& kv : set) io::set_parameter(p, kv);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Real trained Gaussians (tests/data/donut.ply): a copy becomes the target (id 9) on a free spot
// of the table, with three more copies around it (ids 10-12), one touching it; the rigs then
// centre on the trained target. Ground truth comes from renders of the copies (ground_truth.hpp).
void add_trained_donuts(synth::World& w, std::uint64_t seed) {
  static const GaussianScene donut = io::read_ply(std::filesystem::path(VCAR_TEST_DATA_DIR) / "donut.ply");
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  for (std::size_t i = 0; i < donut.size(); ++i) { lo = lo.cwiseMin(donut.mu(i)); hi = hi.cwiseMax(donut.mu(i)); }
  const float s = 0.15f / (0.5f * (hi - lo).maxCoeff());
  const Eigen::Vector3f c = 0.5f * (lo + hi);
  const float touch = s * (hi - lo).x();  // side by side: the copies' extents meet
  const Eigen::Vector3f offsets[4] = {{0.f, 0.f, 0.f}, {touch, 0.f, 0.f}, {-0.1f, 0.4f, 0.f}, {-0.42f, 0.05f, 0.f}};
  // The copies go to the first spot, from (-0.5, -0.5) outwards, where all of them lie on the
  // table and none overlaps a primitive (bounding circles apart), else where at least the target
  // copy overlaps none: a distractor drawn there would bury part of the target.
  const float r_copy = 0.5f * s * std::max((hi - lo).x(), (hi - lo).y());
  auto clear = [&](const Eigen::Vector2f& spot, int copies) {
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2f p = spot + offsets[k].head<2>();
      if (std::max(std::abs(p.x()), std::abs(p.y())) + r_copy > 0.98f) return false;  // on the table
      for (const auto& q : w.primitives)
        if (k < copies && q.object_id != 0 && (p - q.t.head<2>()).norm() < synth::bounding_radius(q) + r_copy + 0.02f)
          return false;
    }
    return true;
  };
  Eigen::Vector2f spot(-0.5f, -0.5f);
  for (int copies : {4, 1}) {
    if (clear(spot, copies)) break;
    bool found = false;
    for (int ring = 1; ring <= 20 && !found; ++ring)
      for (int k = 0; k < 8 * ring && !found; ++k) {
        const float a = 6.2831853f * static_cast<float>(k) / static_cast<float>(8 * ring);
        const Eigen::Vector2f cand = Eigen::Vector2f(-0.5f, -0.5f) + 0.05f * static_cast<float>(ring) * Eigen::Vector2f(std::cos(a), std::sin(a));
        if (clear(cand, copies)) { spot = cand; found = true; }
      }
    if (found) break;
  }
  const Eigen::Vector3f at(spot.x(), spot.y(), 0.5f * s * (hi - lo).z() + 0.01f);
  synth::Rng rng(seed, 0xD0Au);
  synth::insert_gaussians(w, donut, Eigen::Matrix3f::Identity(), at - s * c, s, 9);
  for (int k = 0; k < 3; ++k) {
    const float yaw = rng.uniform(0.f, 6.2831853f);
    const Eigen::Matrix3f R = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    synth::insert_gaussians(w, donut, R, at + offsets[k + 1] - s * (R * c), s, 10 + k);
  }
  w.target_id = 9;
  w.neighbour_id = 10;
}

class Driver {
public:
  explicit Driver(const Options& o) : opt_(o) {}

  void open() {
    std::filesystem::create_directories(opt_.out);
    csv_.open(opt_.out / "evidence.csv");
    if (!csv_) throw Error("cannot write", (opt_.out / "evidence.csv").string());
    csv_ << evidence::csv_header() << "\n";
  }

  void run(const Experiment& e) {
    const synth::World& w = world(e.seed, e.object_size, e.total, e.target);
    synth::RigParams rp;
    rp.intrinsics = synth::make_intrinsics(e.width, e.height);
    rp.n_train = e.n_train;
    rp.seed = static_cast<std::uint64_t>(e.seed);
    const synth::Rig rig = synth::make_rig(e.rig, w, rp);
    std::vector<Mask> gt;
    for (const Camera& c : rig.eval) gt.push_back(synth::silhouette_mask(w, c, w.target_id, renderer_));
    const std::vector<Index> truth = w.gaussians_of(w.target_id);
    synth::OracleSegmenter oracle(w, oracle_for(e), renderer_);
    PipelineOracle segmenter(oracle);

    // The training masks in VCAR's frame order (reference first), stored by training index.
    const auto order = vcar::detail::training_order(rig.train.size(), rig.reference);
    std::vector<std::optional<Mask>> masks(rig.train.size());
    const auto ts = Clock::now();
    for (std::size_t k = 0; k < order.size(); ++k) masks[order[k]] = oracle.mask(rig.train[order[k]], k);
    const double t_masks = since(ts);
    const baselines::MaskProvider provider = baselines::masks_from(masks);
    Prompt prompt;
    prompt.reference_view = rig.reference;

    for (const std::string& m : e.methods) {
      RunRecord r;
      r.method = m.rfind("vcar:", 0) == 0 ? "vcar" : m;
      r.variant = r.method == "vcar" ? m.substr(5) : "full";
      r.rig = e.rig; r.seed = e.seed; r.gaussians = w.scene.size(); r.object_gaussians = truth.size();
      r.failure = e.failure; r.level = e.level; r.width = e.width; r.height = e.height; r.target = e.target;
      r.n_train = static_cast<int>(rig.train.size()); r.n_eval = static_cast<int>(rig.eval.size());
      const double rss0 = evidence::reset_peak();
      std::vector<Index> sel;
      std::optional<LogScales> scales;
      std::optional<GaussianScene> own_scene;  // SAGD's decomposed geometry
      const auto t0 = Clock::now();
      if (r.method == "vcar") {
        const VcarParams p = vcar_params(r.variant, e, opt_.set);
        r.preset = r.variant.rfind("robust", 0) == 0 ? "robust" : is_360(e.rig) ? "lerf" : "nvos";
        SegmentationResult res = segment(w.scene, rig.train, prompt, renderer_, segmenter, p);
        evidence::record_vcar(r, res.diagnostics, since(t0), rig.train.size());
        sel = std::move(res.indices);
        if (!sel.empty()) scales = std::move(res.log_scale);
      } else {
        r.preset = is_360(e.rig) ? "360" : "forward";
        if (r.method == "filtercluster") {  // splat-transform (evidence/filter_cluster.hpp)
          sel = evidence::filter_cluster(w, rig, renderer_, opt_.out / "work").selected;
        } else {
          const std::optional<float> tau = e.failure == "tau" ? std::optional<float>(static_cast<float>(e.level)) : std::nullopt;
          evidence::PeerSelection res = evidence::run_peer(r.method, renderer_, w.scene, rig.train, provider, is_360(e.rig), tau);
          sel = std::move(res.selected);
          own_scene = std::move(res.own_scene);
        }
        r.t_method = since(t0);
        r.t_segment = t_masks;
        r.time_s = r.t_method + t_masks;
        r.frames_segmented = static_cast<int>(rig.train.size());
        if (r.method == "filtercluster") { r.t_segment = 0; r.time_s = r.t_method; r.frames_segmented = 0; }  // no masks
      }
      r.peak_mib = evidence::peak_mib();
      r.peak_delta_mib = std::max(0.0, r.peak_mib - rss0);
      evidence::evaluate(r, renderer_, w.scene, rig.eval, gt, truth, sel, scales ? &*scales : nullptr,
                         own_scene ? &*own_scene : nullptr);
      csv_ << evidence::csv_row(r) << "\n";
      csv_.flush();
      rows_.push_back(r);
      std::fprintf(stderr, "%-11s %-9s %-10s n=%-7zu %-6s %-5g mIoU %.3f bIoU %.3f F1_3d %.3f  %.3fs\n",
                   r.method.c_str(), r.variant.c_str(), r.rig.c_str(), r.gaussians, r.failure.c_str(), r.level,
                   r.miou, r.boundary_iou, r.f1_3d, r.t_method);
    }
  }

  void write_summary(double wall_s) {
    nlohmann::json j;
    j["mode"] = opt_.quick ? "quick" : "full";
    j["threads"] = max_threads();
    j["wall_s"] = wall_s;
    j["runs"] = rows_.size();
    j["peak_memory"] = "process VmHWM during the run after clear_refs reset (MiB); delta = peak - RSS before";
    j["time_columns"] = "t_method excludes the segmenter (oracle); time_s includes it; stage columns for VCAR only";
    // Means over seeds of the failure-free runs (the headline grid), per method/variant/rig.
    std::map<std::string, std::vector<const RunRecord*>> groups;
    for (const RunRecord& r : rows_)
      if (r.failure == "none")
        groups[r.method + "/" + r.variant + "/" + r.rig].push_back(&r);
    nlohmann::json g = nlohmann::json::object();
    for (const auto& [key, v] : groups) {
      auto mean = [&](auto f) { double s = 0; for (auto* r : v) s += f(*r); return s / static_cast<double>(v.size()); };
      g[key] = {{"runs", v.size()},
                {"miou", mean([](const RunRecord& r) { return r.miou; })},
                {"macc", mean([](const RunRecord& r) { return r.macc; })},
                {"miou_01", mean([](const RunRecord& r) { return r.miou_01; })},
                {"boundary_iou", mean([](const RunRecord& r) { return r.boundary_iou; })},
                {"boundary_f1", mean([](const RunRecord& r) { return r.boundary_f1; })},
                {"f1_3d", mean([](const RunRecord& r) { return r.f1_3d; })},
                {"t_method_s", mean([](const RunRecord& r) { return r.t_method; })}};
    }
    j["failure_free"] = g;
    std::ofstream(opt_.out / "evidence.json") << j.dump(2) << "\n";
  }

private:
  const synth::World& world(int seed, std::size_t object_size, std::size_t total, const std::string& target) {
    const std::string key = std::to_string(seed) + "/" + std::to_string(object_size) + "/" + std::to_string(total) + "/" + target;
    if (cache_key_ != key) {
      synth::WorldParams wp;
      wp.seed = static_cast<std::uint64_t>(seed);
      wp.n_gaussians = object_size;
      if (target != "seed" && target != "donut") wp.target_type = synth::primitive_type_from_string(target);
      cache_ = synth::generate_world(wp);
      pad_world(cache_, total, static_cast<std::uint64_t>(seed));
      if (target == "donut") add_trained_donuts(cache_, static_cast<std::uint64_t>(seed));
      cache_key_ = key;
    }
    return cache_;
  }

  Options opt_;
  cpu::TiledRenderer renderer_;
  synth::World cache_;
  std::string cache_key_;
  std::ofstream csv_;
  std::vector<RunRecord> rows_;
};

// ---------------------------------------------------------------------------------------------
// The plan: the headline grid (every method and variant x every rig, no failure), then sweeps.
std::vector<Experiment> plan(const Options& o) {
  std::vector<Experiment> out;
  const bool q = o.quick;
  const int seeds = o.seeds > 0 ? o.seeds : (q ? 1 : 3);
  const std::size_t base = q ? 30000 : 50000;
  // 160 x 120 in both modes: the 2 shared cores of this machine fit the full sweep in ~25 min.
  const int W = 160, H = 120;
  auto make = [&](int seed, const std::string& rig, const std::string& failure, double level,
                  std::vector<std::string> methods) {
    Experiment e;
    e.seed = seed; e.object_size = base; e.total = base; e.rig = rig; e.failure = failure; e.level = level;
    e.width = W; e.height = H; e.methods = std::move(methods);
    return e;
  };
  const std::vector<std::string> rigs = {"forward", "orbit", "sparse", "hemisphere"};
  // Quick mode (CI's smoke run): the grid on every rig, each sweep once, on the forward rig.
  const std::vector<std::string> sweep_rigs = q ? std::vector<std::string>{"forward"}
                                                : std::vector<std::string>{"forward", "orbit"};
  const std::vector<std::string>& every_rig = q ? sweep_rigs : rigs;
  auto want = [&](const char* sweep) { return o.only.empty() || o.only == sweep; };
  if (want("grid"))
    for (int s = 1; s <= seeds; ++s)
      for (const auto& rig : rigs) {
        std::vector<std::string> ms = all_methods();
        if (!q) for (const auto& v : kRobustAblation) ms.push_back("vcar:" + v);
        // splat-transform --filter-cluster: minutes per run on a software GPU, so full mode and
        // seed 1 only, and only where it is installed (evidence/filter_cluster.hpp).
        if (!q && s == 1 && evidence::filter_cluster_available()) ms.push_back("filtercluster");
        out.push_back(make(s, rig, "none", 0, ms));
      }
  // Stability sweeps on a forward-facing and a 360-degree rig; VCAR coarse, full, robust and the peers.
  std::vector<std::string> sweep_methods = kPeers;
  sweep_methods.push_back("vcar:coarse");
  sweep_methods.push_back("vcar:full");
  sweep_methods.push_back("vcar:robust");
  // Beyond the paper's suite (docs/robust.md): every target shape, concave torus included; masks
  // eroded/dilated by a share of the image diagonal on every rig; >= 640 px images; trained
  // Gaussians (tests/data/donut.ply) in a forward and an orbit capture.
  if (want("targets"))
    for (int s = 1; s <= seeds; ++s)
      for (const char* t : {"sphere", "torus", "cylinder", "box"})
        for (const auto& rig : every_rig) {
          Experiment e = make(s, rig, "none", 0, sweep_methods);
          e.target = t;
          out.push_back(e);
        }
  if (want("diag"))
    for (int s = 1; s <= seeds; ++s)
      for (const auto& rig : every_rig)
        for (const char* f : {"erode_diag", "dilate_diag"})
          for (double L : q ? std::vector<double>{2} : std::vector<double>{1, 2}) {
            std::vector<std::string> ms = sweep_methods;  // full mode: the robust ablation under failures too
            if (!q) for (const auto& v : kRobustAblation) ms.push_back("vcar:" + v);
            out.push_back(make(s, rig, f, L, ms));
          }
  if (want("hires") && !q)
    for (int s = 1; s <= seeds; ++s)
      for (const auto& rig : rigs)
        for (const char* t : {"seed", "torus"}) {
          Experiment e = make(s, rig, "none", 0, sweep_methods);
          e.width = 640; e.height = 480; e.target = t;
          out.push_back(e);
        }
  // Not in quick mode: benchmarks/field_quick runs a trained donut (with real segmenters) in
  // the same CI stage.
  if (want("donut") && !q)
    for (int s = 1; s <= seeds; ++s)
      for (const char* rig : {"forward", "orbit"})
        for (double L : {0.0, 2.0}) {
          Experiment e = make(s, rig, L > 0 ? "erode" : "none", L, sweep_methods);
          e.width = 256; e.height = 192; e.target = "donut"; e.object_size = e.total = 20000;
          out.push_back(e);
        }
  const int sweep_seeds = q ? 1 : std::max(1, seeds - 1);  // 2 by default in full mode
  struct Sweep { const char* failure; std::vector<double> levels; };
  std::vector<Sweep> sweeps = q ? std::vector<Sweep>{{"dilate", {4}}, {"blobs", {4}}, {"drop", {0.3}}}
                                : std::vector<Sweep>{{"dilate", {2, 4, 8}},
                                                     {"erode", {2, 4, 8}},
                                                     {"blobs", {2, 4, 8}},
                                                     {"drop", {0.2, 0.4, 0.6}},
                                                     {"swap", {0.1, 0.3}},
                                                     {"jitter", {2, 4}},
                                                     {"tau", {0.3, 0.5, 0.7, 0.9}}};
  for (const auto& sw : sweeps) {
    if (!want(sw.failure) && !want("sweeps")) continue;
    const bool secondary = std::string(sw.failure) == "swap" || std::string(sw.failure) == "jitter" ||
                           std::string(sw.failure) == "tau";
    for (int s = 1; s <= (secondary ? 1 : sweep_seeds); ++s)
      for (const auto& rig : sweep_rigs)
        for (double L : sw.levels) {
          std::vector<std::string> ms = sweep_methods;
          if (std::string(sw.failure) == "tau")  // methods without a threshold have no tau curve
            ms = {"naive", "sagd", "gaussiancut", "ludvig", "vcar:coarse", "vcar:full", "vcar:robust"};
          out.push_back(make(s, rig, sw.failure, L, ms));
        }
  }
  // Number of training views.
  if (want("views")) {
    const std::vector<int> views = q ? std::vector<int>{6} : std::vector<int>{4, 8, 12, 20, 40};
    for (int s = 1; s <= 1; ++s)
      for (const auto& rig : sweep_rigs)
        for (int n : views) {
          Experiment e = make(s, rig, "views", n, sweep_methods);
          e.n_train = n;
          out.push_back(e);
        }
  }
  // Scene size with the object fixed (forward rig): every stage of VCAR and the peers.
  if (want("size")) {
    std::vector<std::size_t> sizes = q ? std::vector<std::size_t>{40000}
                                       : std::vector<std::size_t>{25000, 50000, 100000, 250000, 500000, 1000000};
    for (std::size_t n : sizes) {
      if (o.max_size && n > o.max_size) continue;
      // The kNN-graph and max-contributor peers stop at 250k to keep the run within budget.
      std::vector<std::string> ms = n <= 250000 ? all_methods(false)
                                                : std::vector<std::string>{"naive", "sagd", "flashsplat", "vcar:full"};
      Experiment e = make(1, "forward", "size", static_cast<double>(n), ms);
      e.methods.push_back("vcar:coarse");
      e.methods.push_back("vcar:robust");
      e.object_size = 25000;
      e.total = n;
      out.push_back(e);
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) { std::fprintf(stderr, "%s needs a value\n", a.c_str()); std::exit(2); }
      return argv[++i];
    };
    if (a == "--quick") o.quick = true;
    else if (a == "--full") o.quick = false;
    else if (a == "--out") o.out = value();
    else if (a == "--seeds") o.seeds = std::stoi(value());
    else if (a == "--first-seed") o.first_seed = std::stoi(value());
    else if (a == "--max-size") o.max_size = std::stoul(value());
    else if (a == "--only") o.only = value();
    else if (a == "--set") o.set.push_back(value());
    else if (a == "--methods" || a == "--rigs" || a == "--targets") {
      std::vector<std::string>& list = a == "--methods" ? o.methods : a == "--rigs" ? o.rigs : o.targets;
      const std::string v = value();
      for (std::size_t b = 0, c; b <= v.size(); b = c + 1) {
        c = v.find(',', b);
        if (c == std::string::npos) c = v.size();
        if (c > b) list.push_back(v.substr(b, c - b));
      }
    }
    else {
      std::fprintf(stderr, "usage: %s [--quick|--full] [--out DIR] [--seeds N] [--first-seed N] [--max-size N] "
                           "[--only grid|targets|diag|hires|donut|sweeps|dilate|erode|blobs|drop|swap|jitter|tau|views|size] [--set key=value]... "
                           "[--methods naive,vcar:full,...] [--rigs forward,...] [--targets torus,...]\n", argv[0]);
      return a == "--help" || a == "-h" ? 0 : 2;
    }
  }
  try {
    const auto t0 = Clock::now();
    Driver d(o);
    std::vector<Experiment> p = plan(o);
    auto listed = [](const std::vector<std::string>& l, const std::string& x) {
      return l.empty() || std::find(l.begin(), l.end(), x) != l.end();
    };
    std::erase_if(p, [&](const Experiment& e) {
      return !listed(o.rigs, e.rig) || !listed(o.targets, e.target) || e.seed < o.first_seed;
    });
    if (!o.methods.empty())
      for (Experiment& e : p)
        std::erase_if(e.methods, [&](const std::string& m) { return std::find(o.methods.begin(), o.methods.end(), m) == o.methods.end(); });
    std::fprintf(stderr, "bench_evidence: %s mode, %zu experiments, %d threads -> %s\n", o.quick ? "quick" : "full",
                 p.size(), max_threads(), o.out.string().c_str());
    d.open();
    for (std::size_t k = 0; k < p.size(); ++k) {
      std::fprintf(stderr, "[%zu/%zu] %.0fs\n", k + 1, p.size(), since(t0));
      d.run(p[k]);
    }
    d.write_summary(since(t0));
    std::printf("bench_evidence: %zu experiments in %.1f s, CSV %s\n", p.size(), since(t0),
                (o.out / "evidence.csv").string().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_evidence: %s\n", e.what());
    return 1;
  }
  return 0;
}
