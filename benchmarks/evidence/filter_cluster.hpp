#pragma once
// Peer "filtercluster": what many splat users reach for today to isolate an object, PlayCanvas
// splat-transform's `--filter-cluster` (voxelise the scene, keep the connected cluster of solid
// voxels at a seed point, then the Gaussians that contribute to it). The seed is the prompt
// point's 3D position: the first prompt point (synth::prompt_points on the target's visible mask
// in the reference view, as `vcar synth` writes it) lifted with the rendered depth there, as
// clicking on the object in an editor does. The scene goes to splat-transform as a PLY and its
// output PLY is mapped back to scene indices by Gaussian identity (io/selection_identity.hpp;
// PLY -> PLY keeps every float). No masks, no cameras but the reference view.
//   VCAR_SPLAT_TRANSFORM   launcher (default: tests/interop/splat-transform of this source tree,
//                          which runs the pinned npm package; see tests/interop/README.md)
//   VCAR_FILTER_CLUSTER    "voxel,opacity,min_contribution" (default 0.02,0.999,0.1: 2 cm voxels
//                          on the synthetic world, whose target is 0.4-0.6 units wide)
// t_method is the seed pick (one render), the PLY write and the splat-transform process.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <sys/wait.h>

#include <Eigen/Core>

#include "vcar/baselines/inputs.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/selection_identity.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::evidence {

inline std::string splat_transform_launcher() {
  if (const char* e = std::getenv("VCAR_SPLAT_TRANSFORM"); e && *e) return e;
#ifdef VCAR_SPLAT_TRANSFORM_DEFAULT
  return VCAR_SPLAT_TRANSFORM_DEFAULT;
#else
  return "splat-transform";
#endif
}

inline std::string filter_cluster_args() {
  const char* e = std::getenv("VCAR_FILTER_CLUSTER");
  return e && *e ? e : "0.02,0.999,0.1";
}

inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Whether splat-transform runs here (checked once).
inline bool filter_cluster_available() {
  static const bool ok = [] {
    const std::string cmd = shell_quote(splat_transform_launcher()) + " --version > /dev/null 2>&1";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) && WEXITSTATUS(rc) == 0;
  }();
  return ok;
}

// The prompt point of the reference view in 3D: unprojected at the rendered depth (sum z alpha T
// over alpha) of the pixel under it.
template <Renderer R>
Eigen::Vector3f prompt_point_3d(const synth::World& w, const Camera& cam, R& renderer) {
  const Prompt p = synth::prompt_points(synth::visible_mask(w, cam, w.target_id, renderer), 0, 1, cam.name);
  RenderRequest q;
  q.scene = &w.scene;
  q.camera = &cam;
  q.want_depth = true;
  const RenderOutput out = renderer.render(q);
  const float u = p.points[0].x(), v = p.points[0].y();
  const std::size_t k = static_cast<std::size_t>(v) * static_cast<std::size_t>(cam.width) + static_cast<std::size_t>(u);
  if (!(out.alpha.data[k] > 0.f)) throw Error("nothing rendered under the prompt point", cam.name);
  const float z = out.depth.data[k] / out.alpha.data[k];
  const Eigen::Vector3f x_cam((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
  return cam.R_w.transpose() * (x_cam - cam.t_w);
}

template <Renderer R>
baselines::Result filter_cluster(const synth::World& w, const synth::Rig& rig, R& renderer, const std::filesystem::path& work) {
  if (!filter_cluster_available())
    throw Error("splat-transform does not run (" + splat_transform_launcher() + "): run `npm ci --prefix tests/interop` "
                "or set VCAR_SPLAT_TRANSFORM", "filtercluster");
  const Eigen::Vector3f seed = prompt_point_3d(w, rig.train[rig.reference], renderer);
  std::filesystem::create_directories(work);
  const std::filesystem::path in = work / "filtercluster_in.ply", out = work / "filtercluster_out.ply",
                              log = work / "filtercluster.log";
  io::write_ply(in, w.scene);
  std::filesystem::remove(out);
  char seed_arg[128];
  std::snprintf(seed_arg, sizeof seed_arg, "%.6f,%.6f,%.6f", static_cast<double>(seed.x()), static_cast<double>(seed.y()),
                static_cast<double>(seed.z()));
  const std::string cmd = shell_quote(splat_transform_launcher()) + " -w " + shell_quote(in.string()) + " --filter-cluster " +
                          shell_quote(filter_cluster_args()) + " --seed-pos " + seed_arg + " " + shell_quote(out.string()) +
                          " > " + shell_quote(log.string()) + " 2>&1";
  const int rc = std::system(cmd.c_str());
  if (!WIFEXITED(rc) || WEXITSTATUS(rc) != 0 || !std::filesystem::exists(out))
    throw Error("splat-transform --filter-cluster failed (exit " + std::to_string(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1) +
                "); see " + log.string(), "filtercluster");
  // Back to scene indices by identity (equal identities are identical Gaussians: each taken once).
  const GaussianScene kept = io::read_ply(out);
  std::unordered_map<std::uint64_t, std::vector<Index>> where;
  const std::vector<std::uint64_t> ids = io::gaussian_identities(w.scene);
  for (std::size_t i = ids.size(); i-- > 0;) where[ids[i]].push_back(static_cast<Index>(i));
  baselines::Result res;
  for (std::uint64_t id : io::gaussian_identities(kept)) {
    auto it = where.find(id);
    if (it == where.end() || it->second.empty())
      throw Error("splat-transform returned a Gaussian that is not in the scene (values changed?)", out.string());
    res.selected.push_back(it->second.back());
    it->second.pop_back();
  }
  std::sort(res.selected.begin(), res.selected.end());
  return res;
}

}  // namespace vcar::evidence
