// The field driver (issue 46): VCAR's presets and the peers on a stage of real trained objects
// (default examples/stages/three_objects.json) x rigs x segmenters x seeds, each object the
// target in turn; one CSV row per run, with the 2D quality of the segmenter's masks beside the
// 3D result. docs/results.md ("Field") has the command, the table and the charts.
//
//   bench_field [--quick] [--coarse-only | --mask-folder] [--out DIR] [--stage FILE] [--seeds tuning|heldout|all|N,N,...]
//               [--targets a,b] [--rigs forward,orbit,sparse]
//               [--segmenters grabcut,oracle,oracle-sam,oracle-sam-nodrift,isnet,exact]
//               [--methods vcar:paper,vcar:robust,vcar:code,naive,...] [--width W --height H]
//               [--set key=value]... (VcarParams of the vcar:robust runs only: tuning the default)
//               [--sam key=value]... (oracle-sam's levels instead of sam_levels': p_wrong, p_part,
//               p_leak, leak_px, drift_px)
//               [--isnet CMD] (the isnet segmenter's program; default node
//               examples/segmenters/isnet/isnet.mjs of this source tree)
//
// --coarse-only: every VCAR run without a fine round (enable_sss and force_fine_round off, after
// --set and an ablation row's keys), its `preset` column suffixed ":coarse-only": the regime of
// views without a 90-degree gap, of a mask folder with SSS off, and of Reselection, where G_coarse
// at tau_coarse is the selection (docs/notes/field-tau-coarse-2026-12-07.md).
// --mask-folder: every VCAR run's fine round answered as io::MaskFolderSegmenter answers it: a
// folder holds masks of the captures, not of renders of G_coarse, so every fine frame gets no
// mask and the pipeline keeps G_coarse (until 2026-12-07 each training view's render got that
// view's mask again: docs/notes/field-mask-folder-2026-12-07.md); `preset` suffixed ":mask-folder".
// The regime of users' own masks with SSS on (`vcar segment --masks DIR`).
//
// Seeds: tuning seeds 1 and 2 (the default may be tuned on them), held-out reporting seeds
// 11-15 (never tuned on); the CSV's `role` column says which a row is. --seeds all (default)
// runs both.
//
// The default grid (plan_cells; about 1.5-2 hours on the 2 shared cores of the machine it was
// run on): GrabCut x forward rig on every seed; the oracle x forward and orbit rigs and the
// SAM-like oracle x forward rig on the held-out seeds; every method but lbg, which runs with the
// oracle on the forward rig only. --segmenters, --rigs or --methods run their cross product on
// every seed instead. --quick: seed 1, the donut, forward rig, oracle and GrabCut, vcar:paper,
// vcar:robust and naive, at 320x240 (the ctest benchmarks/field_quick).
//
// Each (seed, target): the stage built in process (synth::make_stage with that target), exactly
// as `vcar synth --stage` builds it (examples/vcar_cli/cmd_synth.cpp: RigParams::fill =
// synth::stage_rig_fill, the rig's seed = the seed); the prompt is the box of the target's
// visible ground truth on the rig's reference view (prompt.json's "box").
//
// Segmenters:
//  - grabcut: vcar::opencv::GrabCutSegmenter on the box (lifted to every frame by
//    algo/prompt_lift.hpp), as `vcar segment --segmenter grabcut --box` (skipped, with a message,
//    in builds without OpenCV);
//  - oracle: synth::OracleSegmenter in the honest rendered mode (what each frame's render draws:
//    the whole scene in the coarse round, G_coarse in the fine round), no failure;
//  - oracle-sam: the same with the SAM-like failures of synth/sam_failures.hpp at the moderate
//    levels of sam_levels() below (--sam changes them);
//  - oracle-sam-nodrift: oracle-sam without its drift along the sequence (the same per-frame
//    draws), so the field tells the per-frame failures from the drift;
//  - exact (only when named): synth::OracleSegmenter by name, no failure: the target where it is
//    the nearest surface in the capture's frames, the target alone (its render, alpha > 0.5) in
//    the fine round's. Issue 47's soft-edge case: the object's own faint edge Gaussians must stay;
//  - isnet (only when named): ISNet through the external segmenter protocol
//    (examples/segmenters/isnet, installed by its install.sh), each frame cut around the
//    prompt's box lifted into it, as `vcar segment --segmenter-cmd`.
// Methods: vcar:paper (the paper's preset for the rig: nvos forward-facing, lerf 360), vcar:robust
// (the library's default, VcarParams::robust()), vcar:code (VcarParams::reference_code(): the
// released code's constants and rules, conventions §7), vcar:lean (issue 47's candidate default:
// the paper's preset plus the occlusion test and view reliability, docs/notes/
// field-probes-2026-12-02.md), and the peers (evidence/methods.hpp), which take the coarse
// round's training masks. An ablation row: vcar:robust@KEY=VALUE[+KEY=VALUE...], the default with
// those parameters changed (text keys as --set; e.g. vcar:robust@snap=false is the default
// without R11-R12), its CSV variant the text after "vcar:".
//
// Cost: the coarse round's training masks (frames rendering the whole scene) are the same for
// every method of a (seed, target, rig, segmenter): they are computed once, and VCAR's coarse
// round is answered from that cache (CachedCoarse); the fine round calls the segmenter for real.
// Times per run: t_segment = the segmenter seconds a real run spends (the cached coarse masks'
// seconds counted in every run that uses them, plus VCAR's fine round); t_method = the method
// without the segmenter (VCAR's own renders included); t_render = VCAR's frame renders for the
// segmenter (the fine round; the training images are photographs in a real capture, so their
// renders here are counted nowhere); time_s = t_method + t_segment; t_own (VCAR's rows) =
// t_method without any render VCAR asked for (the fine round's frames and the depth the robust
// vote renders itself): issue 47's "own time".
// 2D quality (mask_iou): the mean IoU of the coarse-round masks against the target's visible
// ground truth of each training view, over the frames with a mask; mask_none counts the frames
// answered "no mask" (of mask_frames).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "vcar/algo/params.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/algo/prompt_lift.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/eval/mask_metrics.hpp"
#include "vcar/io/external_segmenter.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/io/params_text.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/rendered_labels.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/stage.hpp"
#include "vcar/synth/stage_json.hpp"
#ifdef VCAR_FIELD_HAS_OPENCV
#include "vcar/opencv/grabcut_segmenter.hpp"
#endif

#include "evidence/methods.hpp"
#include "evidence/peak_memory.hpp"
#include "evidence/run_record.hpp"

namespace {

using namespace vcar;
using evidence::RunRecord;
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The seed split (docs/results.md "Field"): tune on these, report on those.
const std::vector<int> kTuningSeeds = {1, 2};
const std::vector<int> kHeldoutSeeds = {11, 12, 13, 14, 15};

// oracle-sam: moderate SAM-like failures (synth/sam_failures.hpp). Per frame: another object's
// mask (the floor included) with p 0.05, half of the object with p 0.1, a touching background
// piece within 8 px (at 640 px width; scaled with the width) with p 0.2, and a drift of 0.2 px
// per frame along the sequence (5 px at the 25th frame).
// --sam key=value (p_wrong, p_part, p_leak, leak_px, drift_px; pixels as given, not scaled)
// replaces one level.
synth::SamFailures sam_levels(int width, const std::vector<std::string>& overrides = {}) {
  synth::SamFailures s;
  s.p_wrong = 0.05;
  s.p_part = 0.1;
  s.p_leak = 0.2;
  s.leak_px = std::max(1, static_cast<int>(std::lround(8.0 * width / 640.0)));
  s.drift_px = 0.2f * static_cast<float>(width) / 640.f;
  for (const std::string& kv : overrides) {
    const auto eq = kv.find('=');
    const std::string key = kv.substr(0, eq);
    const double v = eq == std::string::npos ? NAN : std::stod(kv.substr(eq + 1));
    if (key == "p_wrong") s.p_wrong = v;
    else if (key == "p_part") s.p_part = v;
    else if (key == "p_leak") s.p_leak = v;
    else if (key == "leak_px") s.leak_px = static_cast<int>(v);
    else if (key == "drift_px") s.drift_px = static_cast<float>(v);
    else throw Error("unknown key in '" + kv + "' (p_wrong, p_part, p_leak, leak_px, drift_px)", "--sam");
  }
  s.validate();
  return s;
}

const std::vector<std::string> kSegmenters = {"grabcut", "oracle", "oracle-sam", "oracle-sam-nodrift"};
// Segmenters run only when named (--segmenters): ISNet costs 4-10 s a frame on 2 cores; exact is
// a ceiling, not a segmenter.
const std::vector<std::string> kNamedOnly = {"isnet", "exact"};
const std::vector<std::string> kRigs = {"forward", "orbit"};  // the default grid's and the cross product's
// Every rig --rigs may name: also the sparse capture (an orbit of 6 views unless the stage file
// says "views", synth::sparse_rig), only when named.
const std::vector<std::string> kAllRigs = {"forward", "orbit", "sparse"};

std::vector<std::string> all_methods() {
  std::vector<std::string> m = {"vcar:paper", "vcar:robust", "vcar:code", "vcar:lean"};
  for (const auto& p : evidence::kPeers) m.push_back(p);
  return m;
}

// ---------------------------------------------------------------------------------------------
// A segmenter behind a function (GrabCut and the oracles alike).
using SegmentFn = std::function<void(const FrameSequence&, const Prompt&, const MaskSink&)>;

// CPU seconds of the calling thread (GrabCut is single-threaded: a frame's CPU seconds are its
// time on an idle core, whatever else shares the machine).
double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// A segmenter of the field: `seconds`, when set, holds the sum of its per-frame seconds so far
// (GrabCut runs two frames at a time, so its wall time is not what a sequential run spends).
struct FieldSegmenter {
  SegmentFn fn;
  std::shared_ptr<double> seconds;
};

#ifdef VCAR_FIELD_HAS_OPENCV
// vcar::opencv::GrabCutSegmenter's per-frame rule (its segment(): the box of frame k, the prompt
// points seeding frame 0, "no mask" without a box) on two frames at a time: the frames are
// rendered in order on the calling thread, GrabCut (single-threaded) runs on both at once, the
// masks go to the sink in order. The masks are those of GrabCutSegmenter::segment (the quick
// mode checks it, same_as_library); `seconds` adds up each frame's GrabCut CPU seconds (what a
// sequential run spends on an idle core; the wall time of two at once on a shared machine is
// neither that nor half of it).
class PairedGrabCut {
public:
  explicit PairedGrabCut(opencv::GrabCutSegmenter g) : g_(std::move(g)), seconds_(std::make_shared<double>(0.0)) {}
  const std::shared_ptr<double>& seconds() const { return seconds_; }

  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    const opencv::GrabCutParams& gp = g_.params();
    std::vector<opencv::GrabCutSeed> seeds;
    for (std::size_t p = 0; p < prompt.points.size(); ++p)
      seeds.push_back({prompt.points[p], p >= prompt.point_labels.size() || prompt.point_labels[p] != 0});
    struct Job {
      std::optional<Eigen::Vector4f> box;
      ImageRGB8 image;
      std::optional<Mask> mask;
      double seconds = 0;
      std::exception_ptr error;
    };
    for (std::size_t s = 0; s < frames.size(); s += 2) {
      Job jobs[2];
      const std::size_t n = std::min<std::size_t>(2, frames.size() - s);
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = s + i;
        const Camera& cam = frames.cameras[k];
        jobs[i].box = g_.box(frames, k, prompt);
        if (!jobs[i].box) continue;
        jobs[i].image = frames.image(k);
        if (jobs[i].image.width != cam.width || jobs[i].image.height != cam.height)
          throw Error("the frame's image is not its camera's size", "GrabCut, frame " + std::to_string(k));
      }
      auto work = [&](std::size_t i) {
        Job& j = jobs[i];
        if (!j.box) return;
        const std::size_t k = s + i;
        const Camera& cam = frames.cameras[k];
        const double c0 = thread_cpu_s();
        try {
          const float radius = gp.seed_radius * std::hypot(static_cast<float>(cam.width), static_cast<float>(cam.height));
          const bool seeded = k == 0 && gp.seed_radius > 0.f && !seeds.empty();
          j.mask = opencv::grabcut(j.image, *j.box, gp,
                                   seeded ? std::span<const opencv::GrabCutSeed>(seeds) : std::span<const opencv::GrabCutSeed>{},
                                   radius, "GrabCut, frame " + std::to_string(k) + " (view '" + cam.name + "')");
        } catch (...) {
          j.error = std::current_exception();
        }
        j.seconds = thread_cpu_s() - c0;
      };
      std::thread other;
      if (n == 2) other = std::thread(work, 1);
      work(0);
      if (other.joinable()) other.join();
      for (std::size_t i = 0; i < n; ++i) {
        if (jobs[i].error) std::rethrow_exception(jobs[i].error);
        *seconds_ += jobs[i].seconds;
        sink(s + i, jobs[i].mask ? &*jobs[i].mask : nullptr);
      }
    }
  }

  // Whether GrabCutSegmenter::segment gives the same masks on `frames` (the quick mode's check).
  bool same_as_library(const FrameSequence& frames, const Prompt& prompt) {
    std::vector<std::optional<Mask>> a(frames.size()), b(frames.size());
    segment(frames, prompt, [&](std::size_t k, const Mask* m) { if (m) a.at(k) = *m; });
    g_.segment(frames, prompt, [&](std::size_t k, const Mask* m) { if (m) b.at(k) = *m; });
    for (std::size_t k = 0; k < frames.size(); ++k)
      if (a[k].has_value() != b[k].has_value() || (a[k] && a[k]->data != b[k]->data)) return false;
    return true;
  }

private:
  opencv::GrabCutSegmenter g_;
  std::shared_ptr<double> seconds_;
};
static_assert(Segmenter<PairedGrabCut>);
#endif

// The renderer VCAR runs get: the CPU renderer with its last two renders kept, so that a frame
// rendered for the segmenter (with depth, in a round that keeps depth) and voted on after the
// frame rendered next (PairedGrabCut asks for two frames before delivering their masks) is not
// rendered a second time by the vote: the renders a sequential run does, no more.
class LastRenders {
public:
  explicit LastRenders(cpu::TiledRenderer& r) : r_(&r) {}
  RenderOutput render(const RenderRequest& q) {
    // Counted from the call to the return: the copies this cache makes (an output kept, an output
    // handed out again) are the harness's, not the method's own time.
    const auto t0 = Clock::now();
    for (const auto& [key, out] : kept_)
      if (key.same(q)) {
        RenderOutput copy = out;
        seconds_ += since(t0);
        return copy;
      }
    RenderOutput out = r_->render(q);
    kept_.emplace_back(Key{q}, out);
    if (kept_.size() > 2) kept_.pop_front();
    seconds_ += since(t0);
    return out;
  }
  double seconds() const { return seconds_; }  // every render asked for, and the cache's copies

private:
  struct Key {
    RenderRequest q;
    std::size_t subset_size = q.subset ? q.subset->size() : 0;
    bool same(const RenderRequest& o) const {
      return o.scene == q.scene && o.camera == q.camera && o.subset == q.subset && o.log_scale == q.log_scale &&
             o.want_depth == q.want_depth && o.background == q.background &&
             (o.subset ? o.subset->size() : 0) == subset_size;
    }
  };
  cpu::TiledRenderer* r_;
  std::deque<std::pair<Key, RenderOutput>> kept_;
  double seconds_ = 0;
};
static_assert(Renderer<LastRenders>);

// VCAR's segmenter: the coarse round (frames drawing the whole scene) answered from the masks
// computed once for the case, every other round by the segmenter itself.
class CachedCoarse {
public:
  // folder: later rounds answered as a mask folder answers them (MaskFolderSegmenter::has_masks_of).
  CachedCoarse(SegmentFn inner, const std::vector<std::string>& names, const std::vector<std::optional<Mask>>& masks,
               bool folder = false)
      : inner_(std::move(inner)), names_(&names), masks_(&masks), folder_(folder) {}
  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    if (folder_ && !MaskFolderSegmenter::has_masks_of(frames)) {
      for (std::size_t k = 0; k < frames.size(); ++k) sink(k, nullptr);
      return;
    }
    bool whole = !frames.subset;
    for (std::size_t k = 0; whole && frames.drawn && k < frames.size(); ++k) whole = frames.drawn(k) == nullptr;
    if (!whole) {
      inner_(frames, prompt, sink);
      return;
    }
    if (frames.size() != names_->size()) throw Error("the coarse round's frames differ from the cache's", "CachedCoarse");
    for (std::size_t k = 0; k < frames.size(); ++k) {
      if (frames.cameras[k].name != (*names_)[k]) throw Error("frame " + std::to_string(k) + " is not the cached view", "CachedCoarse");
      sink(k, (*masks_)[k] ? &*(*masks_)[k] : nullptr);
    }
    ++hits_;
  }
  int hits() const { return hits_; }

private:
  SegmentFn inner_;
  const std::vector<std::string>* names_;
  const std::vector<std::optional<Mask>>* masks_;
  bool folder_ = false;
  int hits_ = 0;
};
static_assert(Segmenter<CachedCoarse>);

// ---------------------------------------------------------------------------------------------
struct Options {
  bool quick = false;
  bool coarse_only = false;  // --coarse-only: no fine round in any VCAR run (Reselection)
  bool mask_folder = false;  // --mask-folder: the fine round answered as a folder of masks answers it
  std::filesystem::path out = "field-out";
  std::filesystem::path stage = VCAR_FIELD_STAGE_DEFAULT;
  std::string seeds = "all";
  std::vector<std::string> targets, rigs, segmenters, methods, set;
  std::vector<std::string> sam;  // --sam key=value: oracle-sam's levels instead of sam_levels' defaults
  std::string isnet = VCAR_FIELD_ISNET_DEFAULT;  // --isnet CMD: the isnet segmenter's program
  int width = 0, height = 0;
};

std::vector<int> parse_seeds(const std::string& s) {
  if (s == "tuning") return kTuningSeeds;
  if (s == "heldout") return kHeldoutSeeds;
  std::vector<int> out;
  if (s == "all") {
    out = kTuningSeeds;
    out.insert(out.end(), kHeldoutSeeds.begin(), kHeldoutSeeds.end());
    return out;
  }
  for (std::size_t b = 0, c; b <= s.size(); b = c + 1) {
    c = s.find(',', b);
    if (c == std::string::npos) c = s.size();
    if (c > b) out.push_back(std::stoi(s.substr(b, c - b)));
  }
  if (out.empty()) throw Error("no seed in '" + s + "'", "--seeds");
  return out;
}

std::string role_of(int seed) {
  if (std::find(kTuningSeeds.begin(), kTuningSeeds.end(), seed) != kTuningSeeds.end()) return "tuning";
  if (std::find(kHeldoutSeeds.begin(), kHeldoutSeeds.end(), seed) != kHeldoutSeeds.end()) return "heldout";
  return "other";
}

// One (segmenter, rig) cell of the plan: the methods it runs, on every seed or the held-out ones.
struct Cell {
  std::string segmenter, rig;
  std::vector<std::string> methods;
  bool heldout_only = false;
};

// The default grid, cut from the full one (docs/results.md "Field" says why and what it costs):
// GrabCut on the forward-facing rig, on every seed (the tuning seeds are where the default is
// tuned against GrabCut's failures); the oracle on both rigs and the SAM-like oracle on the
// forward rig (with and without its drift), on the held-out seeds. lbg (a kNN graph of the
// whole scene: 25-65 s a run on the stage's 390k Gaussians) only with the oracle on the forward
// rig. Explicit --segmenters, --rigs or --methods: their cross product instead, on every seed.
std::vector<Cell> plan_cells(const Options& o) {
  std::vector<Cell> cells;
  std::vector<std::string> no_lbg = all_methods();
  std::erase(no_lbg, std::string("lbg"));
  if (o.quick) {
    for (const char* s : {"oracle", "grabcut"}) cells.push_back({s, "forward", {"vcar:paper", "vcar:robust", "naive"}});
  } else {
    cells.push_back({"grabcut", "forward", no_lbg});
    cells.push_back({"oracle", "forward", all_methods(), true});
    cells.push_back({"oracle", "orbit", no_lbg, true});
    cells.push_back({"oracle-sam", "forward", no_lbg, true});
    cells.push_back({"oracle-sam-nodrift", "forward", no_lbg, true});
  }
  if (!o.segmenters.empty() || !o.rigs.empty() || !o.methods.empty()) {  // explicit lists: their cross product
    cells.clear();
    for (const auto& s : o.segmenters.empty() ? kSegmenters : o.segmenters)
      for (const auto& r : o.rigs.empty() ? (o.quick ? std::vector<std::string>{"forward"} : kRigs) : o.rigs)
        cells.push_back({s, r, o.methods.empty() ? (o.quick ? std::vector<std::string>{"vcar:paper", "vcar:robust", "naive"} : all_methods()) : o.methods});
  }
  for (const Cell& c : cells) {
    if (std::find(kSegmenters.begin(), kSegmenters.end(), c.segmenter) == kSegmenters.end() &&
        std::find(kNamedOnly.begin(), kNamedOnly.end(), c.segmenter) == kNamedOnly.end())
      throw Error("unknown segmenter '" + c.segmenter + "' (grabcut, oracle, oracle-sam, oracle-sam-nodrift, isnet, exact)", "--segmenters");
    if (std::find(kAllRigs.begin(), kAllRigs.end(), c.rig) == kAllRigs.end())
      throw Error("unknown rig '" + c.rig + "' (forward, orbit, sparse)", "--rigs");
    const std::vector<std::string> known = all_methods();
    for (const auto& m : c.methods)
      if (m.rfind("vcar:robust@", 0) != 0 && std::find(known.begin(), known.end(), m) == known.end())
        throw Error("unknown method '" + m + "' (vcar:paper, vcar:robust, vcar:code, vcar:lean, naive, sagd, flashsplat, gaussiancut, ludvig, lbg)", "--methods");
  }
  return cells;
}

// ---------------------------------------------------------------------------------------------
class Driver {
public:
  explicit Driver(const Options& o) : opt_(o), sf_(synth::read_stage_file(o.stage)) {
    for (const auto& ob : sf_.stage.objects) scenes_.push_back(io::read_scene(ob.file));
    width_ = o.width > 0 ? o.width : sf_.width > 0 ? sf_.width : 640;
    height_ = o.width > 0 ? o.height : sf_.width > 0 ? sf_.height : 480;
    if (o.quick && o.width == 0) { width_ = 320; height_ = 240; }
  }

  std::vector<std::string> targets() const {
    std::vector<std::string> t;
    if (opt_.quick && opt_.targets.empty()) return {"donut"};
    for (const auto& ob : sf_.stage.objects)
      if (opt_.targets.empty() || std::find(opt_.targets.begin(), opt_.targets.end(), ob.name) != opt_.targets.end())
        t.push_back(ob.name);
    if (t.empty()) throw Error("no object of the stage is listed", "--targets");
    return t;
  }
  int width() const { return width_; }
  std::size_t runs() const { return rows_.size(); }
  int height() const { return height_; }

  void open() {
    std::filesystem::create_directories(opt_.out);
    csv_.open(opt_.out / "field.csv", std::ios::trunc);
    if (!csv_) throw Error("cannot write", (opt_.out / "field.csv").string());
    csv_ << evidence::csv_header() << ",stage,role,segmenter,mask_iou,mask_none,mask_frames,t_own\n";
  }

  // Every cell of one (seed, target).
  void run(int seed, const std::string& target, const std::vector<Cell>& cells) {
    synth::Stage stage = sf_.stage;
    stage.target = target;
    const synth::World w = synth::make_stage(stage, scenes_, static_cast<std::uint64_t>(seed));
    const std::vector<Index> truth = w.gaussians_of(w.target_id);
    const bool heldout = role_of(seed) == "heldout";
    std::set<std::string> rigs;
    bool oracle = false;
    for (const Cell& c : cells)
      if (heldout || !c.heldout_only) {
        rigs.insert(c.rig);
        oracle = oracle || c.segmenter != "grabcut";
      }
    // The oracles' label copies of the scene (synth/rendered_labels.hpp), shared by both oracles.
    std::shared_ptr<const synth::RenderedLabels> labels;
    if (oracle) labels = std::make_shared<const synth::RenderedLabels>(w);
    for (const std::string& rig_name : kAllRigs) {
      if (!rigs.count(rig_name)) continue;
      synth::RigParams rp;  // as `vcar synth --stage` (cmd_synth.cpp)
      rp.intrinsics = synth::make_intrinsics(width_, height_);
      rp.n_train = sf_.views;
      rp.seed = static_cast<std::uint64_t>(seed);
      rp.fill = synth::stage_rig_fill;
      const synth::Rig rig = synth::make_rig(rig_name, w, rp);
      Case k;
      k.seed = seed; k.target = target; k.rig_name = rig_name; k.w = &w; k.rig = &rig; k.truth = &truth;
      for (const Camera& c : rig.eval) k.gt.push_back(synth::silhouette_mask(w, c, w.target_id, renderer_));
      for (const Camera& c : rig.train) k.visible.push_back(synth::visible_mask(w, c, w.target_id, renderer_));
      k.prompt.reference_view = rig.reference;
      k.prompt.box = synth::mask_box(k.visible[rig.reference], "the target on the reference view");
      k.order = vcar::detail::training_order(rig.train.size(), rig.reference);
      for (const Cell& c : cells) {
        if (c.rig != rig_name || (!heldout && c.heldout_only)) continue;
        const auto tc = Clock::now();
        try {
          run_cell(k, c, labels);
        } catch (const Error& e) {  // one failing case does not end the run: field.json lists it
          std::fprintf(stderr, "bench_field: seed %d %s %s %s failed: %s\n", seed, target.c_str(), rig_name.c_str(),
                       c.segmenter.c_str(), e.what());
          skipped_.push_back("seed " + std::to_string(seed) + " " + target + " " + rig_name + " " + c.segmenter + ": " + e.what());
        }
        std::fprintf(stderr, "  cell: %.0f s\n", since(tc));
      }
    }
  }

  void write_summary(double wall_s, const std::vector<int>& seeds, const std::vector<Cell>& plan) {
    nlohmann::json j;
    j["mode"] = opt_.quick ? "quick" : "full";
    j["stage"] = opt_.stage.filename().string();
    j["threads"] = max_threads();
    j["wall_s"] = wall_s;
    j["runs"] = rows_.size();
    j["width"] = width_;
    j["height"] = height_;
    j["seeds"] = seeds;
    j["tuning_seeds"] = kTuningSeeds;
    j["heldout_seeds"] = kHeldoutSeeds;
    const synth::SamFailures s = sam_levels(width_, opt_.sam);
    j["oracle_sam"] = {{"p_wrong", s.p_wrong}, {"p_part", s.p_part}, {"p_leak", s.p_leak},
                       {"leak_px", s.leak_px}, {"drift_px", s.drift_px}};
    j["skipped"] = skipped_;
    nlohmann::json cells = nlohmann::json::array();
    for (const Cell& c : plan)
      cells.push_back({{"segmenter", c.segmenter}, {"rig", c.rig}, {"methods", c.methods},
                       {"seeds", c.heldout_only ? "heldout" : "all"}});
    j["cells"] = cells;
    j["time_columns"] = "t_segment: segmenter seconds of a real run (cached coarse masks counted in each run); "
                        "t_method: the method without the segmenter; time_s = t_method + t_segment";
    // Means over seeds and targets, per role / segmenter / rig / method.
    std::map<std::string, std::vector<const Row*>> groups;
    for (const Row& r : rows_) groups[r.role + "/" + r.segmenter + "/" + r.rec.rig + "/" + r.name].push_back(&r);
    nlohmann::json g = nlohmann::json::object();
    for (const auto& [key, v] : groups) {
      auto mean = [&](auto f) { double s = 0; for (auto* r : v) s += f(*r); return s / static_cast<double>(v.size()); };
      g[key] = {{"runs", v.size()},
                {"f1_3d", mean([](const Row& r) { return r.rec.f1_3d; })},
                {"precision_3d", mean([](const Row& r) { return r.rec.precision_3d; })},
                {"recall_3d", mean([](const Row& r) { return r.rec.recall_3d; })},
                {"miou", mean([](const Row& r) { return r.rec.miou; })},
                {"boundary_iou", mean([](const Row& r) { return r.rec.boundary_iou; })},
                {"mask_iou", mean([](const Row& r) { return r.mask_iou; })},
                {"time_s", mean([](const Row& r) { return r.rec.time_s; })}};
    }
    j["means"] = g;
    std::ofstream(opt_.out / "field.json") << j.dump(2) << "\n";
  }

private:
  struct Case {
    int seed = 0;
    std::string target, rig_name;
    const synth::World* w = nullptr;
    const synth::Rig* rig = nullptr;
    const std::vector<Index>* truth = nullptr;
    std::vector<Mask> gt, visible;  // held-out silhouettes; training views' visible ground truth
    Prompt prompt;
    std::vector<std::size_t> order;  // frame k of a round -> training view
  };
  struct Row {
    RunRecord rec;
    std::string name, role, segmenter;
    double mask_iou = 0;
  };

  // The segmenter of a cell; empty when this build lacks it (message once).
  FieldSegmenter make_segmenter(const std::string& name, const Case& k, const std::shared_ptr<const synth::RenderedLabels>& labels) {
    if (name == "grabcut") {
#ifdef VCAR_FIELD_HAS_OPENCV
      auto g = std::make_shared<PairedGrabCut>(opencv::GrabCutSegmenter(lift_prompt(k.w->scene, k.rig->train, k.prompt, renderer_)));
      return {[g](const FrameSequence& f, const Prompt& p, const MaskSink& s) { g->segment(f, p, s); }, g->seconds()};
#else
      if (skipped_.empty())
        std::fprintf(stderr, "bench_field: this build has no OpenCV: the grabcut rows are skipped\n");
      skipped_.push_back("grabcut: no OpenCV in this build");
      return {};
#endif
    }
    if (name == "isnet") {
      // The external segmenter protocol (io/external_segmenter.hpp), as `vcar segment
      // --segmenter-cmd` runs it: prompt.json's "boxes" are the prompt lifted into every frame.
      // `seconds`: the program's wall time, the frames' renders taken out.
      auto lifted = std::make_shared<LiftedPrompt>(lift_prompt(k.w->scene, k.rig->train, k.prompt, renderer_));
      io::ExternalSegmenterOptions eo;
      eo.boxes = [lifted](std::size_t, const Camera& c) { return lifted->box_for(c); };
      auto e = std::make_shared<io::ExternalSegmenter>(opt_.isnet, eo);
      auto secs = std::make_shared<double>(0.0);
      return {[e, secs](const FrameSequence& f, const Prompt& p, const MaskSink& s) {
                double renders = 0;
                FrameSequence timed = f;
                timed.image = [&](std::size_t k) {
                  const auto tr = Clock::now();
                  ImageRGB8 img = f.image(k);
                  renders += since(tr);
                  return img;
                };
                const auto t0 = Clock::now();
                e->segment(timed, p, s);
                *secs += since(t0) - renders;
              },
              secs};
    }
    if (name != "oracle" && name != "oracle-sam" && name != "oracle-sam-nodrift" && name != "exact")
      throw Error("unknown segmenter '" + name + "'", "--segmenters");
    synth::OracleParams p;
    p.mode = name == "exact" ? synth::OracleMode::by_name : synth::OracleMode::rendered;
    p.seed = static_cast<std::uint64_t>(k.seed) * 7919u + 13u;
    if (name == "oracle-sam") p.sam = sam_levels(width_, opt_.sam);
    if (name == "oracle-sam-nodrift") {  // the same draws per frame, without the sequence's drift
      p.sam = sam_levels(width_, opt_.sam);
      p.sam.drift_px = 0.f;
    }
    auto o = std::make_shared<synth::OracleSegmenter>(*k.w, p, renderer_, labels);
    return {[o](const FrameSequence& f, const Prompt& pr, const MaskSink& s) {
              // A real segmenter looks at each frame's render: the fine round's renders of
              // G_coarse are the pipeline's cost (t_render), as with GrabCut. (The coarse round's
              // frames are the capture's photographs: nothing to render.) Rendered just before
              // its mask is delivered, so the pipeline reuses that render's depth.
              if (!f.subset) return o->segment(f, pr, s);
              o->segment(f, pr, [&](std::size_t k, const Mask* m) {
                (void)f.image(k);
                s(k, m);
              });
            },
            nullptr};
  }

  void run_cell(const Case& k, const Cell& cell, const std::shared_ptr<const synth::RenderedLabels>& labels) {
    const synth::World& w = *k.w;
    const synth::Rig& rig = *k.rig;
    const FieldSegmenter seg = make_segmenter(cell.segmenter, k, labels);
    if (!seg.fn) return;

    // The coarse round's masks, once: frames in VCAR's order (reference first), whole-scene renders.
    std::vector<Camera> frames;
    std::vector<std::string> names;
    for (std::size_t j : k.order) { frames.push_back(rig.train[j]); names.push_back(rig.train[j].name); }
    std::vector<std::optional<Mask>> by_frame(frames.size());
    double t_photos = 0;
    FrameSequence seq;
    seq.cameras = frames;
    seq.image = [&](std::size_t f) {
      const auto tr = Clock::now();
      ImageRGB8 img = to_8bit(vcar::detail::render_view(renderer_, w.scene, frames[f], nullptr).rgb);
      t_photos += since(tr);
      return img;
    };
    const auto ts = Clock::now();
    seg.fn(seq, k.prompt, [&](std::size_t f, const Mask* m) { if (m) by_frame.at(f) = *m; });
    // The segmenter's seconds (the frames' renders stand for the capture's photographs).
    const double t_coarse = seg.seconds ? *seg.seconds : since(ts) - t_photos;

    // 2D quality of those masks, and the peers' provider (by training view).
    std::vector<std::optional<Mask>> masks(rig.train.size());
    double iou_sum = 0;
    int answered = 0, none = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const std::size_t j = k.order[f];
      masks[j] = by_frame[f];
      if (!by_frame[f]) { ++none; continue; }
      iou_sum += eval::mask_iou(*by_frame[f], k.visible[j], "mask of view '" + rig.train[j].name + "'");
      ++answered;
    }
    const double mask_iou = answered ? iou_sum / answered : 0.0;
    const baselines::MaskProvider provider = baselines::masks_from(masks);
    std::fprintf(stderr, "seed %d %-7s %-7s %-10s masks: IoU %.3f, %d none, %.1fs (+%.1fs renders)\n", k.seed,
                 k.target.c_str(), k.rig_name.c_str(), cell.segmenter.c_str(), mask_iou, none, t_coarse, t_photos);
#ifdef VCAR_FIELD_HAS_OPENCV
    if (opt_.quick && cell.segmenter == "grabcut") {  // PairedGrabCut = GrabCutSegmenter, on this case
      PairedGrabCut check(opencv::GrabCutSegmenter(lift_prompt(w.scene, rig.train, k.prompt, renderer_)));
      if (!check.same_as_library(seq, k.prompt)) throw Error("PairedGrabCut's masks differ from GrabCutSegmenter's", "bench_field");
      std::fprintf(stderr, "PairedGrabCut: the coarse masks equal GrabCutSegmenter's\n");
    }
#endif

    for (const std::string& m : cell.methods) {
      Row row;
      RunRecord& r = row.rec;
      row.name = m;
      row.role = role_of(k.seed);
      row.segmenter = cell.segmenter;
      row.mask_iou = mask_iou;
      const bool is_vcar = m.rfind("vcar:", 0) == 0;
      r.method = is_vcar ? "vcar" : m;
      r.variant = is_vcar ? m.substr(5) : "full";
      r.rig = k.rig_name; r.seed = k.seed; r.gaussians = w.scene.size(); r.object_gaussians = k.truth->size();
      r.failure = "none"; r.level = 0; r.width = width_; r.height = height_; r.target = k.target;
      r.n_train = static_cast<int>(rig.train.size()); r.n_eval = static_cast<int>(rig.eval.size());
      const double rss0 = evidence::reset_peak();
      std::vector<Index> sel;
      std::optional<LogScales> scales;
      std::optional<GaussianScene> own_scene;
      double t_own = NAN;  // VCAR: t_method without any render (issue 47's cost: the method's own time)
      const auto t0 = Clock::now();
      if (is_vcar) {
        VcarParams p;
        if (r.variant == "paper") {
          p = evidence::is_360(k.rig_name) ? VcarParams::lerf() : VcarParams::nvos();
          r.preset = evidence::is_360(k.rig_name) ? "lerf" : "nvos";
        } else if (r.variant == "robust" || r.variant.rfind("robust@", 0) == 0) {
          p = VcarParams::robust();
          for (const std::string& kv : opt_.set) io::set_parameter(p, kv);
          // An ablation row: robust@k=v+k=v, applied after --set.
          for (std::size_t b = r.variant.find('@'); b != std::string::npos;) {
            const std::size_t e = r.variant.find('+', b + 1);
            io::set_parameter(p, r.variant.substr(b + 1, e == std::string::npos ? std::string::npos : e - b - 1));
            b = e;
          }
          r.preset = "robust";
        } else if (r.variant == "code") {
          p = VcarParams::reference_code();
          r.preset = "reference_code";
        } else if (r.variant == "lean") {
          // Issue 47's candidate (docs/notes/field-probes-2026-12-02.md): the paper's preset for
          // the rig plus the occlusion test in both rounds (R3) and view reliability (R13), no
          // shrinkage between evidence levels (kappa 0). Not a library preset yet.
          p = evidence::is_360(k.rig_name) ? VcarParams::lerf() : VcarParams::nvos();
          p.evidence.occlusion = p.reliability.enabled = true;
          p.evidence.kappa = 0.f;
          r.preset = evidence::is_360(k.rig_name) ? "lerf+R3+R13" : "nvos+R3+R13";
        } else {
          throw Error("unknown VCAR variant '" + r.variant + "' (vcar:paper, vcar:robust, vcar:code or vcar:lean)", "--methods");
        }
        if (opt_.coarse_only) {  // the coarse vote is the result, as in Reselection or with SSS off
          p.enable_sss = p.force_fine_round = false;
          r.preset += ":coarse-only";
        }
        if (opt_.mask_folder) r.preset += ":mask-folder";
        CachedCoarse cached(seg.fn, names, by_frame, opt_.mask_folder);
        LastRenders renderer(renderer_);
        const double seg0 = seg.seconds ? *seg.seconds : 0.0;
        SegmentationResult res = segment(w.scene, rig.train, k.prompt, renderer, cached, p);
        evidence::record_vcar(r, res.diagnostics, since(t0), rig.train.size());
        if (cached.hits() != 1) throw Error("the coarse round was not answered from the cache", "bench_field");
        // t_method: the run without its segmenter calls (as measured by the pipeline); t_segment:
        // the cached coarse masks' seconds (this run would have spent them) and the fine round's
        // (GrabCut: the sum of its frames' seconds, what a sequential run spends).
        if (seg.seconds) r.t_segment = *seg.seconds - seg0;
        r.t_segment += t_coarse;
        r.time_s = r.t_method + r.t_segment;
        t_own = r.t_method - renderer.seconds();
        sel = std::move(res.indices);
        if (!sel.empty()) scales = std::move(res.log_scale);
      } else {
        r.preset = evidence::is_360(k.rig_name) ? "360" : "forward";
        evidence::PeerSelection res = evidence::run_peer(m, renderer_, w.scene, rig.train, provider, evidence::is_360(k.rig_name));
        r.t_method = since(t0);
        sel = std::move(res.selected);
        own_scene = std::move(res.own_scene);
        r.t_segment = t_coarse;
        r.time_s = r.t_method + t_coarse;
        r.frames_segmented = static_cast<int>(rig.train.size());
      }
      r.peak_mib = evidence::peak_mib();
      r.peak_delta_mib = std::max(0.0, r.peak_mib - rss0);
      evidence::evaluate(r, renderer_, w.scene, rig.eval, k.gt, *k.truth, sel, scales ? &*scales : nullptr,
                         own_scene ? &*own_scene : nullptr);
      csv_ << evidence::csv_row(r) << "," << opt_.stage.stem().string() << "," << row.role << "," << cell.segmenter
           << "," << evidence::fmt(mask_iou) << "," << none << "," << frames.size() << "," << evidence::fmt(t_own) << "\n";
      csv_.flush();
      std::fprintf(stderr, "  %-7s %-11s %-8s F1_3d %.3f (P %.3f R %.3f) mIoU %.3f bIoU %.3f  %.1fs (method %.1fs)\n",
                   row.role.c_str(), m.c_str(), r.preset.c_str(), r.f1_3d, r.precision_3d, r.recall_3d, r.miou,
                   r.boundary_iou, r.time_s, r.t_method);
      rows_.push_back(std::move(row));
    }
  }

  Options opt_;
  synth::StageFile sf_;
  std::vector<GaussianScene> scenes_;
  int width_ = 640, height_ = 480;
  cpu::TiledRenderer renderer_;
  std::ofstream csv_;
  std::vector<Row> rows_;
  std::vector<std::string> skipped_;
};

std::vector<std::string> split(const std::string& v) {
  std::vector<std::string> out;
  for (std::size_t b = 0, c; b <= v.size(); b = c + 1) {
    c = v.find(',', b);
    if (c == std::string::npos) c = v.size();
    if (c > b) out.push_back(v.substr(b, c - b));
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
    else if (a == "--coarse-only") o.coarse_only = true;
    else if (a == "--mask-folder") o.mask_folder = true;
    else if (a == "--out") o.out = value();
    else if (a == "--stage") o.stage = value();
    else if (a == "--seeds") o.seeds = value();
    else if (a == "--targets") o.targets = split(value());
    else if (a == "--rigs") o.rigs = split(value());
    else if (a == "--segmenters") o.segmenters = split(value());
    else if (a == "--methods") o.methods = split(value());
    else if (a == "--set") o.set.push_back(value());
    else if (a == "--sam") o.sam.push_back(value());
    else if (a == "--isnet") o.isnet = value();
    else if (a == "--width") o.width = std::stoi(value());
    else if (a == "--height") o.height = std::stoi(value());
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--coarse-only | --mask-folder] [--out DIR] [--stage FILE] [--seeds tuning|heldout|all|N,N,...] "
                           "[--targets a,b] [--rigs forward,orbit] [--segmenters grabcut,oracle,oracle-sam,oracle-sam-nodrift,isnet,exact] "
                           "[--methods vcar:paper,vcar:robust,vcar:code,vcar:lean,naive,sagd,flashsplat,gaussiancut,ludvig,lbg] "
                           "[--width W --height H] [--set key=value]... (vcar:robust only) "
                           "[--sam key=value]... (oracle-sam's levels: p_wrong, p_part, p_leak, leak_px, drift_px) "
                           "[--isnet CMD] (the isnet segmenter's program)\n", argv[0]);
      return a == "--help" || a == "-h" ? 0 : 2;
    }
  }
  if ((o.width > 0) != (o.height > 0)) { std::fprintf(stderr, "bench_field: give both --width and --height\n"); return 2; }
  if (o.coarse_only && o.mask_folder) { std::fprintf(stderr, "bench_field: --coarse-only and --mask-folder exclude each other\n"); return 2; }
  try {
    const auto t0 = Clock::now();
    const std::vector<int> seeds = o.quick && o.seeds == "all" ? std::vector<int>{kTuningSeeds.front()} : parse_seeds(o.seeds);
    const std::vector<Cell> cells = plan_cells(o);
    Driver d(o);
    const std::vector<std::string> targets = d.targets();
    std::size_t runs = 0;
    for (int seed : seeds)
      for (const Cell& c : cells)
        if (!c.heldout_only || role_of(seed) == "heldout") runs += c.methods.size() * targets.size();
    std::fprintf(stderr, "bench_field: %s, %zu seeds x %zu targets, %zu cells, %zu runs planned at %dx%d, %d threads -> %s\n",
                 o.quick ? "quick" : "full", seeds.size(), targets.size(), cells.size(), runs, d.width(), d.height(),
                 max_threads(), o.out.string().c_str());
    if (!o.set.empty())  // easy to miss: the paper preset's rows keep the paper's values
      std::fprintf(stderr, "bench_field: --set applies to the vcar:robust runs only (vcar:paper: nvos or lerf as published)\n");
    d.open();
    for (int seed : seeds)
      for (const std::string& t : targets) {
        std::fprintf(stderr, "[seed %d, %s] %.0fs\n", seed, t.c_str(), since(t0));
        d.run(seed, t, cells);
      }
    d.write_summary(since(t0), seeds, cells);
    std::printf("bench_field: %zu runs in %.1f s, CSV %s\n", d.runs(), since(t0), (o.out / "field.csv").string().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_field: %s\n", e.what());
    return 1;
  }
  return 0;
}
