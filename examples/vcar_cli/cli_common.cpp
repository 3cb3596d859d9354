#include "cli_common.hpp"

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <type_traits>

#include "vcar/core/parallel.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/diagnostics_json.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/params_text.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/selection_identity.hpp"
#include "vcar/io/state_ply.hpp"

namespace vcar::cli {

std::atomic<bool>& interrupted() {
  static std::atomic<bool> flag{false};
  return flag;
}

namespace {
extern "C" void on_signal(int sig) {
  interrupted().store(true);
  ::signal(sig, SIG_DFL);  // a second Ctrl-C ends the program at once
}
}  // namespace

void install_signal_handlers() {
  ::signal(SIGINT, on_signal);
  ::signal(SIGTERM, on_signal);
}

// ---- progress ------------------------------------------------------------------------------
ProgressLine::ProgressLine(bool quiet) : active_(!quiet && ::isatty(STDERR_FILENO)) {}
ProgressLine::~ProgressLine() { done(); }

std::string ProgressLine::format(std::string_view stage, std::size_t done, std::size_t total, const char* unit,
                                 double elapsed_s, double eta_s) {
  char buf[200];
  int n = std::snprintf(buf, sizeof buf, "%-.*s", static_cast<int>(stage.size()), stage.data());
  if (total > 0) n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), ": %s %zu/%zu", unit, done, total);
  n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), "  %.1f s", elapsed_s);
  if (eta_s >= 0) std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), ", ~%.0f s left", eta_s);
  return buf;
}

void ProgressLine::print(const std::string& text) {
  std::fprintf(stderr, "\r\033[K[vcar] %s", text.c_str());
  std::fflush(stderr);
  dirty_ = true;
}

bool ProgressLine::operator()(const Progress& p) {
  if (active_) {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (p.stage != stage_) {
      stage_ = std::string(p.stage);
      stage_start_s_ = now;
    }
    double eta = -1;
    if (p.views > 0 && p.view > 0) eta = (now - stage_start_s_) / static_cast<double>(p.view) * static_cast<double>(p.views - p.view);
    print(format(p.stage, p.view, p.views, "view", now, eta));
  }
  return !interrupted().load();
}

void ProgressLine::external(const io::ExternalProgress& p) {
  if (!active_) return;
  const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::string stage = "segmenter round " + std::to_string(p.round) +
                            (p.phase == io::ExternalProgress::Phase::rendering ? ", rendering" : ", running");
  double eta = -1;
  if (p.done > 0) eta = p.elapsed_s / static_cast<double>(p.done) * static_cast<double>(p.frames - std::min(p.done, p.frames));
  print(format(stage, p.phase == io::ExternalProgress::Phase::rendering ? p.done + 1 : p.done, p.frames,
               p.phase == io::ExternalProgress::Phase::rendering ? "frame" : "masks written", now, eta));
}

void ProgressLine::message(const std::string& line) {
  if (active_) print(line);
}

void ProgressLine::done() {
  if (active_ && dirty_) {
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
  }
  dirty_ = false;
}

// ---- files ---------------------------------------------------------------------------------
nlohmann::json read_json(const std::filesystem::path& file) {
  try {
    return io::read_json_file(file);
  } catch (const Error& e) {
    throw CliError(exit_bad_input, e.what());
  }
}

void write_json(const std::filesystem::path& file, const nlohmann::json& j) {
  try {
    io::write_json_file(file, j);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
}

void make_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw CliError(exit_output, "cannot create the output directory" + (ec ? ": " + ec.message() : ""),
                   dir.string());
}

OutputDir::OutputDir(std::filesystem::path dir) : dir_(std::move(dir)) {
  std::error_code ec;
  for (std::filesystem::path p = std::filesystem::absolute(dir_, ec); !p.empty() && !std::filesystem::exists(p, ec);
       p = p.parent_path()) {
    created_.insert(created_.begin(), p);
    if (p == p.parent_path()) break;
  }
  make_output_dir(dir_);
}

OutputDir::~OutputDir() {
  if (committed_) return;
  std::error_code ec;
  std::filesystem::remove(dir_ / "requests", ec);  // only when empty
  for (auto it = created_.rbegin(); it != created_.rend(); ++it)
    if (!std::filesystem::remove(*it, ec)) break;  // only empty directories; stop at the first that is not
}

// ---- parsing -------------------------------------------------------------------------------
namespace {
std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) out.push_back(cur);
  if (!s.empty() && s.back() == sep) out.emplace_back();
  return out;
}
float parse_float(std::string s, const std::string& where) {
  s.erase(0, s.find_first_not_of(" \t"));
  s.erase(s.find_last_not_of(" \t") + 1);
  errno = 0;
  char* end = nullptr;
  const float v = std::strtof(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno != 0 || !std::isfinite(v))
    throw CliError(exit_usage, "expected a number, got '" + s + "'", where);
  return v;
}
}  // namespace

void parse_points(const std::string& text, Prompt& prompt, const std::string& where) {
  for (const std::string& item : split(text, ';')) {
    if (item.find_first_not_of(" \t") == std::string::npos) continue;
    const auto f = split(item, ',');
    if (f.size() != 2 && f.size() != 3)
      throw CliError(exit_usage, "expected u,v or u,v,label; got '" + item + "'", where);
    prompt.points.emplace_back(parse_float(f[0], where), parse_float(f[1], where));
    int label = 1;
    if (f.size() == 3) {
      const float l = parse_float(f[2], where);
      if (l != 0.f && l != 1.f) throw CliError(exit_usage, "label must be 1 or 0, got '" + f[2] + "'", where);
      label = static_cast<int>(l);
    }
    prompt.point_labels.push_back(label);
  }
  if (prompt.points.empty()) throw CliError(exit_usage, "no point given", where);
}

Eigen::Vector4f parse_box(const std::string& text, const std::string& where) {
  const auto f = split(text, ',');
  if (f.size() != 4) throw CliError(exit_usage, "expected x0,y0,x1,y1; got '" + text + "'", where);
  Eigen::Vector4f b;
  for (int k = 0; k < 4; ++k) b[k] = parse_float(f[k], where);
  if (!(b[2] > b[0] && b[3] > b[1])) throw CliError(exit_usage, "box must have x1 > x0 and y1 > y0", where);
  return b;
}

Eigen::Vector3f parse_rgb(const std::string& text, const std::string& where) {
  const auto f = split(text, ',');
  if (f.size() != 3) throw CliError(exit_usage, "expected r,g,b; got '" + text + "'", where);
  Eigen::Vector3f c;
  for (int k = 0; k < 3; ++k) {
    c[k] = parse_float(f[k], where);
    if (!(c[k] >= 0.f && c[k] <= 1.f)) throw CliError(exit_usage, "colour channels must be in [0, 1]", where);
  }
  return c;
}

std::size_t find_view(const std::vector<Camera>& cams, const std::string& name, const std::string& where) {
  for (std::size_t k = 0; k < cams.size(); ++k)
    if (cams[k].name == name) return k;
  // Also accept the name without its extension ("frame_001" for "frame_001.png") and vice versa.
  auto stem = [](const std::string& s) { return std::filesystem::path(s).stem().string(); };
  for (std::size_t k = 0; k < cams.size(); ++k)
    if (stem(cams[k].name) == stem(name)) return k;
  std::string names;
  for (std::size_t k = 0; k < cams.size() && k < 6; ++k) names += (k ? ", " : "") + cams[k].name;
  if (cams.size() > 6) names += ", ... (" + std::to_string(cams.size()) + " views)";
  throw CliError(exit_bad_input, "no view named '" + name + "'; views: " + names, where);
}

VcarParams make_params(const std::string& preset, const std::vector<std::string>& sets) {
  VcarParams p;
  try {
    p = VcarParams::preset(preset);
  } catch (const Error&) {
    throw CliError(exit_usage, "unknown preset '" + preset + "'; valid: robust, nvos, lerf, reference_code", "--preset");
  }
  for (const std::string& s : sets) io::set_parameter(p, s);  // vcar::Error naming the key -> exit 2
  p.validate();
  return p;
}

nlohmann::json params_json(const VcarParams& p) { return io::params_json(p); }

double peak_rss_mib() {
  rusage ru{};
  ::getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;  // Linux: KiB
}

std::string summary_text(const Diagnostics& d, const VcarParams& p, std::size_t scene_size,
                         const MaskCounts* masks, double seconds, bool mask_source_folder) {
  std::string s;
  char buf[512];
  std::snprintf(buf, sizeof buf, "selected  %zu of %zu Gaussians   (coarse %zu -> fine %zu -> final %zu)\n",
                d.n_final, scene_size, d.n_coarse, d.n_fine, d.n_final);
  s += buf;
  if (!p.enable_sss)
    std::snprintf(buf, sizeof buf, "views     SSS off (enable_sss=false)\n");
  else if (d.n_coarse == 0)
    std::snprintf(buf, sizeof buf, "views     SSS not reached (the coarse vote selected nothing)\n");
  else if (d.sss_triggered)
    std::snprintf(buf, sizeof buf, "views     %zu valid cameras, largest gap %.1f deg %s %.0f: SSS ran (%zu sampled views)\n",
                  d.valid_cameras, d.max_gap_deg, d.max_gap_deg > p.Delta_th_deg ? ">" : "<=",
                  static_cast<double>(p.Delta_th_deg), d.sampled_cameras.size());
  else
    std::snprintf(buf, sizeof buf, "views     %zu valid cameras, largest gap %.1f deg <= %.0f: SSS not needed\n",
                  d.valid_cameras, d.max_gap_deg, static_cast<double>(p.Delta_th_deg));
  s += buf;
  if (!p.enable_abr) std::snprintf(buf, sizeof buf, "ABR       off (enable_abr=false)\n");
  else std::snprintf(buf, sizeof buf, "ABR       %zu Gaussians flagged, %zu compressed\n", d.abr_flagged, d.abr_compressed);
  s += buf;
  if (d.tau_fine_applied > 0.f && (p.strict.tau > p.tau_fine || p.valley.enabled)) {  // Eq. R7 or R14 (and R8) ran
    std::snprintf(buf, sizeof buf, "fine vote %s: tau %.2f", d.fine_split ? "split" : "decisive",
                  static_cast<double>(d.tau_fine_applied));
    s += buf;
    if (d.undershoot_applied) s += ", undershoot band on (Eq. R6)";
    if (d.abr_masks_widened > 0) {
      std::snprintf(buf, sizeof buf, ", %zu training masks widened by their undershoot for ABR", d.abr_masks_widened);
      s += buf;
    }
    s += "\n";
  }
  if (d.overshoot_eroded > 0) {  // Eq. R11 ran
    std::snprintf(buf, sizeof buf, "overshoot %zu masks eroded: their contours lay outside the render's edges (Eq. R11)\n",
                  d.overshoot_eroded);
    s += buf;
  }
  if (d.masks_grown > 0) {  // Eq. R12 ran
    std::snprintf(buf, sizeof buf, "undershoot %zu masks grown to the render's occlusion edges (Eq. R12)\n", d.masks_grown);
    s += buf;
  }
  if (masks) {
    std::snprintf(buf, sizeof buf, "masks     %zu of %zu training views missing", masks->training_missing, masks->training);
    s += buf;
    if (masks->sampled) {
      std::snprintf(buf, sizeof buf, ", %zu of %zu sampled views missing", masks->sampled_missing, masks->sampled);
      s += buf;
    }
    s += "\n";
    if (mask_source_folder && d.sss_triggered) s += mask_folder_advice;
  }
  std::snprintf(buf, sizeof buf, "time      %.1f s on %d threads, peak memory %.0f MiB\n", seconds, max_threads(), peak_rss_mib());
  s += buf;
  if (!d.note.empty()) s += "note: " + d.note + "\n";
  return s;
}

nlohmann::json mask_counts_json(const MaskCounts& m) {
  return {{"training_views", m.training}, {"training_missing", m.training_missing},
          {"sampled_views", m.sampled}, {"sampled_missing", m.sampled_missing}};
}

nlohmann::json write_segmentation(const std::filesystem::path& out, const GaussianScene& scene,
                                  const SegmentationResult& r, const VcarParams& params,
                                  const nlohmann::json& inputs) {
  const Diagnostics& d = r.diagnostics;
  // The rest of the scene: every index not selected, ascending.
  std::vector<Index> rest;
  rest.reserve(scene.size() - r.indices.size());
  for (std::size_t i = 0, k = 0; i < scene.size(); ++i) {
    if (k < r.indices.size() && r.indices[k] == i) { ++k; continue; }
    rest.push_back(static_cast<Index>(i));
  }
  try {
    io::write_ply(out / "object.ply", scene, r.indices, r.log_scale[0].empty() ? nullptr : &r.log_scale);
    io::write_ply(out / "removed.ply", scene, rest);
  } catch (const Error& e) {
    throw CliError(exit_output, e.what());
  }
  Selection sel;
  sel.indices = r.indices;
  sel.scores = r.scores;
  sel.log_scale = r.log_scale;
  sel.scene_gaussians = scene.size();
  sel.identity = io::selection_identity(io::gaussian_identities(scene), r.indices);
  write_json(out / "selection.json", selection_json(sel));

  nlohmann::json report = io::diagnostics_json(d);  // counts, view completeness, ABR, rules, timings
  report["inputs"] = inputs;
  report["parameters"] = params_json(params);
  report["counts"]["removed"] = rest.size();
  report["threads"] = max_threads();
  report["peak_rss_mib"] = peak_rss_mib();
  report["outputs"] = {{"object", "object.ply"}, {"removed", "removed.ply"}, {"selection", "selection.json"}};
  write_json(out / "report.json", report);
  return report;
}

}  // namespace vcar::cli
