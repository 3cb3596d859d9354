#pragma once
// Shared pieces of the `vcar` program: exit codes, the terminal progress line, Ctrl-C and small
// parsers. Every error names the file, view or parameter at fault.
#include <atomic>
#include <chrono>
#include <string_view>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vcar/io/external_segmenter.hpp"
#include "vcar/io/selection_file.hpp"
#include "vcar/io/selection_identity.hpp"
#include "vcar/algo/params.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"

namespace vcar::cli {

// Exit codes (docs/cli.md). CLI11 reports usage errors itself with 1... see main.cpp.
enum ExitCode : int {
  exit_ok = 0,
  exit_usage = 1,          // bad command line (unknown flag, missing value, conflicting options)
  exit_bad_input = 2,      // a file, view or parameter is wrong (the message names it)
  exit_segmenter = 3,      // the external segmenter failed, timed out or wrote a bad mask
  exit_cancelled = 4,      // interrupted (Ctrl-C / SIGTERM)
  exit_output = 5,         // an output could not be written
  exit_internal = 70,      // a bug or resource exhaustion (out of memory)
};

// An error with its exit code decided where it is raised.
struct CliError : Error {
  int code;
  CliError(int c, const std::string& message, const std::string& where = {})
      : Error(message, where), code(c) {}
};

// Set by SIGINT/SIGTERM; the pipeline's progress callback and the external segmenter poll it.
std::atomic<bool>& interrupted();
void install_signal_handlers();

// One status line on a terminal (stderr is a tty), nothing otherwise. Within a round it shows
// the view (i of n), the time since the command started and an estimate of what the round
// still needs (from the views done so far); while an external segmenter works, the frame being
// rendered for it or the masks it has written.
class ProgressLine {
public:
  explicit ProgressLine(bool quiet);
  ~ProgressLine();
  // The pipeline callback: prints, and returns false once interrupted (cancels the pipeline).
  bool operator()(const Progress& p);
  void external(const io::ExternalProgress& p);  // ExternalSegmenterOptions::progress
  void message(const std::string& line);  // a stage outside the pipeline ("reading scene")
  void done();                            // clears the line
  bool active() const { return active_; }
  ProgressCallback callback() { return [this](const Progress& p) { return (*this)(p); }; }
  // The text of the line for `p`, without terminal codes (tested; `eta_s` < 0: unknown).
  static std::string format(std::string_view stage, std::size_t done, std::size_t total, const char* unit,
                            double elapsed_s, double eta_s);

private:
  void print(const std::string& text);
  bool active_ = false, dirty_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::string stage_;  // the round the estimate is for
  double stage_start_s_ = 0;
};

// ---- files ---------------------------------------------------------------------------------
nlohmann::json read_json(const std::filesystem::path& file);
// Atomic write of a JSON document (indent 1), exit_output on failure.
void write_json(const std::filesystem::path& file, const nlohmann::json& j);
// Creates the output directory (and parents); exit_output naming it on failure.
void make_output_dir(const std::filesystem::path& dir);

// The output directory of a command that may fail: created (with its parents) by the
// constructor; unless commit() is called, the destructor removes what the failed run left empty:
// DIR/requests, then DIR and the parents it created. Files are never removed.
class OutputDir {
public:
  explicit OutputDir(std::filesystem::path dir);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;
  void commit() { committed_ = true; }
  const std::filesystem::path& path() const { return dir_; }

private:
  std::filesystem::path dir_;
  std::vector<std::filesystem::path> created_;  // outermost first
  bool committed_ = false;
};

// selection.json and state PLYs as selections: io/selection_file.hpp.
using io::ObjectSelection;
using io::read_object_selections;
using io::read_selection;
using io::Selection;
using io::selection_json;

// ---- parsing -------------------------------------------------------------------------------
// "u,v;u,v,0": points, label 1 unless a third value says 0 (negative). Errors name `where`.
void parse_points(const std::string& text, Prompt& prompt, const std::string& where = "--points");
// "x0,y0,x1,y1".
Eigen::Vector4f parse_box(const std::string& text, const std::string& where = "--box");
// "r,g,b" in [0,1].
Eigen::Vector3f parse_rgb(const std::string& text, const std::string& where);
// Index of the camera named `name`; the error lists some of the names that exist.
std::size_t find_view(const std::vector<Camera>& cams, const std::string& name, const std::string& where);
// The parameters of a preset, then each "key=value" (errors name the key).
VcarParams make_params(const std::string& preset, const std::vector<std::string>& sets);
nlohmann::json params_json(const VcarParams& p);

double peak_rss_mib();

// The summary `segment` and `demo` print: one line each for the counts (selected / coarse /
// fine), the view gap and whether SSS ran, ABR, missing masks (when `masks` is given: training
// and sampled views, last round), time and peak memory. `mask_source_folder` adds the advice
// for the fine round a mask folder cannot answer (mask_folder_advice) when SSS ran.
struct MaskCounts {
  std::size_t training = 0, training_missing = 0, sampled = 0, sampled_missing = 0;
};
std::string summary_text(const Diagnostics& d, const VcarParams& p, std::size_t scene_size,
                         const MaskCounts* masks, double seconds, bool mask_source_folder);
nlohmann::json mask_counts_json(const MaskCounts& m);
// The advice `segment` and `segment-objects` print when SSS ran on a mask folder's masks.
// (The library's own note already says that the fine round had no mask.)
inline constexpr const char* mask_folder_advice =
    "note: a mask folder holds masks of the captures only; use --segmenter-cmd to segment the fine round's "
    "renders of G_coarse\n";

// ---- outputs shared by `segment` and `demo` -------------------------------------------------
// Writes object.ply, removed.ply, selection.json and report.json into `out`, and returns the
// report (the caller may add keys, e.g. metrics, and write it again).
nlohmann::json write_segmentation(const std::filesystem::path& out, const GaussianScene& scene,
                                  const SegmentationResult& r, const VcarParams& params,
                                  const nlohmann::json& inputs);

}  // namespace vcar::cli
