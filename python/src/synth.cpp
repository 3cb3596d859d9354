// vcar.synth (the synthetic world with exact ground truth, rigs, the oracle segmenter, datasets)
// and vcar.eval (the metrics of conventions §6).
#include <filesystem>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "common.hpp"
#include "segmenters.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/eval/aggregate.hpp"
#include "vcar/eval/selection_metrics.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/world.hpp"

namespace vcar::python {

namespace fs = std::filesystem;

namespace {

// The world's Gaussians lent to w.scene for the duration of a C++ call that reads them.
class WorldScene {
public:
  explicit WorldScene(WorldPy& w) : w_(&w), s_(&scene_from(w.scene)), use_(*s_) { std::swap(w_->w.scene, s_->g); }
  ~WorldScene() { std::swap(w_->w.scene, s_->g); }
  WorldScene(const WorldScene&) = delete;
  WorldScene& operator=(const WorldScene&) = delete;
  const synth::World& world() const { return w_->w; }

private:
  WorldPy* w_;
  Scene* s_;
  SceneUse use_;
};

std::shared_ptr<WorldPy> world_py(synth::World&& w) {
  auto out = std::make_shared<WorldPy>();
  out->scene = py::cast(Scene::from_cpp(std::move(w.scene)));
  w.scene = GaussianScene{};
  out->w = std::move(w);
  return out;
}

WorldPy& world_from(py::handle obj) {
  if (!py::isinstance<WorldPy>(obj)) throw Error("expected a vcar.synth.World", "world");
  return obj.cast<WorldPy&>();
}

const Camera& camera_arg(py::handle obj) {
  if (!py::isinstance<Camera>(obj)) throw Error("expected a vcar.Camera", "camera");
  const Camera& c = obj.cast<const Camera&>();
  c.validate();
  return c;
}

synth::OracleMode oracle_mode(const std::string& s) {
  if (s == "visible") return synth::OracleMode::visible;
  if (s == "silhouette") return synth::OracleMode::silhouette;
  if (s == "by_name") return synth::OracleMode::by_name;
  throw Error("unknown mode '" + s + "'; valid: by_name, visible, silhouette", "mode");
}

py::dict scores_dict(const eval::SelectionScores& s) {
  py::dict d;
  d["precision"] = s.precision;
  d["recall"] = s.recall;
  d["f1"] = s.f1;
  d["tp"] = s.tp;
  d["fp"] = s.fp;
  d["fn"] = s.fn;
  return d;
}

}  // namespace

void register_synth(py::module_& m, py::module_& synth, py::module_& ev) {
  (void)m;
  py::class_<WorldPy, std::shared_ptr<WorldPy>>(synth, "World", R"doc(
A synthetic world (synth/world.hpp): primitives with exact ground truth and their Gaussians
(`scene`, a vcar.Scene), the true object id of each Gaussian (-1: background or floater), the
target and the neighbour that touches it.)doc")
      .def_readonly("scene", &WorldPy::scene)
      .def_property_readonly("object_id",
                             [](py::object self) {
                               WorldPy& w = self.cast<WorldPy&>();
                               return py::array_t<int>(static_cast<py::ssize_t>(w.w.object_id.size()),
                                                       w.w.object_id.data(), self);
                             },
                             "int32 (N,) view: the true object of each Gaussian")
      .def_property_readonly("target_id", [](const WorldPy& w) { return w.w.target_id; })
      .def_property_readonly("neighbour_id", [](const WorldPy& w) { return w.w.neighbour_id; })
      .def_property_readonly("up", [](const WorldPy& w) { return vec3_array(w.w.up); })
      .def_property_readonly("seed", [](const WorldPy& w) { return w.w.seed; })
      .def_property_readonly("n_primitives", [](const WorldPy& w) { return w.w.primitives.size(); })
      .def("gaussians_of", [](const WorldPy& w, int id) { return index_array(w.w.gaussians_of(id)); }, py::arg("id"),
           "Indices (int64) of the Gaussians whose true id is `id` (the ideal selection for the target).")
      .def(
          "bounds",
          [](WorldPy& w, int id) {
            WorldScene ws(w);
            const auto [c, r] = ws.world().bounds(id);
            return py::make_tuple(vec3_array(c), r);
          },
          py::arg("id"), "(centre, radius) of a bounding sphere of object `id`.")
      .def(
          "visible_mask",
          [](const WorldPy& w, py::object camera, std::optional<int> id) {
            const Camera cam = camera_arg(camera);
            Mask mk;
            {
              py::gil_scoped_release nogil;
              mk = synth::visible_mask(w.w, cam, id.value_or(w.w.target_id));
            }
            return mask_array(mk);
          },
          py::arg("camera"), py::arg("id") = py::none(),
          "bool (H, W): where object `id` (default the target) is the nearest surface (ray cast).")
      .def(
          "silhouette_mask",
          [](const WorldPy& w, py::object camera, std::optional<int> id) {
            const Camera cam = camera_arg(camera);
            Mask mk;
            {
              py::gil_scoped_release nogil;
              mk = synth::silhouette_mask(w.w, cam, id.value_or(w.w.target_id));
            }
            return mask_array(mk);
          },
          py::arg("camera"), py::arg("id") = py::none(), "bool (H, W): where object `id` alone covers the pixel.")
      .def("__repr__", [](const WorldPy& w) {
        return "<vcar.synth.World: seed " + std::to_string(w.w.seed) + ", " + std::to_string(w.w.object_id.size()) +
               " Gaussians, " + std::to_string(w.w.primitives.size()) + " primitives, target " +
               std::to_string(w.w.target_id) + ">";
      });

  synth.def(
      "generate_world",
      [](std::uint64_t seed, std::size_t n_gaussians, std::optional<std::string> target_type, int n_distractors,
         float straddler_fraction, float needle_fraction, float floater_fraction) {
        synth::WorldParams wp;
        wp.seed = seed;
        wp.n_gaussians = n_gaussians;
        wp.n_distractors = n_distractors;
        wp.straddler_fraction = straddler_fraction;
        wp.needle_fraction = needle_fraction;
        wp.floater_fraction = floater_fraction;
        if (target_type) {
          const auto t = synth::primitive_type_from_string(*target_type);
          if (t != synth::PrimitiveType::sphere && t != synth::PrimitiveType::torus &&
              t != synth::PrimitiveType::cylinder && t != synth::PrimitiveType::box)
            throw Error("must be sphere, torus, cylinder or box", "target_type");
          wp.target_type = t;
        }
        synth::World w;
        {
          py::gil_scoped_release nogil;
          w = synth::generate_world(wp);
        }
        return world_py(std::move(w));
      },
      py::arg("seed") = 1, py::arg("n_gaussians") = 100000, py::arg("target_type") = py::none(),
      py::arg("n_distractors") = 2, py::arg("straddler_fraction") = 0.003f, py::arg("needle_fraction") = 0.005f,
      py::arg("floater_fraction") = 0.01f,
      "The world `vcar synth --seed S --gaussians N` builds: a target touching a neighbour on a table,\n"
      "distractors, straddling Gaussians, needles and floaters.");

  py::class_<synth::Rig>(synth, "Rig", "Training cameras (train, reference = the prompt view) and held-out cameras (eval).")
      .def_readonly("kind", &synth::Rig::kind)
      .def_readonly("train", &synth::Rig::train)
      .def_readonly("eval", &synth::Rig::eval)
      .def_readonly("reference", &synth::Rig::reference)
      .def("__repr__", [](const synth::Rig& r) {
        return "<vcar.synth.Rig " + r.kind + ": " + std::to_string(r.train.size()) + " training, " +
               std::to_string(r.eval.size()) + " held-out views>";
      });

  synth.def(
      "make_rig",
      [](const std::string& kind, py::object world, int width, int height, std::optional<float> hfov_deg, int n_train,
         int n_eval, float distance, float elevation_deg, std::uint64_t seed) {
        synth::RigParams rp;
        // The default field of view through make_intrinsics' own default, as `vcar synth` calls it:
        // there the compiler folds tan(30 deg) at compile time, which differs from a run-time tanf
        // by one ulp, and the cameras (and the dataset files) would differ in the last digit.
        rp.intrinsics = hfov_deg ? synth::make_intrinsics(width, height, *hfov_deg) : synth::make_intrinsics(width, height);
        rp.n_train = n_train;
        rp.n_eval = n_eval;
        rp.distance = distance;
        rp.elevation_deg = elevation_deg;
        rp.seed = seed;
        WorldScene ws(world_from(world));
        return synth::make_rig(kind == "360" ? "orbit" : kind, ws.world(), rp);
      },
      py::arg("kind"), py::arg("world"), py::arg("width") = 320, py::arg("height") = 240, py::arg("hfov_deg") = py::none(),
      py::arg("n_train") = 0, py::arg("n_eval") = 0, py::arg("distance") = 0.f, py::arg("elevation_deg") = 25.f,
      py::arg("seed") = 1,
      "Cameras around the target: forward (LLFF/NVOS-like, default 20 views), orbit or 360 (LERF-like,\n"
      "40), sparse (6), hemisphere (24); n_train / n_eval 0 take those defaults; hfov_deg None: 60.");

  synth.def(
      "export_dataset",
      [](const fs::path& folder, py::object world, const synth::Rig& rig, bool render_images) {
        WorldScene ws(world_from(world));
        synth::ExportOptions opt;
        opt.render_images = render_images;
        py::gil_scoped_release nogil;
        cpu::TiledRenderer renderer;
        synth::export_dataset(folder, ws.world(), rig, renderer, opt);
      },
      py::arg("folder"), py::arg("world"), py::arg("rig"), py::arg("render_images") = true,
      "Writes the dataset `vcar synth` writes (scene.ply, cameras, images, masks, prompt.json, gt/).");
  synth.def(
      "load_world",
      [](const fs::path& folder) {
        synth::World w;
        {
          py::gil_scoped_release nogil;
          w = synth::load_world(folder);
        }
        return world_py(std::move(w));
      },
      py::arg("folder"), "The world of a dataset written by `vcar synth` or export_dataset.");
  synth.def(
      "load_rig",
      [](const fs::path& folder) {
        py::gil_scoped_release nogil;
        return synth::load_rig(folder);
      },
      py::arg("folder"), "The rig of a dataset (cameras.json, gt/eval_cameras.json, prompt.json).");

  py::class_<OracleSegmenterPy>(synth, "OracleSegmenter", R"doc(
Exact masks of the world's target from ray casting, with seeded failure models (synth/
oracle_segmenter.hpp): mode "by_name" (visible in renders of the whole scene, the silhouette in
renders of a subset and in views named sss_...), "visible" or "silhouette"; p_drop (no mask),
p_swap (the neighbour's mask), dilate_px (> 0 dilates, < 0 erodes), jitter_px, n_blobs false
positives. Runs in C++ when given to vcar.segment (as `vcar segment --oracle`); also a callable
taking a request, and .mask(camera) for one view.)doc")
      .def(py::init([](py::object world, const std::string& mode, std::uint64_t seed, int dilate_px, int n_blobs,
                       float blob_radius_px, double p_drop, double p_swap, int jitter_px, const std::string& prefix) {
             WorldPy& w = world_from(world);
             if (!w.w.inserted.empty())
               throw Error("this world holds inserted Gaussian objects, which the Python oracle does not model", "world");
             synth::OracleParams p;
             p.mode = oracle_mode(mode);
             p.seed = seed;
             p.dilate_px = dilate_px;
             p.n_blobs = n_blobs;
             p.blob_radius_px = blob_radius_px;
             p.p_drop = p_drop;
             p.p_swap = p_swap;
             p.jitter_px = jitter_px;
             p.silhouette_prefix = prefix;
             OracleSegmenterPy o;
             o.world = world;
             o.seg.emplace(w.w, p);
             return o;
           }),
           py::arg("world"), py::arg("mode") = "by_name", py::arg("seed") = 1, py::arg("dilate_px") = 0,
           py::arg("n_blobs") = 0, py::arg("blob_radius_px") = 6.f, py::arg("p_drop") = 0.0, py::arg("p_swap") = 0.0,
           py::arg("jitter_px") = 0, py::arg("silhouette_prefix") = "sss_")
      .def("__call__", [](OracleSegmenterPy& o, SegmentationRequest& r) { return run_on_request(*o.seg, r); },
           py::arg("request"))
      .def(
          "mask",
          [](const OracleSegmenterPy& o, py::object camera, std::size_t frame, bool subset) -> py::object {
            const Camera cam = camera_arg(camera);
            std::optional<Mask> mk;
            {
              py::gil_scoped_release nogil;
              mk = o.seg->mask(cam, frame, subset);
            }
            return mk ? py::object(mask_array(*mk)) : py::object(py::none());
          },
          py::arg("camera"), py::arg("frame") = 0, py::arg("subset") = false,
          "The answer for one view: bool (H, W), or None when the failure model drops it.");

  synth.def(
      "prompt_points",
      [](py::object mask, std::size_t reference_view, int n_points) {
        const Mask mk = mask_from(mask, "mask");
        const Prompt p = synth::prompt_points(mk, reference_view, n_points);
        py::array_t<float> pts({static_cast<py::ssize_t>(p.points.size()), py::ssize_t{2}});
        for (std::size_t i = 0; i < p.points.size(); ++i) {
          pts.mutable_data()[i * 2] = p.points[i].x();
          pts.mutable_data()[i * 2 + 1] = p.points[i].y();
        }
        py::dict d;
        d["reference_view"] = p.reference_view;
        d["points"] = pts;
        d["point_labels"] = p.point_labels;
        return d;
      },
      py::arg("mask"), py::arg("reference_view") = 0, py::arg("n_points") = 3,
      "A prompt of positive points deep inside a visible mask (as prompt.json of a dataset).");

  // ---- vcar.eval -----------------------------------------------------------------------------
  ev.attr("ALPHA_DEFAULT") = eval::alpha_default;
  ev.attr("ALPHA_RELEASED") = eval::alpha_released;
  ev.def("band_width", &eval::band_width, py::arg("width"), py::arg("height"), py::arg("ratio") = 0.02,
         "d = max(1, round(ratio * image diagonal)), the band of the boundary metrics.");
  ev.def(
      "predicted_mask",
      [](py::object alpha, float a) {
        py::array arr = as_array(alpha, "alpha");
        if (arr.ndim() != 2) throw Error("must be (H, W), got " + shape_text(arr), "alpha");
        const ImageF A = float_image(arr, static_cast<int>(arr.shape(1)), static_cast<int>(arr.shape(0)), 1, "alpha");
        return mask_array(eval::predicted_mask(A, a));
      },
      py::arg("alpha"), py::arg("a") = eval::alpha_default, "alpha > a, as bool (H, W).");
  ev.def(
      "evaluate_mask",
      [](py::object pred, py::object gt, int d) {
        const Mask g = mask_from(gt, "gt");
        const Mask p = mask_from(pred, g.width, g.height, "pred");
        const eval::ViewMetrics v = eval::evaluate_mask(p, g, d);
        py::dict out;
        out["iou"] = v.iou;
        out["accuracy"] = v.accuracy;
        out["boundary_iou"] = v.boundary_iou;
        out["boundary_f1"] = v.boundary_f1;
        out["trimap_iou"] = v.trimap_iou;
        return out;
      },
      py::arg("pred"), py::arg("gt"), py::arg("d") = 0,
      "IoU, pixel accuracy, boundary IoU, boundary F1 and trimap IoU of a predicted mask against the\n"
      "ground truth (conventions §6); d <= 0: the default band width.");
  ev.def(
      "selection_scores",
      [](py::object selected, py::object truth, std::size_t n) {
        return scores_dict(eval::selection_scores(index_vector(selected, n, "selected"), index_vector(truth, n, "truth"), n));
      },
      py::arg("selected"), py::arg("truth"), py::arg("n"), "Per-Gaussian precision, recall, F1 of a selection.");
  ev.def(
      "weighted_selection_scores",
      [](py::object selected, py::object truth, py::object scene) {
        Scene& s = scene_from(scene);
        const auto sel = index_vector(selected, s.size(), "selected"), tru = index_vector(truth, s.size(), "truth");
        SceneUse use(s, false);
        return scores_dict(eval::weighted_selection_scores(sel, tru, use.scene()));
      },
      py::arg("selected"), py::arg("truth"), py::arg("scene"),
      "The same, each Gaussian weighted by opacity x its largest cross-section (eval/selection_metrics.hpp).");
}

}  // namespace vcar::python
