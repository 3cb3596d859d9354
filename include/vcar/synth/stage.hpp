#pragma once
// A stage: real trained objects (any file io::read_scene reads) standing upright on a floor of
// flat textured Gaussians, each object's Gaussians labelled with its id, so that the ground
// truth is exact (synth/ground_truth.hpp: an inserted object's mask is its rendering alone,
// alpha > 0.5). The file format is synth/stage_json.hpp; `vcar synth --stage` writes a dataset.
//
// Each object is turned from its own frame to the world's (+z up): first the shortest turn that
// takes its `up` axis to +z, then `yaw_deg` about +z. It is scaled so that its robust height
// (or width) is the one asked for, its robust footprint centred on `position` and its robust
// lowest point put on the floor (z = 0). Robust extents are quantiles of the Gaussians' means
// (robust_extent_quantile), so a stray floater neither sizes an object nor lifts it off the floor.
// The objects' Gaussians are copied as they are (opacity, soft low-opacity edges, DC colour:
// insert_gaussians); nothing keeps two objects apart: the positions decide whether they touch.
//
// Deterministic by seed: the seed draws each object's yaw jitter (+- Stage::yaw_jitter_deg,
// uniform) and position jitter (+- Stage::position_jitter of its footprint width, per axis), and
// the floor's Gaussians; nothing else. The same stage and seed give the same bytes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vcar/core/error.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/synth/primitive.hpp"
#include "vcar/synth/random.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::synth {

// How much of the image height the rigs give a stage's target (RigParams::fill): its bounding
// sphere spans 70%, framed as a photographer would, with the objects beside it still in view.
inline constexpr float stage_rig_fill = 0.7f;

struct StageObject {
  std::string name;               // [A-Za-z0-9_.-], unique: names its prompt (and segment's folder)
  std::filesystem::path file;     // PLY, compressed PLY, SPZ or .splat
  std::string up = "+z";          // the object's up axis in its own frame: +x -x +y -y +z -z
  float yaw_deg = 0.f;            // turn about world +z once upright (counter-clockwise from above)
  // Its size: exactly one of these is > 0.
  float height = 0.f;             // robust vertical extent, world units
  float width = 0.f;              // robust horizontal extent (the larger of its own two), world units
  float scale = 0.f;              // a plain factor
  Eigen::Vector2f position{0.f, 0.f};  // world (x, y) of its robust footprint's centre
  int object_id = 0;              // its label; 0: its place in the stage (1, 2, 3, ...)
};

struct Stage {
  std::vector<StageObject> objects;
  std::string target;                  // the target's name; empty: the first object
  float floor_half_size = 0.f;         // the floor is a square of this half side; 0: derived (make_stage)
  std::size_t floor_gaussians = 0;     // 0: one per (1.25% of the tallest object's height)^2
  float yaw_jitter_deg = 3.f;          // per object, from the seed
  float position_jitter = 0.02f;       // per object and axis, times its footprint width, from the seed
};

// Where an object goes: world = R (scale x) + t, the argument list of insert_gaussians.
struct Placement {
  Eigen::Matrix3f R = Eigen::Matrix3f::Identity();
  Eigen::Vector3f t = Eigen::Vector3f::Zero();
  float scale = 1.f;
  float height = 0.f, width = 0.f;  // its robust world extents (vertical; larger horizontal one)
};

namespace detail {

inline bool valid_stage_name(const std::string& s) {
  return !s.empty() && s != "." && s != ".." &&
         s.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.-") == std::string::npos;
}

}  // namespace detail

// The shortest turn taking the axis `up` ("+x", "-x", "+y", "-y", "+z", "-z"; "x" = "+x") to +z:
// a quarter turn about the horizontal axis up x z, none for +z, half a turn about x for -z. The
// matrix is exact (entries 0, +-1). For a COLMAP-like capture whose up is -y, its +z (away from
// the capturing cameras) ends along world +y, so its front faces -y, the rigs' front.
inline Eigen::Matrix3f up_rotation(const std::string& up, const std::string& where = "up") {
  std::string s = up;
  if (s.size() == 1) s = "+" + s;
  if (s.size() != 2 || (s[0] != '+' && s[0] != '-') || s[1] < 'x' || s[1] > 'z')
    throw Error("bad up axis '" + up + "': one of +x, -x, +y, -y, +z, -z", where);
  Eigen::Vector3f u = Eigen::Vector3f::Zero();
  u[s[1] - 'x'] = s[0] == '+' ? 1.f : -1.f;
  if (u.z() == -1.f) return Eigen::Vector3f(1.f, -1.f, -1.f).asDiagonal();
  if (u.z() == 1.f) return Eigen::Matrix3f::Identity();
  const Eigen::Vector3f k = u.cross(Eigen::Vector3f::UnitZ());  // unit: u is horizontal
  Eigen::Matrix3f K;
  K << 0.f, -k.z(), k.y(), k.z(), 0.f, -k.x(), -k.y(), k.x(), 0.f;
  return K + k * k.transpose();  // Rodrigues at 90 degrees: cos 0, sin 1
}

// Places one object. `yaw_jitter_deg` and `position_jitter` (in footprint widths, per axis) are
// its draws from the seed. Throws naming `where` when the size is not exactly one positive value
// or the object is flat along the measured axis.
inline Placement place_object(const StageObject& o, const GaussianScene& g, float yaw_jitter_deg,
                              const Eigen::Vector2f& position_jitter, const std::string& where) {
  const int sizes = (o.height > 0.f) + (o.width > 0.f) + (o.scale > 0.f);
  if (sizes != 1 || !(o.height >= 0.f) || !(o.width >= 0.f) || !(o.scale >= 0.f))
    throw Error("give exactly one positive size: height, width or scale", where);
  if (g.size() == 0) throw Error("the object has no Gaussians", where);
  if (!std::isfinite(o.yaw_deg) || !o.position.allFinite()) throw Error("yaw and position must be finite", where);
  const Eigen::Matrix3f R_up = up_rotation(o.up, where + ".up");
  // Robust box of the upright object in its own units.
  Eigen::Vector3f lo, hi;
  std::vector<float> v(g.size());
  for (int d = 0; d < 3; ++d) {
    for (std::size_t i = 0; i < g.size(); ++i) v[i] = R_up.row(d).dot(g.mu(i));
    lo[d] = detail::quantile(v, robust_extent_quantile);
    hi[d] = detail::quantile(v, 1.0 - robust_extent_quantile);
  }
  const Eigen::Vector3f ext = hi - lo;
  const float own_width = std::max(ext.x(), ext.y());
  float s = o.scale;
  if (o.height > 0.f) {
    if (!(ext.z() > 0.f)) throw Error("the object has no vertical extent to scale to a height", where);
    s = o.height / ext.z();
  } else if (o.width > 0.f) {
    if (!(own_width > 0.f)) throw Error("the object has no horizontal extent to scale to a width", where);
    s = o.width / own_width;
  }
  const float yaw = (o.yaw_deg + yaw_jitter_deg) * std::numbers::pi_v<float> / 180.f;
  const Eigen::Matrix3f Rz = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  Placement p;
  p.R = Rz * R_up;
  p.scale = s;
  p.height = s * ext.z();
  p.width = s * own_width;
  // The footprint's centre at the robust lowest point goes to (position + jitter, 0).
  const Eigen::Vector3f anchor(0.5f * (lo.x() + hi.x()), 0.5f * (lo.y() + hi.y()), lo.z());
  const Eigen::Vector2f xy = o.position + p.width * position_jitter;
  p.t = Eigen::Vector3f(xy.x(), xy.y(), 0.f) - Rz * (s * anchor);
  return p;
}

// The stage from scenes already in memory: scenes[k] is objects[k]'s (their files are not read).
// Gaussians: the floor's first (id 0), then each object's in stage order (its id).
inline World make_stage(const Stage& stage, std::span<const GaussianScene> scenes, std::uint64_t seed) {
  if (stage.objects.empty()) throw Error("a stage needs at least one object", "stage.objects");
  if (scenes.size() != stage.objects.size())
    throw Error("one scene per object expected: " + std::to_string(stage.objects.size()) + " objects, " +
                std::to_string(scenes.size()) + " scenes", "make_stage");
  if (!(stage.yaw_jitter_deg >= 0.f) || !(stage.position_jitter >= 0.f))
    throw Error("jitters must be >= 0", "stage");
  if (!(stage.floor_half_size >= 0.f) || !std::isfinite(stage.floor_half_size))
    throw Error("the floor's half size must be >= 0 (0: derived)", "stage.floor");
  const std::size_t n_obj = stage.objects.size();
  std::vector<int> ids(n_obj);
  World w;
  w.seed = seed;
  w.up = Eigen::Vector3f::UnitZ();
  w.target_id = -1;
  for (std::size_t k = 0; k < n_obj; ++k) {
    const StageObject& o = stage.objects[k];
    const std::string where = "stage.objects[" + std::to_string(k) + "]";
    if (!detail::valid_stage_name(o.name)) throw Error("name '" + o.name + "' must be [A-Za-z0-9_.-]", where + ".name");
    ids[k] = o.object_id != 0 ? o.object_id : static_cast<int>(k) + 1;
    if (ids[k] < 1) throw Error("object id must be >= 1 (0 is the floor)", where + ".id");
    for (std::size_t m = 0; m < k; ++m) {
      if (stage.objects[m].name == o.name) throw Error("two objects are named '" + o.name + "'", where + ".name");
      if (ids[m] == ids[k]) throw Error("two objects have id " + std::to_string(ids[k]), where + ".id");
    }
    if ((stage.target.empty() && k == 0) || o.name == stage.target) w.target_id = ids[k];
  }
  if (w.target_id < 0) throw Error("no object is named '" + stage.target + "'", "stage.target");

  // Placements first (each from its own draws), so that the floor can be sized to the stage.
  std::vector<Placement> place(n_obj);
  float reach = 0.f, tallest = 0.f;  // the stage's horizontal reach from the origin; its tallest object
  for (std::size_t k = 0; k < n_obj; ++k) {
    const StageObject& o = stage.objects[k];
    const std::string where = "stage.objects[" + std::to_string(k) + "] ('" + o.name + "')";
    scenes[k].validate(o.file.empty() ? where : o.file.string());
    Rng rng(seed, 0x57A6Eu, k);
    const float yaw_j = stage.yaw_jitter_deg * rng.uniform(-1.f, 1.f);  // sequenced: yaw, x, y
    const float jx = rng.uniform(-1.f, 1.f);
    const float jy = rng.uniform(-1.f, 1.f);
    place[k] = place_object(o, scenes[k], yaw_j, stage.position_jitter * Eigen::Vector2f(jx, jy), where);
    reach = std::max(reach, o.position.cwiseAbs().maxCoeff() + place[k].width);
    tallest = std::max(tallest, place[k].height);
  }

  // The floor: a square plane (id 0) reaching 1.5 tallest heights beyond the stage, so the
  // rigs, which stand about that far out, look at floor behind every object.
  Primitive floor;
  floor.type = PrimitiveType::plane;
  floor.object_id = 0;
  const float half = stage.floor_half_size > 0.f ? stage.floor_half_size : reach + 1.5f * tallest;
  floor.params = {half, half, 0.f};
  floor.texture.pattern = Pattern::noise;
  floor.texture.colour_a = {0.62f, 0.55f, 0.45f};  // light and dark wood-like tones
  floor.texture.colour_b = {0.30f, 0.26f, 0.22f};
  floor.texture.frequency = 6.f / tallest;         // blotches about a sixth of the tallest object
  w.primitives.push_back(floor);
  const float spacing = 0.0125f * tallest;
  const double n_floor_d = stage.floor_gaussians > 0 ? static_cast<double>(stage.floor_gaussians)
                                                     : std::ceil(area(floor) / (spacing * spacing));
  if (n_floor_d > 5e7) throw Error("the floor would need " + std::to_string(n_floor_d) + " Gaussians: give floor.gaussians", "stage.floor");
  const std::size_t n_floor = static_cast<std::size_t>(n_floor_d);
  w.scene.resize(n_floor, 0);
  w.object_id.assign(n_floor, 0);
  const float h = std::sqrt(area(floor) / static_cast<float>(n_floor));
  const WorldParams defaults;
  parallel_for(static_cast<std::int64_t>(n_floor), [&](std::int64_t ii) {
    const std::size_t i = static_cast<std::size_t>(ii);
    Rng rng(seed, 0xF1002u, i);
    detail::surface_disc(w.scene, i, w.primitives, 0, h, defaults.disc_scale, defaults.normal_scale, rng);
  });

  for (std::size_t k = 0; k < n_obj; ++k) insert_gaussians(w, scenes[k], place[k].R, place[k].t, place[k].scale, ids[k]);

  // The neighbour: the object whose footprint centre is nearest the target's (the floor alone: 0).
  w.neighbour_id = 0;
  float best = INFINITY;
  std::size_t target_k = 0;
  for (std::size_t k = 0; k < n_obj; ++k) if (ids[k] == w.target_id) target_k = k;
  for (std::size_t k = 0; k < n_obj; ++k) {
    const float d = (stage.objects[k].position - stage.objects[target_k].position).norm();
    if (k != target_k && d < best) { best = d; w.neighbour_id = ids[k]; }
  }
  return w;
}

// Reads each object's file (io::read_scene: PLY, compressed PLY, SPZ, .splat), then make_stage.
inline World make_stage(const Stage& stage, std::uint64_t seed) {
  std::vector<GaussianScene> scenes;
  scenes.reserve(stage.objects.size());
  for (const StageObject& o : stage.objects) scenes.push_back(io::read_scene(o.file));
  return make_stage(stage, scenes, seed);
}

}  // namespace vcar::synth
