#pragma once
// ExternalSegmenter: a vcar::Segmenter that runs an external program once per segmentation
// round (SAM 2 in video mode, a colour picker, anything that writes PNG masks).
//
// The protocol (docs/cli.md):
//  - the command line is split like a shell would split it (quotes and backslashes honoured, no
//    expansion, no shell involved) and a fresh request directory is appended as last argument;
//  - the request directory holds
//      frames/00000.png ...  8-bit RGB, frame 0 = the reference view of the prompt;
//      cameras.json          Inria layout, one entry per frame in frame order, img_name = the
//                            frame file stem ("00000"), plus "view" (the camera's own name) and
//                            "cx", "cy" (the Inria layout assumes a centred principal point);
//      prompt.json           {"points": [[u, v], ...], "point_labels": [1, 0, ...],
//                             "box": [x0, y0, x1, y1] or null, "text": "...",
//                             "round": r, "frames": n}, and with ExternalSegmenterOptions::boxes
//                            "boxes": [[x0, y0, x1, y1] or null, ...], one per frame in frame
//                            order, pixels of that frame (the prompt lifted to 3D and boxed in
//                            each frame: vcar::lift_prompt, LiftedPrompt::box_for);
//  - the program writes masks/00000.png ... (8-bit, any channel count, foreground >= 128 as
//    io::read_mask reads it; a missing file means "no mask" for that frame) and exits with
//    status 0.
// A non-zero exit, a timeout, a mask that cannot be decoded or has the wrong size is an error
// naming the round and the frame; `failure()` then says which, so a program can map it to an
// exit code. The request directory is removed after a successful round and kept after a
// failed one (its path is in the message), unless options say otherwise.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "vcar/concepts/multi_segmenter.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/error.hpp"
#include "vcar/core/image.hpp"
#include "vcar/io/image_file.hpp"

extern char** environ;

namespace vcar::io {

// Splits a command line into words like a POSIX shell (without any expansion): blanks separate
// words; '...' is literal; "..." is literal except \" \\ \$ \` and a backslash-newline; outside
// quotes a backslash escapes the next character. Throws vcar::Error naming `where` for an
// unterminated quote or a trailing backslash.
inline std::vector<std::string> split_command_line(const std::string& line,
                                                   const std::string& where = "command") {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == ' ' || c == '\t' || c == '\n') {
      if (in_word) words.push_back(std::move(word));
      word.clear();
      in_word = false;
    } else if (c == '\'') {
      const std::size_t end = line.find('\'', i + 1);
      if (end == std::string::npos) throw Error("unterminated single quote", where);
      word.append(line, i + 1, end - i - 1);
      i = end;
      in_word = true;
    } else if (c == '"') {
      std::size_t j = i + 1;
      for (; j < line.size() && line[j] != '"'; ++j) {
        if (line[j] == '\\' && j + 1 < line.size() &&
            (line[j + 1] == '"' || line[j + 1] == '\\' || line[j + 1] == '$' || line[j + 1] == '`' ||
             line[j + 1] == '\n')) {
          if (line[j + 1] != '\n') word.push_back(line[j + 1]);
          ++j;
        } else {
          word.push_back(line[j]);
        }
      }
      if (j >= line.size()) throw Error("unterminated double quote", where);
      i = j;
      in_word = true;
    } else if (c == '\\') {
      if (i + 1 >= line.size()) throw Error("trailing backslash", where);
      if (line[i + 1] != '\n') { word.push_back(line[i + 1]); in_word = true; }
      ++i;
    } else {
      word.push_back(c);
      in_word = true;
    }
  }
  if (in_word) words.push_back(std::move(word));
  return words;
}

// What the progress callback sees while a round is under way: the frames being rendered into
// the request (frame i of n), then the program running (masks it has written so far).
struct ExternalProgress {
  enum class Phase { rendering, running } phase = Phase::rendering;
  std::size_t round = 0;          // 1-based
  std::size_t done = 0;           // frames rendered / masks written so far
  std::size_t frames = 0;         // frames of the round
  double elapsed_s = 0;           // since the phase began
};

struct ExternalSegmenterOptions {
  double timeout_s = 3600;               // per round; the program is killed after it
  std::filesystem::path work_dir;        // where request directories go ("" = system temp)
  bool keep_requests = false;            // keep request directories after successful rounds
  bool keep_failed_requests = true;      // keep the request directory of a failed round
  bool inherit_output = false;           // child's stdout/stderr: ours (true) or a log file
  std::function<bool()> cancelled;       // polled while the program runs; true kills it
  // Called before each frame is rendered and about every 0.25 s while the program runs.
  std::function<void(const ExternalProgress&)> progress;
  // The prompt's box on frame k of a round (its camera given), nullopt where the object is out
  // of view: prompt.json's "boxes" (one-object rounds only). Unset: no "boxes". A caller that
  // lifted the prompt: [lifted](std::size_t, const Camera& c) { return lifted.box_for(c); }.
  std::function<std::optional<Eigen::Vector4f>(std::size_t frame, const Camera&)> boxes;
};

namespace detail {

// The camera entry of cameras.json (Inria layout: camera-to-world rotation rows, centre).
inline nlohmann::json request_camera_json(const Camera& c, std::size_t id, const std::string& img_name) {
  const Eigen::Matrix3f R_c2w = c.R_w.transpose();
  const Eigen::Vector3f pos = c.position();
  nlohmann::json rot = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rot.push_back({R_c2w(r, 0), R_c2w(r, 1), R_c2w(r, 2)});
  return {{"id", id}, {"img_name", img_name}, {"width", c.width}, {"height", c.height},
          {"position", {pos.x(), pos.y(), pos.z()}}, {"rotation", rot},
          {"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"view", c.name}};
}

// prompt.json's prompt fields.
inline nlohmann::json request_prompt_json(const Prompt& prompt) {
  nlohmann::json pts = nlohmann::json::array();
  for (const auto& p : prompt.points) pts.push_back({p.x(), p.y()});
  nlohmann::json p = {{"points", pts}, {"point_labels", prompt.point_labels}, {"box", nullptr}, {"text", prompt.text}};
  if (prompt.box) p["box"] = {(*prompt.box)[0], (*prompt.box)[1], (*prompt.box)[2], (*prompt.box)[3]};
  return p;
}

// The last lines of the program's log, for error messages.
inline std::string program_log_tail(const std::filesystem::path& log, std::size_t max_chars = 1500) {
  std::ifstream in(log, std::ios::binary);
  if (!in) return {};
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s.empty() ? std::string{} : "\n--- segmenter output (tail) ---\n" + s;
}

// Masks the program has finished so far: masks/NNNNN.png (a file being written under another
// name, e.g. NNNNN.png.part.png, does not count).
inline std::size_t masks_written(const std::filesystem::path& dir, int depth = 0) {
  std::size_t n = 0;
  std::error_code ec;
  const std::filesystem::path d = depth == 0 ? dir / "masks" : dir;
  for (const auto& e : std::filesystem::directory_iterator(d, ec)) {
    if (depth == 0 && e.is_directory(ec)) {
      n += masks_written(e.path(), 1);  // masks/<object>/ of a multi-object request
      continue;
    }
    const std::string f = e.path().filename().string();
    n += f.size() == 9 && f.compare(5, 4, ".png") == 0 && f.find_first_not_of("0123456789") == 5;
  }
  return n;
}

// Ends the program's process group: SIGTERM, up to 2 s, then SIGKILL.
inline void kill_process_group(pid_t pid) {
  ::kill(-pid, SIGTERM);
  int status = 0;
  for (int i = 0; i < 100; ++i) {  // up to 2 s to exit cleanly, then SIGKILL
    if (::waitpid(pid, &status, WNOHANG) == pid) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid, SIGKILL);
  ::waitpid(pid, &status, 0);
}

}  // namespace detail

class ExternalSegmenter {
public:
  enum class Failure { none, start, exit_status, timeout, bad_mask, cancelled };

  explicit ExternalSegmenter(std::string command, ExternalSegmenterOptions options = {})
      : command_(std::move(command)), options_(std::move(options)) {
    argv_ = split_command_line(command_, "segmenter command");
    if (argv_.empty()) throw Error("empty command", "segmenter command");
    if (!(options_.timeout_s > 0)) throw Error("must be positive", "segmenter timeout");
  }

  // One segmentation round (see the protocol above).
  void segment(const FrameSequence& frames, const Prompt& prompt, const MaskSink& sink) {
    run_round(frames, {{std::string(), prompt, 0, frames.size()}}, false,
              [&](std::size_t k, std::size_t, const Mask* m) { sink(k, m); });
  }

  // One round for several objects at once (`vcar segment --prompts`): prompt.json gets
  // "objects": [{"name", "frame" (the frame its prompt is on), "frames": [first, count] (the
  // frames it is asked about: first .. first + count - 1), "points", "point_labels", "box",
  // "text"}, ...] (the top-level prompt fields are the first object's), and the program writes
  // masks/<name>/00000.png ... for the frames of each object's range (other files are not
  // read); `sink(frame, object, mask)` in frame order, objects inner, each object only within
  // its range. A shared round (every object on every frame: the coarse round's renders of the
  // whole scene) gives every object all frames; a batched round (each object's own frames one
  // after the other: the fine rounds' renders of each object's G_coarse) gives each its part.
  // Object names must be usable as folder names ([A-Za-z0-9_.-], not "." or "..").
  // A model of MultiSegmenter (concepts/multi_segmenter.hpp): segment_objects(vcar's
  // ObjectRequests).
  using Object = ObjectRequest;
  static constexpr std::size_t all_frames = ObjectRequest::all_frames;
  void segment_objects(const FrameSequence& frames, std::vector<Object> objects, const ObjectMaskSink& sink) {
    if (objects.empty()) throw Error("no object to segment", "segmenter");
    for (Object& o : objects) {
      if (o.name.empty() || o.name == "." || o.name == ".." ||
          o.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.-") != std::string::npos)
        throw Error("object name '" + o.name + "' is not a folder name ([A-Za-z0-9_.-])", "segmenter");
      if (o.first_frame > frames.size()) throw Error("object '" + o.name + "': first frame out of range", "segmenter");
      if (o.frames == all_frames) o.frames = frames.size() - o.first_frame;
      if (o.frames > frames.size() - o.first_frame) throw Error("object '" + o.name + "': frames out of range", "segmenter");
      if (o.prompt.reference_view < o.first_frame || o.prompt.reference_view >= o.first_frame + o.frames)
        throw Error("object '" + o.name + "': prompt frame outside its frames", "segmenter");
    }
    run_round(frames, objects, true, sink);
  }

private:
  void run_round(const FrameSequence& frames, const std::vector<Object>& objects, bool multi,
                 const ObjectMaskSink& sink) {
    const Prompt& prompt = objects.front().prompt;
    ++round_;
    failure_ = Failure::none;
    const std::string where_round = "segmenter round " + std::to_string(round_);
    const std::filesystem::path dir = make_request_dir(where_round);
    last_request_dir_ = dir;
    bool ok = false;
    struct Cleanup {  // removes the request directory unless asked to keep it
      const std::filesystem::path& dir; const ExternalSegmenterOptions& o; bool& ok;
      ~Cleanup() {
        if ((ok && !o.keep_requests) || (!ok && !o.keep_failed_requests)) {
          std::error_code ec;
          std::filesystem::remove_all(dir, ec);
        }
      }
    } cleanup{dir, options_, ok};

    write_request(dir, frames, prompt, where_round, multi ? &objects : nullptr);
    std::size_t expected = 0;  // masks the program should write
    for (const Object& o : objects) expected += o.frames;
    run_program(dir, where_round, expected);
    // Each mask is decoded and checked before it goes to the sink, so a bad file fails the round
    // with its name.
    const std::size_t n = frames.size();
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t o = 0; o < objects.size(); ++o) {
        if (k < objects[o].first_frame || k - objects[o].first_frame >= objects[o].frames) continue;
        const std::filesystem::path file =
            multi ? dir / "masks" / objects[o].name / (frame_stem(k) + ".png") : dir / "masks" / (frame_stem(k) + ".png");
        const std::string where = where_round + ", frame " + std::to_string(k) + " (view '" +
                                  frames.cameras[k].name + "'" + (multi ? ", object '" + objects[o].name + "'" : "") +
                                  ", " + file.string() + ")";
        std::error_code ec;
        if (!std::filesystem::exists(file, ec)) {
          sink(k, o, nullptr);  // no file: no mask for this frame
          continue;
        }
        Mask m = read_mask_png(file, where);
        const Camera& cam = frames.cameras[k];
        if (m.width != cam.width || m.height != cam.height) {
          failure_ = Failure::bad_mask;
          throw Error("mask is " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                          ", the frame is " + std::to_string(cam.width) + "x" +
                          std::to_string(cam.height) + "; request kept in " + dir.string(), where);
        }
        sink(k, o, &m);
      }
    }
    ok = true;
  }

public:

  // Sets ExternalSegmenterOptions::boxes (e.g. once the scene is read and the prompt lifted).
  void set_boxes(std::function<std::optional<Eigen::Vector4f>(std::size_t, const Camera&)> boxes) {
    options_.boxes = std::move(boxes);
  }

  std::size_t rounds() const noexcept { return round_; }
  Failure failure() const noexcept { return failure_; }
  const std::vector<std::string>& argv() const noexcept { return argv_; }
  const std::filesystem::path& last_request_dir() const noexcept { return last_request_dir_; }

  static std::string frame_stem(std::size_t k) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%05zu", k);
    return buf;
  }


private:
  std::filesystem::path make_request_dir(const std::string& where) {
    std::error_code ec;
    std::filesystem::path base = options_.work_dir.empty()
                                     ? std::filesystem::temp_directory_path(ec)
                                     : options_.work_dir;
    std::filesystem::create_directories(base, ec);
    std::string templ = (base / ("vcar-request-" + std::to_string(round_) + "-XXXXXX")).string();
    if (!::mkdtemp(templ.data())) {
      failure_ = Failure::start;
      throw Error(std::string("cannot create a request directory: ") + std::strerror(errno),
                  where + ", " + base.string());
    }
    return templ;
  }


  void write_request(const std::filesystem::path& dir, const FrameSequence& frames,
                     const Prompt& prompt, const std::string& where,
                     const std::vector<Object>* objects = nullptr) {
    std::filesystem::create_directories(dir / "frames");
    std::filesystem::create_directories(dir / "masks");
    if (objects)
      for (const Object& o : *objects) std::filesystem::create_directories(dir / "masks" / o.name);
    nlohmann::json cams = nlohmann::json::array();
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t k = 0; k < frames.size(); ++k) {
      if (options_.progress)
        options_.progress({ExternalProgress::Phase::rendering, round_, k, frames.size(),
                           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()});
      const std::string stem = frame_stem(k);
      const ImageRGB8 img = frames.image(k);
      const std::filesystem::path file = dir / "frames" / (stem + ".png");
      try {
        write_png(file, img);
      } catch (const Error& e) {
        failure_ = Failure::start;
        throw Error(std::string("cannot write a frame: ") + e.what(), where);
      }
      cams.push_back(detail::request_camera_json(frames.cameras[k], k, stem));
    }
    nlohmann::json p = detail::request_prompt_json(prompt);
    p["round"] = round_;
    p["frames"] = frames.size();
    if (options_.boxes && !objects) {
      nlohmann::json boxes = nlohmann::json::array();
      for (std::size_t k = 0; k < frames.size(); ++k) {
        const std::optional<Eigen::Vector4f> b = options_.boxes(k, frames.cameras[k]);
        boxes.push_back(b ? nlohmann::json{(*b)[0], (*b)[1], (*b)[2], (*b)[3]} : nlohmann::json(nullptr));
      }
      p["boxes"] = std::move(boxes);
    }
    if (objects) {
      nlohmann::json list = nlohmann::json::array();
      for (const Object& o : *objects) {
        nlohmann::json e = detail::request_prompt_json(o.prompt);
        e["name"] = o.name;
        e["frame"] = o.prompt.reference_view;
        e["frames"] = {o.first_frame, o.frames};
        list.push_back(std::move(e));
      }
      p["objects"] = std::move(list);
    }
    write_text(dir / "cameras.json", cams.dump(1), where);
    write_text(dir / "prompt.json", p.dump(1), where);
  }

  void write_text(const std::filesystem::path& file, const std::string& text, const std::string& where) {
    std::ofstream out(file, std::ios::binary);
    out << text << '\n';
    if (!out) {
      failure_ = Failure::start;
      throw Error("cannot write request file", where + ", " + file.string());
    }
  }



  void run_program(const std::filesystem::path& dir, const std::string& where, std::size_t frames) {
    std::vector<std::string> args = argv_;
    args.push_back(dir.string());
    std::vector<char*> cargv;
    for (auto& a : args) cargv.push_back(a.data());
    cargv.push_back(nullptr);

    const std::filesystem::path log = dir / "segmenter.log";
    posix_spawn_file_actions_t fa;
    posix_spawnattr_t attr;
    posix_spawn_file_actions_init(&fa);
    posix_spawnattr_init(&attr);
    if (!options_.inherit_output) {
      posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      posix_spawn_file_actions_adddup2(&fa, 1, 2);
    }
    // Own process group: a timeout or cancel kills the program and whatever it started.
    posix_spawnattr_setpgroup(&attr, 0);
    short flags = POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF;
    sigset_t none, defaults;
    sigemptyset(&none);
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    sigaddset(&defaults, SIGPIPE);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setflags(&attr, flags);
    pid_t pid = -1;
    const int rc = posix_spawnp(&pid, cargv[0], &fa, &attr, cargv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&attr);
    const std::string cmd_where = where + " ('" + argv_[0] + "')";
    if (rc != 0) {
      failure_ = Failure::start;
      throw Error(std::string("cannot start the segmenter program: ") + std::strerror(rc), cmd_where);
    }

    const auto t0 = std::chrono::steady_clock::now();
    int status = 0;
    auto sleep = std::chrono::milliseconds(2);
    double next_tick = 0;
    for (;;) {
      const pid_t w = ::waitpid(pid, &status, WNOHANG);
      if (w == pid) break;
      if (options_.progress) {
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (t >= next_tick) {
          options_.progress({ExternalProgress::Phase::running, round_, detail::masks_written(dir), frames, t});
          next_tick = t + 0.25;
        }
      }
      if (w < 0 && errno != EINTR) {
        failure_ = Failure::start;
        throw Error(std::string("waitpid failed: ") + std::strerror(errno), cmd_where);
      }
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const bool cancel = options_.cancelled && options_.cancelled();
      if (cancel || elapsed > options_.timeout_s) {
        detail::kill_process_group(pid);
        failure_ = cancel ? Failure::cancelled : Failure::timeout;
        if (cancel) throw Error("interrupted while the segmenter was running", cmd_where);
        char secs[32];
        std::snprintf(secs, sizeof secs, "%g", options_.timeout_s);
        throw Error(std::string("timed out after ") + secs +
                        " s (--segmenter-timeout); request kept in " + dir.string() + detail::program_log_tail(log),
                    cmd_where);
      }
      std::this_thread::sleep_for(sleep);
      if (sleep < std::chrono::milliseconds(50)) sleep *= 2;
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
    failure_ = Failure::exit_status;
    const std::string how = WIFEXITED(status)
                                ? "exited with status " + std::to_string(WEXITSTATUS(status))
                                : "was killed by signal " + std::to_string(WTERMSIG(status));
    throw Error("the segmenter program " + how + "; request kept in " + dir.string() + detail::program_log_tail(log),
                cmd_where);
  }


  Mask read_mask_png(const std::filesystem::path& file, const std::string& where) {
    try {
      return read_mask(file);  // io/image_file.hpp: any channel count, foreground from half range
    } catch (const Error& e) {
      failure_ = Failure::bad_mask;
      throw Error(std::string("cannot decode the mask (") + e.what() + ")", where);
    }
  }

  std::string command_;
  ExternalSegmenterOptions options_;
  std::vector<std::string> argv_;
  std::size_t round_ = 0;
  Failure failure_ = Failure::none;
  std::filesystem::path last_request_dir_;
};

static_assert(Segmenter<ExternalSegmenter>);

static_assert(MultiSegmenter<ExternalSegmenter>);

}  // namespace vcar::io
