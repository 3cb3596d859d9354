// vcar's readers and writers against an independent implementation, @playcanvas/splat-transform
// (pinned in package.json here; tests/interop/README.md). For each tests/data/*.ply:
//   splat-transform PLY -> compressed PLY, SPZ v4, SPZ v3; vcar reads them;
//   vcar writes .splat, SPZ v3 and a state PLY; splat-transform reads them and writes PLY, vcar
//   reads that;
// and every value is compared with the original within the format's quantisation (the bounds of
// docs/formats.md, "Tolerances"). Prints the largest error of each attribute next to its bound.
// Exit 0: all within; 1: something is not; 77: splat-transform cannot run here (CTest SKIP).
//   interop_test_splat_transform <tests/interop/splat-transform> <data dir> <work dir>
#include <algorithm>
#include <deque>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numeric>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include <sys/wait.h>

#include "vcar/io/compressed_ply.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/selection_identity.hpp"
#include "vcar/io/splat_file.hpp"
#include "vcar/io/spz.hpp"
#include "vcar/io/state_ply.hpp"

namespace fs = std::filesystem;
using vcar::GaussianScene;

namespace {

constexpr int kSkip = 77;
std::string g_tool;
fs::path g_work;

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs splat-transform with `args`; its output goes to work/<log>.
int splat_transform(const std::string& args, const std::string& log) {
  const std::string cmd = quote(g_tool) + " -w " + args + " > " + quote((g_work / (log + ".log")).string()) + " 2>&1";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128;
}

std::string tail_of(const std::string& log) {
  std::ifstream in(g_work / (log + ".log"));
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  std::string out;
  for (std::size_t k = lines.size() > 8 ? lines.size() - 8 : 0; k < lines.size(); ++k) out += "    | " + lines[k] + "\n";
  return out;
}

// Largest error of one attribute against its bound (a bound per value when `per_value`).
struct Stat {
  std::string name;
  double max_err = 0, bound = 0;  // bound: the largest bound met (for the report)
  std::size_t over = 0, n = 0;
  void add(double err, double b) {
    ++n;
    max_err = std::max(max_err, err);
    bound = std::max(bound, b);
    if (!(err <= b)) ++over;
  }
};

struct Report {
  std::string conversion;
  std::deque<Stat> stats;  // stable references: stat() hands out references across push_backs
  bool failed = false;
  std::string note;
  Stat& stat(const std::string& name) {
    for (auto& s : stats) if (s.name == name) return s;
    stats.push_back({name});
    return stats.back();
  }
};
std::vector<Report> g_reports;
Report report(std::string conversion) {
  Report r;
  r.conversion = std::move(conversion);
  return r;
}

float sigmoid(float x) { return 1.f / (1.f + std::exp(-x)); }

// Angle (radians) between the rotations of two quaternions.
double rotation_angle(const GaussianScene& a, std::size_t i, const GaussianScene& b, std::size_t j) {
  double dot = 0, na = 0, nb = 0;
  for (int k = 0; k < 4; ++k) {
    dot += double(a.rotation[k][i]) * b.rotation[k][j];
    na += double(a.rotation[k][i]) * a.rotation[k][i];
    nb += double(b.rotation[k][j]) * b.rotation[k][j];
  }
  return 2.0 * std::acos(std::min(1.0, std::abs(dot) / std::sqrt(na * nb)));
}

// Bounds of one comparison, per attribute; functions of (original i, decoded j).
struct Bounds {
  std::function<double(std::size_t j, int d)> position;
  std::function<double(std::size_t j, int d)> log_scale;
  std::function<float(float)> clamp_log_scale = [](float v) { return v; };
  double alpha = 0.5 / 255 + 1e-6;
  std::function<double(std::size_t j)> dc;  // on f_dc
  std::function<float(float)> clamp_dc = [](float v) { return v; };
  double rotation_rad = 0;
  std::function<double(float original, std::size_t k)> sh;  // k = coefficient 1..15; nan: skip
  std::function<float(float)> clamp_sh = [](float v) { return v; };
  int sh_degree = -1;  // expected degree of the decoded scene (-1: the original's)
};

// Compares decoded Gaussian j with original Gaussian match[j].
void compare(Report& r, const GaussianScene& orig, const GaussianScene& dec, const std::vector<std::size_t>& match,
             const Bounds& b) {
  const int want_degree = b.sh_degree < 0 ? orig.sh_degree : b.sh_degree;
  if (dec.size() != orig.size() || dec.sh_degree != want_degree) {
    r.failed = true;
    r.note = "decoded " + std::to_string(dec.size()) + " Gaussians, SH degree " + std::to_string(dec.sh_degree) + "; expected " +
             std::to_string(orig.size()) + ", degree " + std::to_string(want_degree);
    return;
  }
  const std::size_t Bo = static_cast<std::size_t>(orig.sh_coeffs()), Bd = static_cast<std::size_t>(dec.sh_coeffs());
  for (std::size_t j = 0; j < dec.size(); ++j) {
    const std::size_t i = match[j];
    for (int d = 0; d < 3; ++d) {
      r.stat("position").add(std::abs(double(dec.mean[d][j]) - orig.mean[d][i]), b.position(j, d));
      r.stat("log_scale").add(std::abs(double(dec.log_scale[d][j]) - b.clamp_log_scale(orig.log_scale[d][i])), b.log_scale(j, d));
    }
    r.stat("opacity (after sigmoid)").add(std::abs(double(sigmoid(dec.opacity_logit[j])) - sigmoid(orig.opacity_logit[i])), b.alpha);
    for (std::size_t c = 0; c < 3; ++c)
      r.stat("f_dc").add(std::abs(double(dec.sh[j * Bd * 3 + c]) - b.clamp_dc(orig.sh[i * Bo * 3 + c])), b.dc(j));
    r.stat("rotation (rad)").add(rotation_angle(orig, i, dec, j), b.rotation_rad);
    for (std::size_t k = 1; k < Bd; ++k)
      for (std::size_t c = 0; c < 3; ++c) {
        const float o = orig.sh[(i * Bo + k) * 3 + c];
        r.stat("f_rest").add(std::abs(double(dec.sh[(j * Bd + k) * 3 + c]) - b.clamp_sh(o)), b.sh(o, k));
      }
  }
  for (const auto& s : r.stats) r.failed = r.failed || s.over > 0;
}

std::vector<std::size_t> identity_match(std::size_t n) {
  std::vector<std::size_t> m(n);
  for (std::size_t i = 0; i < n; ++i) m[i] = i;
  return m;
}

// Writers that sort (compressed PLY): decoded Gaussian j is the original nearest to it, among
// those within `radius` per axis, by the sum of position, log-scale and colour differences
// scaled by their bounds; each original is taken once. Unmatched: SIZE_MAX.
std::vector<std::size_t> nearest_match(const GaussianScene& orig, const GaussianScene& dec, const std::function<double(std::size_t, int)>& pos_bound,
                                       const std::function<double(std::size_t, int)>& scale_bound) {
  double cell = 0;
  for (std::size_t j = 0; j < dec.size(); ++j)
    for (int d = 0; d < 3; ++d) cell = std::max(cell, 2.0 * pos_bound(j, d));
  cell = std::max(cell, 1e-9);
  auto key = [&](double x, double y, double z) {
    const auto q = [&](double v) { return static_cast<std::int64_t>(std::floor(v / cell)); };
    return std::array<std::int64_t, 3>{q(x), q(y), q(z)};
  };
  struct H { std::size_t operator()(const std::array<std::int64_t, 3>& k) const { return std::hash<std::int64_t>()(k[0] * 73856093 ^ k[1] * 19349663 ^ k[2] * 83492791); } };
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<std::size_t>, H> grid;
  for (std::size_t i = 0; i < orig.size(); ++i) grid[key(orig.mean[0][i], orig.mean[1][i], orig.mean[2][i])].push_back(i);
  std::vector<char> used(orig.size(), 0);
  std::vector<std::size_t> m(dec.size(), SIZE_MAX);
  const std::size_t Bo = static_cast<std::size_t>(orig.sh_coeffs()), Bd = static_cast<std::size_t>(dec.sh_coeffs());
  for (std::size_t j = 0; j < dec.size(); ++j) {
    const auto k = key(dec.mean[0][j], dec.mean[1][j], dec.mean[2][j]);
    double best = INFINITY;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end()) continue;
          for (std::size_t i : it->second) {
            if (used[i]) continue;
            double cost = 0;
            for (int d = 0; d < 3; ++d) {
              cost += std::abs(dec.mean[d][j] - orig.mean[d][i]) / std::max(pos_bound(j, d), 1e-9);
              cost += std::abs(dec.log_scale[d][j] - std::clamp(orig.log_scale[d][i], -20.f, 20.f)) / std::max(scale_bound(j, d), 1e-9);
            }
            for (std::size_t c = 0; c < 3; ++c) cost += std::abs(dec.sh[j * Bd * 3 + c] - orig.sh[i * Bo * 3 + c]);
            if (cost < best) { best = cost; m[j] = i; }
          }
        }
    if (m[j] != SIZE_MAX) used[m[j]] = 1;
  }
  return m;
}

// ---- the conversions ------------------------------------------------------------------------
void check_compressed_ply(const fs::path& ply, const GaussianScene& orig, const std::string& stem) {
  Report r = report("splat-transform -> " + stem + ".compressed.ply -> vcar");
  const fs::path out = g_work / (stem + ".compressed.ply");
  if (splat_transform(quote(ply.string()) + " " + quote(out.string()), stem + "_cply") != 0) {
    r.failed = true;
    r.note = "splat-transform failed:\n" + tail_of(stem + "_cply");
    g_reports.push_back(r);
    return;
  }
  const GaussianScene dec = vcar::io::read_scene(out);
  const auto raw = vcar::io::detail::read_compressed_ply_raw(out);
  // Half a quantisation step of Gaussian j's chunk (11-10-11 bits), plus float rounding.
  auto half_step = [&](std::size_t j, int lo, int d) {
    const float* ch = raw.chunks.data() + (j / 256) * 18;
    const double range = double(ch[lo + 3 + d]) - ch[lo + d];
    return range / (2.0 * ((d == 1 ? 1023 : 2047))) + 1e-6 * (1.0 + std::abs(ch[lo + d]) + std::abs(ch[lo + 3 + d]));
  };
  Bounds b;
  b.position = [&](std::size_t j, int d) { return half_step(j, 0, d); };
  b.log_scale = [&](std::size_t j, int d) { return half_step(j, 6, d); };
  b.clamp_log_scale = [](float v) { return std::clamp(v, -20.f, 20.f); };
  b.dc = [&](std::size_t j) {
    const float* ch = raw.chunks.data() + (j / 256) * 18;
    double range = 0;
    for (int c = 0; c < 3; ++c) range = std::max(range, double(ch[15 + c]) - ch[12 + c]);
    return range / 510.0 / 0.28209479177 + 1e-5;
  };
  b.rotation_rad = 4 * std::sqrt(3.0) * (std::sqrt(2.0) / 1023 / 2);  // smallest three, 10 bits (docs/formats.md)
  b.clamp_sh = [](float v) { return std::clamp(v, -4.f, 4.f); };
  b.sh = [](float o, std::size_t) { return (o < -3.96875f || o >= 3.96875f ? 1.0 / 32 : 1.0 / 64) + 1e-6; };
  const auto match = nearest_match(orig, dec, b.position, b.log_scale);
  if (std::count(match.begin(), match.end(), SIZE_MAX) > 0) {
    r.failed = true;
    r.note = std::to_string(std::count(match.begin(), match.end(), SIZE_MAX)) + " decoded Gaussians match no original within the position bound";
  } else {
    compare(r, orig, dec, match, b);
    r.note = "matched by nearest position (the writer sorts in Morton order)";
  }
  g_reports.push_back(r);
}

Bounds spz_bounds(bool splat_transform_sh_bits) {
  Bounds b;
  b.position = [](std::size_t, int) { return 0.5 / 4096 + 1e-6; };
  b.log_scale = [](std::size_t, int) { return 1.0 / 32 + 1e-6; };
  b.clamp_log_scale = [](float v) { return std::clamp(v, -10.f, 15.9375f - 10.f); };
  b.dc = [](std::size_t) { return 0.5 / 38.25 + 1e-5; };
  b.clamp_dc = [](float v) { return std::clamp(v, -127.5f / 38.25f, 127.5f / 38.25f); };
  b.rotation_rad = 4 * std::sqrt(3.0) * (std::sqrt(0.5) / 511 / 2);  // smallest three, sign + 9 bits
  b.clamp_sh = [](float v) { return std::clamp(v, -1.f, 127.f / 128.f); };
  if (splat_transform_sh_bits)  // splat-transform: 5 bits for degree 1, 4 bits above (SPZ defaults)
    b.sh = [](float, std::size_t k) { return (k <= 3 ? 4.5 : 8.5) / 128.0 + 1e-6; };
  else  // vcar writes all 8 bits
    b.sh = [](float, std::size_t) { return 0.5 / 128.0 + 1e-6; };
  return b;
}

void check_spz_in(const fs::path& ply, const GaussianScene& orig, const std::string& stem, int version) {
  const std::string name = stem + ".v" + std::to_string(version) + ".spz";
  Report r = report("splat-transform -> " + name + " -> vcar");
  const fs::path out = g_work / name;
  if (splat_transform("--spz-version " + std::to_string(version) + " " + quote(ply.string()) + " " + quote(out.string()), name) != 0) {
    r.failed = true;
    r.note = "splat-transform failed:\n" + tail_of(name);
  } else {
    compare(r, orig, vcar::io::read_scene(out), identity_match(orig.size()), spz_bounds(true));
    r.note = "same order";
  }
  g_reports.push_back(r);
}

// splat-transform's PLY output, read without GaussianScene::validate: its SPZ reader turns an
// alpha byte of 255 into an infinite logit (vcar clamps it, docs/formats.md), which is still
// opacity 1 after the sigmoid, the value compared. Binary little-endian, any scalar types.
GaussianScene read_ply_lenient(const fs::path& path) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  const auto h = vcar::io::detail::parse_ply_header(in, where);
  const auto& v = h.elements.at(0);
  if (!h.binary || v.name != "vertex" || v.has_list) throw vcar::Error("unexpected PLY layout", where);
  int rest = 0;
  for (const auto& p : v.props) rest += p.name.rfind("f_rest_", 0) == 0;
  GaussianScene s;
  bool has_state = false;
  for (const auto& p : v.props) has_state = has_state || p.name == "state";
  if (has_state) s.extra_names = {"state"};
  s.resize(static_cast<std::size_t>(v.count), rest == 45 ? 3 : rest == 24 ? 2 : rest == 9 ? 1 : 0);
  const std::size_t B = static_cast<std::size_t>(s.sh_coeffs());
  std::vector<unsigned char> row(v.stride);
  in.seekg(static_cast<std::streamoff>(h.data_offset));
  for (std::size_t i = 0; i < s.size(); ++i) {
    in.read(reinterpret_cast<char*>(row.data()), static_cast<std::streamsize>(row.size()));
    if (!in) throw vcar::Error("truncated", where);
    for (const auto& p : v.props) {
      const float x = vcar::io::detail::decode_ply_value(row.data() + p.offset, p.type);
      int k = 0;
      const std::string& n = p.name;
      if (n == "x" || n == "y" || n == "z") s.mean[static_cast<std::size_t>(n[0] - 'x')][i] = x;
      else if (n == "opacity") s.opacity_logit[i] = x;
      else if (n == "state") s.extra[i] = x;
      else if (vcar::io::detail::parse_index_suffix(n, "scale_", k)) s.log_scale[static_cast<std::size_t>(k)][i] = x;
      else if (vcar::io::detail::parse_index_suffix(n, "rot_", k)) s.rotation[static_cast<std::size_t>(k)][i] = x;
      else if (vcar::io::detail::parse_index_suffix(n, "f_dc_", k)) s.sh[i * B * 3 + static_cast<std::size_t>(k)] = x;
      else if (vcar::io::detail::parse_index_suffix(n, "f_rest_", k))
        s.sh[(i * B + static_cast<std::size_t>(k) % (B - 1) + 1) * 3 + static_cast<std::size_t>(k) / (B - 1)] = x;
    }
  }
  return s;
}

// vcar writes `file`, splat-transform reads it and writes PLY, vcar reads that PLY back.
GaussianScene through_splat_transform(Report& r, const fs::path& file, const std::string& log) {
  const fs::path back = fs::path(file.string() + ".back.ply");
  if (splat_transform(quote(file.string()) + " " + quote(back.string()), log) != 0) {
    r.failed = true;
    r.note = "splat-transform could not read it:\n" + tail_of(log);
    return {};
  }
  return read_ply_lenient(back);
}

void check_spz_out(const GaussianScene& orig, const std::string& stem) {
  Report r = report("vcar -> " + stem + ".spz (v3) -> splat-transform -> PLY");
  const fs::path f = g_work / (stem + ".vcar.spz");
  vcar::io::write_spz(f, orig);
  const GaussianScene back = through_splat_transform(r, f, stem + "_spz_out");
  if (!r.failed) {
    compare(r, orig, back, identity_match(orig.size()), spz_bounds(false));
    r.note = "same order";
  }
  g_reports.push_back(r);
}

void check_splat_out(const GaussianScene& orig, const std::string& stem) {
  Report r = report("vcar -> " + stem + ".splat -> splat-transform -> PLY");
  const fs::path f = g_work / (stem + ".vcar.splat");
  vcar::io::write_splat(f, orig);
  const GaussianScene back = through_splat_transform(r, f, stem + "_splat_out");
  if (!r.failed) {
    Bounds b;
    b.sh_degree = 0;
    b.position = [](std::size_t, int) { return 0.0; };
    b.log_scale = [](std::size_t, int) { return 2e-6; };  // exp then log in float32
    b.dc = [](std::size_t) { return 0.5 / 255 / 0.28209479177 + 1e-5; };
    b.clamp_dc = [](float v) { return std::clamp(v, -0.5f / 0.28209479f, 0.5f / 0.28209479f); };
    // 8 bits per component; splat-transform decodes v / 127.5 - 1 where antimatter15 (and vcar)
    // decode (v - 128) / 128, so its angle to the original is a little larger than vcar's.
    b.rotation_rad = 0.05;  // 4 components off by <= 1/128 + 1/256 each: angle <= 2 |dq|
    compare(r, orig, back, identity_match(orig.size()), b);
    // And splat-transform's decode against vcar's decode of the same file.
    const GaussianScene ours = vcar::io::read_splat(f);
    Stat& s = r.stat("vs vcar's own read: rotation (rad)");
    for (std::size_t i = 0; i < ours.size(); ++i) s.add(rotation_angle(ours, i, back, i), 0.032);  // 4 x 1/128
    r.failed = r.failed || s.over > 0;
    r.note = "same order; SH degree > 0 dropped by the format";
  }
  g_reports.push_back(r);
}

void check_state_ply(const GaussianScene& orig, const std::string& stem) {
  Report r = report("vcar -> " + stem + ".state.ply -> splat-transform -> PLY");
  const fs::path f = g_work / (stem + ".state.ply");
  std::vector<std::uint8_t> state(orig.size(), 0);
  for (std::size_t i = 0; i < state.size(); i += 7) state[i] = vcar::io::splat_state::selected;
  vcar::io::write_state_ply(f, orig, state);
  const GaussianScene back = through_splat_transform(r, f, stem + "_state");
  if (!r.failed) {
    // Lossless: identical Gaussians (identities), the same state bytes, in the same order.
    const auto a = vcar::io::gaussian_identities(orig), b = vcar::io::gaussian_identities(back);
    Stat& s = r.stat("Gaussians with another identity");
    s.add(static_cast<double>(a.size() == b.size() ? std::inner_product(a.begin(), a.end(), b.begin(), std::size_t{0}, std::plus<>(),
                                                                         [](auto x, auto y) { return std::size_t(x != y); })
                                                   : a.size()),
          0);
    Stat& t = r.stat("state bytes that differ");
    const auto back_state = vcar::io::state_of(back);
    std::size_t diff = back_state.size() == state.size() ? 0 : state.size();
    for (std::size_t i = 0; i < std::min(state.size(), back_state.size()); ++i) diff += back_state[i] != state[i];
    t.add(static_cast<double>(diff), 0);
    r.failed = s.over > 0 || t.over > 0;
    r.note = "lossless";
  }
  g_reports.push_back(r);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s <splat-transform launcher> <data dir> <work dir>\n", argv[0]);
    return 2;
  }
  g_tool = argv[1];
  const fs::path data = argv[2];
  g_work = argv[3];
  fs::remove_all(g_work);
  fs::create_directories(g_work);
  const int rc = splat_transform("--version", "version");
  if (rc != 0) {
    std::printf("SKIP: splat-transform cannot run here (exit %d): npm unreachable or `npm ci --prefix tests/interop` "
                "not run (.ci/install-deps runs it)\n%s", rc, tail_of("version").c_str());
    return kSkip;
  }
  std::vector<fs::path> plys;
  for (const auto& e : fs::directory_iterator(data))
    if (e.path().extension() == ".ply") plys.push_back(e.path());
  std::sort(plys.begin(), plys.end());
  for (const fs::path& ply : plys) {
    const GaussianScene orig = vcar::io::read_ply(ply);
    const std::string stem = ply.stem().string();
    std::printf("%s: %zu Gaussians, SH degree %d\n", ply.filename().string().c_str(), orig.size(), orig.sh_degree);
    check_compressed_ply(ply, orig, stem);
    check_spz_in(ply, orig, stem, 4);
    check_spz_in(ply, orig, stem, 3);
    check_spz_out(orig, stem);
    check_splat_out(orig, stem);
    check_state_ply(orig, stem);
  }
  bool failed = false;
  for (const Report& r : g_reports) {
    std::printf("%s %s%s%s\n", r.failed ? "FAIL" : "ok  ", r.conversion.c_str(), r.note.empty() ? "" : ": ", r.note.c_str());
    for (const Stat& s : r.stats)
      std::printf("       %-36s max error %-12.6g bound %-12.6g values %zu, over the bound %zu\n", s.name.c_str(), s.max_err,
                  s.bound, s.n, s.over);
    failed = failed || r.failed;
  }
  return failed ? 1 : 0;
}
