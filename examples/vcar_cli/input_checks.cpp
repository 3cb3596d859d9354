#include "input_checks.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <set>

#include <Eigen/Core>

#include "cli_common.hpp"
#include "vcar/io/selection_identity.hpp"

namespace fs = std::filesystem;

namespace vcar::cli {

void warn(const std::string& text) {
  if (::isatty(STDERR_FILENO)) std::fputs("\r\033[K", stderr);
  std::fprintf(stderr, "vcar: warning: %s\n", text.c_str());
  std::fflush(stderr);
}

void opengl_to_opencv(std::vector<Camera>& cams) {
  const Eigen::Matrix3f D = Eigen::Vector3f(1.f, -1.f, -1.f).asDiagonal();
  for (Camera& c : cams) {
    c.R_w = D * c.R_w;
    c.t_w = D * c.t_w;
  }
}

namespace {
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}
std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}
}  // namespace

MaskCoverage check_mask_folder(const fs::path& dir, const std::vector<Camera>& cams, std::size_t reference_view) {
  std::set<std::string> stems;
  std::vector<std::string> others;  // files that are no mask of any view, for the message
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (!e.is_regular_file()) continue;
    const std::string ext = lower(e.path().extension().string());
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") stems.insert(e.path().stem().string());
    else if (others.size() < 3) others.push_back(e.path().filename().string());
  }
  MaskCoverage cov;
  for (const Camera& c : cams) {
    const std::string stem = fs::path(c.name).stem().string();
    if (stems.count(stem)) continue;
    cov.missing.push_back(c.name);
    cov.expected_missing.push_back(dir / (stem + ".png"));
  }
  auto examples = [&](std::size_t n) {
    std::string s;
    for (std::size_t k = 0; k < cov.expected_missing.size() && k < n; ++k)
      s += (k ? ", " : "") + cov.expected_missing[k].string();
    if (cov.expected_missing.size() > n) s += ", ...";
    return s;
  };
  if (cov.missing.size() == cams.size()) {
    std::string found;
    std::size_t k = 0;
    for (const std::string& s : stems) {
      if (k++ == 3) { found += ", ..."; break; }
      found += (k > 1 ? ", " : "") + s;
    }
    for (const std::string& s : others) found += (found.empty() ? "" : ", ") + s;
    throw CliError(exit_bad_input,
                   "no mask matches a view: expected one file per view named like the view (.png, .jpg or .jpeg), e.g. " +
                       examples(2) + (found.empty() ? "; the folder holds no image" : "; the folder holds " + found),
                   dir.string() + " (--masks)");
  }
  if (!cov.missing.empty()) {
    const bool ref_missing = std::find(cov.missing.begin(), cov.missing.end(), cams[reference_view].name) != cov.missing.end();
    warn(std::to_string(cov.missing.size()) + " of " + std::to_string(cams.size()) +
         " views have no mask in " + dir.string() + " (" + examples(3) +
         "); they count as no evidence" + (ref_missing ? " (the prompt view is one of them)" : ""));
  }
  return cov;
}

double mean_visible_fraction(const GaussianScene& scene, const std::vector<Camera>& cams, std::size_t sample) {
  const std::size_t n = scene.size();
  if (n == 0 || cams.empty()) return 0;
  const std::size_t step = std::max<std::size_t>(1, n / std::max<std::size_t>(1, sample));
  double sum = 0;
  for (const Camera& c : cams) {
    std::size_t seen = 0, total = 0;
    for (std::size_t i = 0; i < n; i += step, ++total) {
      const Eigen::Vector3f p = c.to_camera({scene.mean[0][i], scene.mean[1][i], scene.mean[2][i]});
      if (!(p.z() > 0.01f)) continue;
      const float u = c.fx * p.x() / p.z() + c.cx, v = c.fy * p.y() / p.z() + c.cy;
      seen += inside_image(u, v, c.width, c.height);
    }
    sum += total ? static_cast<double>(seen) / static_cast<double>(total) : 0.0;
  }
  return sum / static_cast<double>(cams.size());
}

namespace {
// The scene's extent (2nd to 98th percentile of the means per axis) and centre, and the
// cameras' distances from that centre, in scene units: what a user compares with their file.
std::string scene_units(const GaussianScene& scene, const std::vector<Camera>& cams) {
  Eigen::Vector3f lo, hi;
  for (int d = 0; d < 3; ++d) {
    std::vector<float> v(scene.mean[d]);
    const std::size_t a = v.size() / 50, b = v.size() - 1 - v.size() / 50;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(a), v.end());
    lo[d] = v[a];
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(b), v.end());
    hi[d] = v[b];
  }
  const Eigen::Vector3f centre = 0.5f * (lo + hi), size = hi - lo;
  double dmin = 1e30, dmax = 0;
  for (const Camera& c : cams) {
    const double d = (c.position() - centre).norm();
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "the scene's Gaussians span %.3g x %.3g x %.3g units around (%.3g, %.3g, %.3g); the cameras are %.3g to %.3g units from that centre",
                size.x(), size.y(), size.z(), centre.x(), centre.y(), centre.z(), dmin, dmax);
  return buf;
}
}  // namespace

void check_cameras_face_scene(const GaussianScene& scene, const std::vector<Camera>& cams,
                              const std::string& cameras_path, bool opengl) {
  const double f = mean_visible_fraction(scene, cams);
  std::vector<Camera> flipped = cams;
  opengl_to_opencv(flipped);
  const double f_other = mean_visible_fraction(scene, flipped);
  const std::string convention = opengl
      ? "read with --opengl-cameras (the file's axes taken as OpenGL's: x right, y up, z backward)"
      : "cameras must use OpenCV/COLMAP axes (x right, y down, z forward) in the scene's units";
  const bool other_helps = f_other > 3.0 * f && f_other >= 0.05;
  const std::string hint = other_helps
      ? std::string(opengl ? "; without --opengl-cameras " : "; read as OpenGL axes (--opengl-cameras) ") +
            fmt("%.1f%%", 100.0 * f_other) + " would be in view"
      : "";
  const std::string what = fmt("%.2f%%", 100.0 * f) + " of the Gaussians lie in front of the average camera and inside its image";
  if (f < 0.01)
    throw CliError(exit_bad_input, "almost no Gaussian is in view of the cameras: " + what + "; " + convention + "; " +
                                       scene_units(scene, cams) + hint, cameras_path + " (--cameras)");
  if (f < 0.05 || other_helps)
    warn("few Gaussians are in view of the cameras: " + what + "; " + convention + hint + " (" + cameras_path + ")");
}

void check_oracle_scene(const GaussianScene& scene, const GaussianScene& dataset_scene, const fs::path& dataset_dir) {
  const io::SceneFingerprint a = io::scene_fingerprint(io::gaussian_identities(scene));
  const io::SceneFingerprint b = io::scene_fingerprint(io::gaussian_identities(dataset_scene));
  if (a.gaussians == b.gaussians && a.unordered == b.unordered) return;  // same Gaussians, any order
  throw CliError(exit_bad_input,
                 "the oracle dataset is of another scene: its scene.ply has " + std::to_string(b.gaussians) +
                     " Gaussians (fingerprint " + io::identity_hex(b.unordered) + "), --scene has " +
                     std::to_string(a.gaussians) + " (fingerprint " + io::identity_hex(a.unordered) +
                     "); the oracle answers with that dataset's ground truth, so give --scene " +
                     (dataset_dir / "scene.ply").string() + " (or a re-sorted copy of it)",
                 dataset_dir.string() + " (--oracle)");
}

void check_program(const std::string& program) {
  auto runnable = [](const fs::path& f) {
    std::error_code ec;
    return fs::is_regular_file(f, ec) && ::access(f.c_str(), X_OK) == 0;
  };
  if (program.find('/') != std::string::npos) {
    if (runnable(program)) return;
    std::error_code ec;
    throw CliError(exit_segmenter, fs::exists(program, ec) ? "the segmenter program is not an executable file"
                                                           : "the segmenter program does not exist",
                   program + " (--segmenter-cmd)");
  }
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t at = 0;
  while (at <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', at), dirs.size());
    const std::string d = dirs.substr(at, end - at);
    if (runnable(fs::path(d.empty() ? "." : d) / program)) return;
    at = end + 1;
  }
  throw CliError(exit_segmenter, "the segmenter program is not in PATH (give its path, or install it)",
                 program + " (--segmenter-cmd)");
}

}  // namespace vcar::cli
