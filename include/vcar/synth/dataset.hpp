#pragma once
// Exports a world and a rig as an ordinary dataset directory, and reads the world back.
//
//   scene.ply                   the Gaussians (Inria layout, SH degree 0)
//   cameras.json                TRAINING cameras only (Inria), same order as the rig
//   sparse/0/*.txt              the training cameras as a COLMAP text model (no points)
//   transforms.json             the training cameras (nerfstudio)
//   images/<name>.png           renders of the training views (full scene)
//   masks/<name>.png            visible ground truth of the target in the training views
//   prompt.json                 {"reference_view": name, "reference_index": k,
//                                "points": [[u, v], ...] (positive, deep inside the visible
//                                mask of the reference view), "labels": [1, ...], "target_id",
//                                "box": [x0, y0, x1, y1] (around that visible mask)}; with
//                                ExportOptions::objects also "objects": [{"name", "object_id",
//                                "reference_view", "points", "labels", "box"}, ...]
//   prompts.json                with ExportOptions::objects: the objects' prompts in the format
//                                of `vcar segment --prompts` (those some training view shows)
//   gt/eval_cameras.json        the held-out evaluation cameras (Inria layout)
//   gt/eval_images/<name>.png   renders of the evaluation views
//   gt/silhouettes/<name>.png   the target alone (evaluation and training views)
//   gt/visible/<name>.png       visible ground truth of the evaluation views
//   gt/gaussian_ids.bin         int32 little-endian per Gaussian: true object id (-1 background)
//   gt/scene.json               primitives, inserted ranges, target / neighbour ids, up, rig kind
// File names are Camera::name + ".png". The ground truth of inserted Gaussian objects comes
// from the renderer (alpha > 0.5 of the object alone), the primitives' from ray casting.
#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vcar/concepts/renderer.hpp"
#include "vcar/core/error.hpp"
#include "vcar/io/atomic_file.hpp"
#include "vcar/io/cameras_json.hpp"
#include "vcar/io/colmap.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/transforms_json.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/object_prompts.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"
#include "vcar/synth/world_json.hpp"

namespace vcar::synth {

struct ExportOptions {
  bool render_images = true;                           // images/ and gt/eval_images/
  Eigen::Vector3f background = Eigen::Vector3f::Zero();
  int n_prompt_points = 3;
  // Objects to prompt besides the target (synth/object_prompts.hpp), by name: prompt.json gains
  // "objects", prompts.json is written, gt/scene.json names them. Empty: the target only.
  std::vector<NamedObject> objects;
};

namespace detail {
inline void make_dir(const std::filesystem::path& p) {
  std::error_code ec;
  std::filesystem::create_directories(p, ec);
  if (ec) throw Error("cannot create folder: " + ec.message(), p.string());
}
}  // namespace detail

// Returns the prompts of ExportOptions::objects (empty without them), to report the hidden ones.
template <Renderer R>
std::vector<PromptedObject> export_dataset(const std::filesystem::path& dir, const World& w, const Rig& rig,
                                           R& renderer, const ExportOptions& opt = {}) {
  static_assert(std::endian::native == std::endian::little, "gaussian_ids.bin is written little-endian");
  if (w.object_id.size() != w.scene.size()) throw Error("object_id and scene sizes differ", "world");
  if (rig.reference >= rig.train.size()) throw Error("reference view out of range", "rig");
  for (const char* sub : {"images", "masks", "gt/eval_images", "gt/silhouettes", "gt/visible"})
    detail::make_dir(dir / sub);
  io::write_ply(dir / "scene.ply", w.scene);
  io::write_cameras_json(dir / "cameras.json", rig.train);
  io::write_colmap_text(dir / "sparse" / "0", rig.train);
  io::write_transforms_json(dir / "transforms.json", rig.train);
  io::write_cameras_json(dir / "gt" / "eval_cameras.json", rig.eval);

  auto render_to = [&](const Camera& cam, const std::filesystem::path& p) {
    RenderRequest q;
    q.scene = &w.scene;
    q.camera = &cam;
    q.background = opt.background;
    io::write_png(p, to_8bit(renderer.render(q).rgb));
  };
  Mask reference_visible;
  for (std::size_t k = 0; k < rig.train.size(); ++k) {
    const Camera& cam = rig.train[k];
    const std::string file = cam.name + ".png";
    const Mask vis = visible_mask(w, cam, w.target_id, renderer);
    io::write_png(dir / "masks" / file, vis);
    io::write_png(dir / "gt" / "silhouettes" / file, silhouette_mask(w, cam, w.target_id, renderer));
    if (opt.render_images) render_to(cam, dir / "images" / file);
    if (k == rig.reference) reference_visible = vis;
  }
  for (const Camera& cam : rig.eval) {
    const std::string file = cam.name + ".png";
    io::write_png(dir / "gt" / "visible" / file, visible_mask(w, cam, w.target_id, renderer));
    io::write_png(dir / "gt" / "silhouettes" / file, silhouette_mask(w, cam, w.target_id, renderer));
    if (opt.render_images) render_to(cam, dir / "gt" / "eval_images" / file);
  }

  const Prompt prompt = prompt_points(reference_visible, rig.reference, opt.n_prompt_points,
                                      "reference view '" + rig.train[rig.reference].name + "'");
  nlohmann::json pj;
  pj["reference_view"] = rig.train[rig.reference].name;
  pj["reference_index"] = rig.reference;
  pj["points"] = nlohmann::json::array();
  for (const auto& p : prompt.points) pj["points"].push_back({static_cast<double>(p.x()), static_cast<double>(p.y())});
  pj["labels"] = prompt.point_labels;
  pj["target_id"] = w.target_id;
  const Eigen::Vector4f box = mask_box(reference_visible);
  pj["box"] = {box[0], box[1], box[2], box[3]};
  const std::vector<PromptedObject> objects = prompt_objects(w, rig, renderer, opt.objects, opt.n_prompt_points);
  if (!objects.empty()) {
    nlohmann::json all = nlohmann::json::array(), prompts = nlohmann::json::array();
    for (const PromptedObject& o : objects) {
      nlohmann::json e{{"name", o.name}, {"object_id", o.object_id}, {"reference_view", nullptr},
                       {"points", nlohmann::json::array()}, {"labels", nlohmann::json::array()}, {"box", nullptr}};
      if (o.visible) {
        const Eigen::Vector4f& b = *o.prompt.box;
        e["reference_view"] = rig.train[o.prompt.reference_view].name;
        for (const auto& p : o.prompt.points) e["points"].push_back({static_cast<double>(p.x()), static_cast<double>(p.y())});
        e["labels"] = o.prompt.point_labels;
        e["box"] = {b[0], b[1], b[2], b[3]};
        prompts.push_back({{"name", o.name}, {"reference_view", e["reference_view"]}, {"points", e["points"]},
                           {"point_labels", e["labels"]}, {"box", e["box"]}, {"object_id", o.object_id}});
      }
      all.push_back(std::move(e));
    }
    pj["objects"] = std::move(all);
    std::error_code ec;
    if (!prompts.empty()) io::write_json_file(dir / "prompts.json", prompts);
    else std::filesystem::remove(dir / "prompts.json", ec);  // none visible: no stale file of an earlier run
  }
  io::write_json_file(dir / "prompt.json", pj);

  nlohmann::json sj = world_to_json(w);
  sj["rig"] = rig.kind;
  if (!opt.objects.empty()) {
    sj["objects"] = nlohmann::json::array();
    for (const NamedObject& o : opt.objects) sj["objects"].push_back({{"name", o.name}, {"object_id", o.object_id}});
  }
  io::write_json_file(dir / "gt" / "scene.json", sj);
  io::atomic_write(dir / "gt" / "gaussian_ids.bin", [&](std::ostream& out) {
    for (int id : w.object_id) {
      const std::int32_t v = id;
      out.write(reinterpret_cast<const char*>(&v), sizeof v);
    }
  });
  return objects;
}

// The world of an exported dataset: gt/scene.json + scene.ply + gt/gaussian_ids.bin.
inline World load_world(const std::filesystem::path& dir) {
  const auto scene_json = dir / "gt" / "scene.json";
  World w = world_from_json(io::read_json_file(scene_json), scene_json.string());
  w.scene = io::read_ply(dir / "scene.ply");
  const auto ids_path = dir / "gt" / "gaussian_ids.bin";
  std::ifstream in(ids_path, std::ios::binary);
  if (!in) throw Error("cannot open file", ids_path.string());
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(ids_path, ec);
  if (ec || bytes != w.scene.size() * sizeof(std::int32_t))
    throw Error("expected " + std::to_string(w.scene.size()) + " int32 ids (one per Gaussian of scene.ply)",
                ids_path.string());
  std::vector<std::int32_t> ids(w.scene.size());
  in.read(reinterpret_cast<char*>(ids.data()), static_cast<std::streamsize>(bytes));
  if (!in) throw Error("short read", ids_path.string());
  w.object_id.assign(ids.begin(), ids.end());
  for (const auto& o : w.inserted)
    if (o.begin + o.count > w.scene.size()) throw Error("inserted range beyond the scene", scene_json.string());
  return w;
}

// The rig of an exported dataset: cameras.json (training), gt/eval_cameras.json, prompt.json.
inline Rig load_rig(const std::filesystem::path& dir) {
  Rig rig;
  rig.train = io::read_cameras_json(dir / "cameras.json");
  rig.eval = io::read_cameras_json(dir / "gt" / "eval_cameras.json");
  const auto pj = io::read_json_file(dir / "prompt.json");
  const auto sj = io::read_json_file(dir / "gt" / "scene.json");
  rig.kind = sj.value("rig", std::string{});
  const std::string ref = pj.value("reference_view", std::string{});
  rig.reference = rig.train.size();
  for (std::size_t k = 0; k < rig.train.size(); ++k) if (rig.train[k].name == ref) rig.reference = k;
  if (rig.reference == rig.train.size())
    throw Error("reference view '" + ref + "' is not a training camera", (dir / "prompt.json").string());
  return rig;
}

}  // namespace vcar::synth
