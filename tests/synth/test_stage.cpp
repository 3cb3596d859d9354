#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <unordered_map>
#include <vector>

#include <unistd.h>

#include "reference_renderer.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/stage.hpp"
#include "vcar/synth/stage_json.hpp"
#include "synth_test_util.hpp"

using namespace vcar::synth;
namespace fs = std::filesystem;

namespace {

using vcar_test::fresh_dir;

// A box of Gaussians on a grid (exact extents) whose long side, `length`, runs along the object's
// `up` axis from 0 to `length` (so its lowest point is the origin), 0.2 x 0.6 across (the 0.6
// along the next axis in x, y, z order after up's), plus 4 far floaters, 2 past each end.
vcar::GaussianScene column(const std::string& up, float length = 2.f) {
  const int a = up.back() - 'x', b = (a + 1) % 3, c = (a + 2) % 3;
  const float sign = up.front() == '-' ? -1.f : 1.f;
  vcar::GaussianScene g;
  const int nl = 41, nb = 13, nc = 5;  // 2665 on the grid: the 0.001 quantiles skip 2 floaters
  g.resize(nl * nb * nc + 4, 0);
  std::size_t i = 0;
  auto put = [&](float along, float across_b, float across_c) {
    Eigen::Vector3f x;
    x[a] = sign * along; x[b] = across_b; x[c] = across_c;
    g.set(i, x, Eigen::Vector3f::Constant(std::log(0.01f)), {1, 0, 0, 0}, 2.f + 0.001f * static_cast<float>(i));
    g.set_rgb(i, Eigen::Vector3f(0.2f + 0.5f * along / length, 0.4f, 0.6f));
    ++i;
  };
  for (int l = 0; l < nl; ++l)
    for (int m = 0; m < nb; ++m)
      for (int n = 0; n < nc; ++n)
        put(length * l / (nl - 1), -0.3f + 0.6f * m / (nb - 1), -0.1f + 0.2f * n / (nc - 1));
  for (float far : {-9.f, -8.f, length + 7.f, length + 8.f}) put(far, 0.f, 0.f);
  return g;
}

StageObject object(const std::string& name, const std::string& up, float height) {
  StageObject o;
  o.name = name;
  o.up = up;
  o.height = height;
  return o;
}

Stage still(std::vector<StageObject> objects) {  // no jitter: placements exact
  Stage s;
  s.objects = std::move(objects);
  s.yaw_jitter_deg = 0.f;
  s.position_jitter = 0.f;
  s.floor_gaussians = 2000;
  return s;
}

struct Box { Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo; };
// The world box of a column's grid (its Gaussians but the last 4, the floaters).
Box box_of(const World& w, int id) {
  Box b;
  for (const InsertedObject& o : w.inserted)
    if (o.object_id == id)
      for (std::size_t i = o.begin; i + 4 < o.begin + o.count; ++i) {
        b.lo = b.lo.cwiseMin(w.scene.mu(i));
        b.hi = b.hi.cwiseMax(w.scene.mu(i));
      }
  return b;
}

using vcar_test::same_bytes;
bool same_range(const vcar::GaussianScene& a, const vcar::GaussianScene& b, std::size_t begin, std::size_t end,
                bool means) {
  auto part = [&](const std::vector<float>& v, std::size_t per) {
    return std::vector<float>(v.begin() + static_cast<std::ptrdiff_t>(begin * per), v.begin() + static_cast<std::ptrdiff_t>(end * per));
  };
  bool ok = same_bytes(part(a.opacity_logit, 1), part(b.opacity_logit, 1)) && same_bytes(part(a.sh, 3), part(b.sh, 3));
  for (int d = 0; d < 3; ++d) {
    ok = ok && same_bytes(part(a.log_scale[d], 1), part(b.log_scale[d], 1));
    if (means) ok = ok && same_bytes(part(a.mean[d], 1), part(b.mean[d], 1));
  }
  return ok;
}

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::string error_of(const fs::path& file) {
  try {
    read_stage_file(file);
  } catch (const vcar::Error& e) {
    return e.what();
  }
  return "(no error)";
}

const fs::path shared_data = fs::path(VCAR_TEST_DATA_DIR) / ".." / ".." / ".." / "shared" / "data";

}  // namespace

TEST_CASE("up axes: the shortest turn to +z, exact") {
  for (const char* up : {"+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"}) {
    INFO(up);
    const Eigen::Matrix3f R = up_rotation(up);
    Eigen::Vector3f u = Eigen::Vector3f::Zero();
    u[up[std::strlen(up) - 1] - 'x'] = up[0] == '-' ? -1.f : 1.f;
    CHECK(R * u == Eigen::Vector3f::UnitZ());  // exact: entries are 0 and +-1
    CHECK(R.determinant() == 1.f);
    CHECK((R * R.transpose()).isIdentity(0.f));
  }
  // A COLMAP-like capture (up -y) faces the rigs' front: its +z (away from its cameras) ends along +y.
  CHECK(up_rotation("-y") * Eigen::Vector3f::UnitZ() == Eigen::Vector3f::UnitY());
  CHECK(up_rotation("-z") * Eigen::Vector3f::UnitX() == Eigen::Vector3f::UnitX());
  for (const char* bad : {"", "+", "w", "+w", "yy", "++y", "up"})
    CHECK_THROWS_WITH(up_rotation(bad, "objects[0].up"), Catch::Contains("objects[0].up") && Catch::Contains("bad up axis"));
}

TEST_CASE("objects stand upright on the floor at their size, position and yaw; floaters ignored") {
  for (const char* up : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    INFO("up " << up);
    StageObject o = object("a", up, 1.f);
    o.position = {0.4f, -0.2f};
    const std::vector<vcar::GaussianScene> scenes{column(up)};
    const World w = make_stage(still({o}), scenes, 1);
    const Box b = box_of(w, 1);
    // Its long side (2 units along `up`) is now vertical, 1 unit tall, from the floor up.
    CHECK(b.lo.z() == Approx(0.f).margin(1e-6));
    CHECK(b.hi.z() == Approx(1.f).epsilon(1e-5));
    // Scaled by 1/2: 0.1 x 0.3 across; the footprint centred on the position.
    const Eigen::Vector3f ext = b.hi - b.lo;
    CHECK(std::max(ext.x(), ext.y()) == Approx(0.3f).epsilon(1e-5));
    CHECK(std::min(ext.x(), ext.y()) == Approx(0.1f).epsilon(1e-5));
    CHECK(0.5f * (b.lo.x() + b.hi.x()) == Approx(0.4f).margin(1e-6));
    CHECK(0.5f * (b.lo.y() + b.hi.y()) == Approx(-0.2f).margin(1e-6));
    // The floaters kept their place relative to the object (nothing is dropped).
    CHECK(w.gaussians_of(1).size() == scenes[0].size());
  }
  SECTION("yaw turns about +z, counter-clockwise from above") {
    StageObject o = object("a", "-y", 1.f);  // the 0.6 side (its z) ends along +y ...
    const std::vector<vcar::GaussianScene> scenes{column("-y")};
    Box b = box_of(make_stage(still({o}), scenes, 1), 1);
    CHECK(b.hi.y() - b.lo.y() == Approx(0.3f).epsilon(1e-5));
    o.yaw_deg = 90.f;  // ... and after a quarter turn along x
    b = box_of(make_stage(still({o}), scenes, 1), 1);
    CHECK(b.hi.x() - b.lo.x() == Approx(0.3f).epsilon(1e-5));
    CHECK(b.hi.y() - b.lo.y() == Approx(0.1f).epsilon(1e-5));
  }
  SECTION("width and scale") {
    StageObject o = object("a", "-y", 0.f);
    o.width = 0.9f;  // the larger horizontal side, 0.6 units: scale 1.5
    const std::vector<vcar::GaussianScene> scenes{column("-y")};
    Box b = box_of(make_stage(still({o}), scenes, 1), 1);
    CHECK(b.hi.z() == Approx(3.f).epsilon(1e-5));
    o.width = 0.f;
    o.scale = 0.25f;
    b = box_of(make_stage(still({o}), scenes, 1), 1);
    CHECK(b.hi.z() == Approx(0.5f).epsilon(1e-5));
  }
  SECTION("a real capture: the donut, +z up, 0.4 wide") {
    StageObject o = object("donut", "+z", 0.f);
    o.width = 0.4f;
    o.file = fs::path(VCAR_TEST_DATA_DIR) / "donut.ply";
    Stage s = still({o});
    const World w = make_stage(s, 3);
    std::vector<float> z;
    for (vcar::Index i : w.gaussians_of(1)) z.push_back(w.scene.mu(i).z());
    std::sort(z.begin(), z.end());
    const float lowest = z[static_cast<std::size_t>(0.001 * (z.size() - 1))];
    CHECK(lowest == Approx(0.f).margin(1e-6));
    // Only the strays below the robust lowest point (a thousandth) sink into the floor.
    const auto below = std::count_if(z.begin(), z.end(), [](float v) { return v < -1e-6f; });
    CHECK(below > 0);
    CHECK(static_cast<double>(below) <= 0.001 * static_cast<double>(z.size()) + 1);
    CHECK(z[static_cast<std::size_t>(0.999 * (z.size() - 1))] < 0.5f * 0.4f);  // a flat ring
  }
}

TEST_CASE("same seed, same bytes; another seed moves the objects rigidly and redraws the floor, nothing else") {
  Stage s;
  s.objects = {object("a", "-y", 1.f), object("b", "+x", 0.5f)};
  s.objects[1].position = {0.5f, 0.f};
  s.floor_gaussians = 3000;
  const std::vector<vcar::GaussianScene> scenes{column("-y"), column("+x")};
  const World a = make_stage(s, scenes, 5);
  const int threads = vcar::max_threads();
  vcar::set_num_threads(1);
  const World b = make_stage(s, scenes, 5);
  vcar::set_num_threads(threads);
  REQUIRE(a.scene.size() == b.scene.size());
  CHECK(same_range(a.scene, b.scene, 0, a.scene.size(), true));
  CHECK(same_bytes(a.scene.rotation[0], b.scene.rotation[0]));
  CHECK(a.object_id == b.object_id);

  const World c = make_stage(s, scenes, 6);
  REQUIRE(c.scene.size() == a.scene.size());
  CHECK(c.object_id == a.object_id);
  CHECK(c.primitives.size() == 1);
  CHECK(c.primitives[0].params == a.primitives[0].params);  // the floor's extent: same
  const std::size_t n_floor = a.gaussians_of(0).size();
  CHECK(n_floor == 3000);
  CHECK_FALSE(same_range(a.scene, c.scene, 0, n_floor, true));  // the floor's Gaussians: redrawn
  for (const InsertedObject& o : a.inserted) {
    INFO("object " << o.object_id);
    // Same Gaussians (scales, opacity, colour), moved: the means differ ...
    CHECK(same_range(a.scene, c.scene, o.begin, o.begin + o.count, false));
    CHECK_FALSE(same_range(a.scene, c.scene, o.begin, o.begin + o.count, true));
    // ... by a rigid motion: distances kept, still standing on the floor, turned by a few degrees.
    float worst = 0.f;
    for (std::size_t i = o.begin + 1; i < o.begin + o.count; i += 7) {
      const float da = (a.scene.mu(i) - a.scene.mu(o.begin)).norm(), dc = (c.scene.mu(i) - c.scene.mu(o.begin)).norm();
      worst = std::max(worst, std::abs(da - dc));
    }
    CHECK(worst < 1e-5f);
    const Box ba = box_of(a, o.object_id), bc = box_of(c, o.object_id);
    CHECK(bc.lo.z() == Approx(0.f).margin(1e-6));
    CHECK(bc.hi.z() == Approx(ba.hi.z()).epsilon(1e-5));
    const Eigen::Vector3f ca = 0.5f * (ba.lo + ba.hi), cc = 0.5f * (bc.lo + bc.hi);
    const float width = o.object_id == 1 ? 0.3f : 0.15f;  // the footprints' larger sides
    CHECK((ca - cc).head<2>().norm() > 0.f);
    CHECK((ca - cc).head<2>().cwiseAbs().maxCoeff() <= 2.f * s.position_jitter * width * 1.01f);
  }
}

TEST_CASE("labels are exact: each object's Gaussians render to its ground truth, through the files") {
  // The donut in front of a column, partly hiding it from the forward rig.
  Stage s = still({object("column", "-y", 0.5f), object("donut", "+z", 0.f)});
  s.objects[1].width = 0.3f;
  s.objects[1].position = {0.f, -0.25f};
  s.objects[1].object_id = 7;
  s.target = "column";
  s.floor_gaussians = 4000;
  const std::vector<vcar::GaussianScene> scenes{column("-y"), vcar::io::read_scene(fs::path(VCAR_TEST_DATA_DIR) / "donut.ply")};
  const World w = make_stage(s, scenes, 2);
  CHECK(w.target_id == 1);
  CHECK(w.neighbour_id == 7);
  RigParams rp;
  rp.intrinsics = make_intrinsics(96, 72);
  rp.n_train = 4;
  rp.n_eval = 2;
  const Rig rig = forward_facing_rig(w, rp);
  synth_test::ReferenceRenderer renderer;
  const fs::path dir = fresh_dir("labels");
  ExportOptions opt;
  opt.objects = {{"column", 1}, {"donut", 7}};
  const std::vector<PromptedObject> prompts = export_dataset(dir, w, rig, renderer, opt);

  // The labels on disk select, for every object, exactly the Gaussians placed from its file.
  const World back = load_world(dir);
  REQUIRE(back.object_id.size() == w.scene.size());
  CHECK(back.gaussians_of(0).size() == 4000);
  CHECK(back.gaussians_of(1).size() == scenes[0].size());
  CHECK(back.gaussians_of(7).size() == scenes[1].size());
  const std::vector<vcar::Index> donut = back.gaussians_of(7);
  for (std::size_t k = 0; k < donut.size(); k += 97) {  // the donut's Gaussians, in file order
    CHECK(back.scene.opacity_logit[donut[k]] == scenes[1].opacity_logit[k]);  // soft edges kept
    CHECK(back.scene.log_scale[0][donut[k]] - scenes[1].log_scale[0][k] ==
          Approx(back.scene.log_scale[0][donut[0]] - scenes[1].log_scale[0][0]).margin(1e-5));
  }
  std::size_t hidden = 0;
  for (const vcar::Camera& cam : rig.train) {
    INFO(cam.name);
    const IdImage ids = raycast(back, cam, renderer);
    for (int id : {1, 7}) {
      // Rendered alone from the labels on disk, alpha > 0.5: the ground-truth silhouette.
      const std::vector<vcar::Index> mine = back.gaussians_of(id);
      vcar::RenderRequest q;
      q.scene = &back.scene;
      q.camera = &cam;
      q.subset = &mine;
      const vcar::RenderOutput r = renderer.render(q);
      const vcar::Mask sil = silhouette_mask(w, cam, id, renderer);
      std::size_t differ = 0, visible = 0, outside = 0;
      for (std::size_t k = 0; k < sil.data.size(); ++k) {
        differ += (r.alpha.data[k] > 0.5f) != (sil.data[k] != 0);
        visible += ids.id[k] == id;
        outside += ids.id[k] == id && !sil.data[k];
      }
      CHECK(differ == 0);
      CHECK(outside == 0);  // visible only where its silhouette is
      if (id == 1) hidden += vcar::synth::count(sil) - visible;
      if (id == 1) CHECK(vcar::io::read_mask(dir / "gt" / "silhouettes" / (cam.name + ".png")).data == sil.data);
    }
  }
  CHECK(hidden > 0);  // the donut hides part of the column

  // Prompts: the target's box on the reference view; each object's points inside its box.
  const auto pj = vcar::io::read_json_file(dir / "prompt.json");
  const vcar::Mask ref = vcar::io::read_mask(dir / "masks" / (rig.train[rig.reference].name + ".png"));
  const Eigen::Vector4f box = mask_box(ref);
  CHECK(pj.at("box") == nlohmann::json{box[0], box[1], box[2], box[3]});
  CHECK(pj.at("target_id") == 1);
  REQUIRE(pj.at("objects").size() == 2);
  REQUIRE(prompts.size() == 2);
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& o = pj["objects"][k];
    CHECK(o.at("name") == opt.objects[k].name);
    CHECK(o.at("object_id") == opt.objects[k].object_id);
    REQUIRE(prompts[k].visible);
    const auto b = o.at("box").get<std::vector<float>>();
    REQUIRE(b.size() == 4);
    CHECK(b[2] > b[0]);
    for (const auto& p : o.at("points")) {
      CHECK(p[0].get<float>() > b[0]);
      CHECK(p[0].get<float>() < b[2]);
      CHECK(p[1].get<float>() > b[1]);
      CHECK(p[1].get<float>() < b[3]);
    }
  }
  CHECK(pj["objects"][0].at("box") == pj.at("box"));
  const auto many = vcar::io::read_json_file(dir / "prompts.json");
  REQUIRE(many.is_array());
  REQUIRE(many.size() == 2);
  CHECK(many[1].at("name") == "donut");
  CHECK(many[1].at("object_id") == 7);
  CHECK(many[1].at("reference_view") == pj["objects"][1].at("reference_view"));
  CHECK(many[1].at("point_labels").size() == many[1].at("points").size());
  CHECK(vcar::io::read_json_file(dir / "gt" / "scene.json").at("objects")[1].at("name") == "donut");

  // The same seed writes the same files.
  const fs::path again = fresh_dir("labels_again");
  export_dataset(again, make_stage(s, scenes, 2), rig, renderer, opt);
  for (const char* f : {"scene.ply", "gt/gaussian_ids.bin", "prompt.json", "prompts.json", "gt/scene.json"})
    CHECK(file_bytes(dir / f) == file_bytes(again / f));
  fs::remove_all(dir);
  fs::remove_all(again);
}

TEST_CASE("stage files: relative paths, defaults, and errors naming the file and the field") {
  const fs::path dir = fresh_dir("files");
  fs::copy_file(fs::path(VCAR_TEST_DATA_DIR) / "donut.ply", dir / "d.ply");
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  const fs::path good = write("good.json", R"({"comment": "two donuts",
    "objects": [{"name": "a", "file": "d.ply", "width": 0.4},
                {"name": "b", "file": ")" + (dir / "d.ply").string() + R"(", "up": "-y", "yaw": 30,
                 "height": 0.2, "position": [1, -0.5], "id": 9, "comment": "absolute path"}],
    "target": "b", "floor": {"half_size": 3, "gaussians": 1000}, "rig": "orbit", "width": 64, "height": 48,
    "views": 3})");
  const StageFile sf = read_stage_file(good);
  REQUIRE(sf.stage.objects.size() == 2);
  const StageObject& a = sf.stage.objects[0];
  const StageObject& b = sf.stage.objects[1];
  CHECK(a.file == dir / "d.ply");  // relative to the stage file's folder
  CHECK(a.up == "+z");
  CHECK(a.width == 0.4f);
  CHECK(a.height == 0.f);
  CHECK(a.position == Eigen::Vector2f(0, 0));
  CHECK(a.object_id == 0);
  CHECK(b.up == "-y");
  CHECK(b.yaw_deg == 30.f);
  CHECK(b.height == 0.2f);
  CHECK(b.position == Eigen::Vector2f(1.f, -0.5f));
  CHECK(b.object_id == 9);
  CHECK(sf.stage.target == "b");
  CHECK(sf.stage.floor_half_size == 3.f);
  CHECK(sf.stage.floor_gaussians == 1000);
  CHECK(sf.rig == "orbit");
  CHECK((sf.width == 64 && sf.height == 48 && sf.views == 3));
  const World w = make_stage(sf.stage, 1);
  CHECK(w.target_id == 9);
  CHECK(w.primitives[0].params.x() == 3.f);
  CHECK(w.gaussians_of(0).size() == 1000);

  const std::string obj = R"("name": "a", "file": "d.ply")";
  const std::vector<std::pair<std::string, std::vector<std::string>>> bad = {
      {R"({"objects": [{)" + obj + R"(, "height": 1}], "colour": 1})", {"unknown key \"colour\"", "bad.json"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1, "hieght": 2}]})", {"objects[0] ('a')", "unknown key \"hieght\""}},
      {R"({"objects": [{"name": "a", "file": "nowhere.ply", "height": 1}]})", {"objects[0] ('a').file", "no such file", "nowhere.ply"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1, "up": "up"}]})", {"objects[0] ('a').up", "bad up axis 'up'"}},
      {R"({"objects": [{)" + obj + R"(, "height": 0}]})", {"objects[0] ('a').height", "must be > 0"}},
      {R"({"objects": [{)" + obj + R"(, "width": -1}]})", {"objects[0] ('a').width", "must be > 0"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1, "scale": 2}]})", {"objects[0] ('a')", "exactly one size"}},
      {R"({"objects": [{)" + obj + R"(}]})", {"objects[0] ('a')", "exactly one size"}},
      {R"({"objects": [{"file": "d.ply", "height": 1}]})", {"objects[0]", "missing \"name\""}},
      {R"({"objects": [{"name": "a b", "file": "d.ply", "height": 1}]})", {"objects[0].name", "letters, digits"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1}, {)" + obj + R"(, "height": 1}]})", {"objects[1].name", "two objects are named 'a'"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1, "id": 2}, {"name": "b", "file": "d.ply", "height": 1}]})", {"objects[1].id", "two objects have id 2"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1, "id": 0}]})", {"objects[0] ('a').id", "whole number"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1, "position": [1]}]})", {"objects[0] ('a').position", "[x, y]"}},
      {R"({"objects": [{)" + obj + R"(, "height": "tall"}]})", {"objects[0] ('a').height", "expected a number"}},
      {R"({"objects": []})", {"objects", "non-empty"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1}], "target": "c"})", {"target", "no object is named 'c'"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1}], "rig": "moon"})", {"rig", "unknown rig 'moon'"}},
      {R"({"objects": [{)" + obj + R"(, "height": 1}], "width": 64})", {"both \"width\" and \"height\""}},
      {R"({"objects": [{)" + obj + R"(, "height": 1}], "floor": {"size": 3}})", {"floor", "unknown key \"size\""}},
      {R"({"objects": [{)" + obj + R"(, "height": 1}], "floor": {"half_size": 0}})", {"floor.half_size", "must be > 0"}},
      {R"({"objects": [)", {"bad.json", "malformed JSON"}},
  };
  for (const auto& [text, wanted] : bad) {
    INFO(text);
    const std::string msg = error_of(write("bad.json", text));
    CHECK_THAT(msg, Catch::Contains((dir / "bad.json").string()));
    for (const std::string& w : wanted) CHECK_THAT(msg, Catch::Contains(w));
  }
  // make_stage refuses the same mistakes made in code.
  Stage s = still({object("a", "-y", 1.f)});
  const std::vector<vcar::GaussianScene> scenes{column("-y")};
  s.objects[0].scale = 2.f;
  CHECK_THROWS_WITH(make_stage(s, scenes, 1), Catch::Contains("exactly one positive size"));
  s.objects[0].scale = 0.f;
  s.objects[0].up = "sideways";
  CHECK_THROWS_WITH(make_stage(s, scenes, 1), Catch::Contains("stage.objects[0] ('a').up"));
  s.objects[0].up = "-y";
  s.target = "nobody";
  CHECK_THROWS_WITH(make_stage(s, scenes, 1), Catch::Contains("no object is named 'nobody'"));
  fs::remove_all(dir);
}

namespace {

// An example stage file of the repository (examples/stages/NAME), or nothing (a warning) when the
// shared captures it reads are not beside the repository.
std::optional<StageFile> example_stage(const char* name) {
  if (!fs::exists(shared_data / "biker.spz") || !fs::exists(shared_data / "donut.ply")) {
    WARN("SKIPPED: the shared data is not at " << shared_data.string() << " (the repository's sibling folder shared/)");
    return std::nullopt;
  }
  return read_stage_file(fs::path(VCAR_TEST_DATA_DIR) / ".." / ".." / "examples" / "stages" / name);
}

}  // namespace

TEST_CASE("the example stage: the three shared captures stand upright on the floor") {
  const auto stage = example_stage("three_objects.json");
  if (!stage) return;
  const StageFile& sf = *stage;
  const World w = make_stage(sf.stage, 1);
  REQUIRE(w.inserted.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    const StageObject& o = sf.stage.objects[k];
    INFO(o.name);
    std::vector<float> v[3];
    for (std::size_t i = w.inserted[k].begin; i < w.inserted[k].begin + w.inserted[k].count; ++i)
      for (int d = 0; d < 3; ++d) v[d].push_back(w.scene.mu(i)[d]);
    float ext[3];
    for (int d = 0; d < 3; ++d) {
      std::sort(v[d].begin(), v[d].end());
      ext[d] = v[d][static_cast<std::size_t>(0.999 * (v[d].size() - 1))] - v[d][static_cast<std::size_t>(0.001 * (v[d].size() - 1))];
    }
    CHECK(v[2][static_cast<std::size_t>(0.001 * (v[2].size() - 1))] == Approx(0.f).margin(1e-5));
    if (o.height > 0.f) {
      CHECK(ext[2] == Approx(o.height).epsilon(1e-4));
      CHECK(ext[2] > 1.5f * std::max(ext[0], ext[1]));  // the biker and the guitar stand upright
    } else {
      CHECK(std::max(ext[0], ext[1]) == Approx(o.width).epsilon(0.01));  // the yaw jitter turns its box
      CHECK(ext[2] < 0.5f * std::max(ext[0], ext[1]));  // the donut lies flat
    }
  }
}

namespace {

// The smallest distance between a mean of `a` and one of `b` (a grid of `cell` m over b's means:
// a pair closer than `cell` lies in neighbouring cells, so the answer is exact below `cell` and
// `cell` otherwise).
float nearest_between(const World& w, const InsertedObject& a, const InsertedObject& b, float cell) {
  std::unordered_map<std::int64_t, std::vector<Eigen::Vector3f>> grid;
  auto key = [&](const Eigen::Vector3i& c) {
    return (static_cast<std::int64_t>(c.x()) * 4096 + c.y()) * 4096 + c.z();
  };
  auto cell_of = [&](const Eigen::Vector3f& x) { return (x / cell).array().floor().cast<int>().matrix().eval(); };
  for (std::size_t i = b.begin; i < b.begin + b.count; ++i) grid[key(cell_of(w.scene.mu(i)))].push_back(w.scene.mu(i));
  float best = cell;
  for (std::size_t i = a.begin; i < a.begin + a.count; ++i) {
    const Eigen::Vector3f x = w.scene.mu(i);
    const Eigen::Vector3i c = cell_of(x);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == grid.end()) continue;
          for (const auto& y : it->second) best = std::min(best, (x - y).norm());
        }
  }
  return best;
}

}  // namespace

TEST_CASE("the example stage: the three captures stand apart, none inside a neighbour") {
  // The field's stage (benchmarks/bench_field): neighbours close enough to share a segmenter's
  // box, never one inside another, where a target's Gaussians would be hidden from every view.
  // Until 2026-12-06 the donut sat 6 cm inside the guitar's base (means 0.0-0.5 cm apart,
  // hundreds within 1 cm). Measured now (seeds 1 / 11): biker-guitar 1.4 / 2.5 cm, biker-donut
  // 5.4 / 4.7 cm, guitar-donut 9.1 / 7.0 cm (the nearest means).
  const auto stage = example_stage("three_objects.json");
  if (!stage) return;
  for (std::uint64_t seed : {1u, 11u}) {
    INFO("seed " << seed);
    const World w = make_stage(stage->stage, seed);
    REQUIRE(w.inserted.size() == 3);
    const float biker_guitar = nearest_between(w, w.inserted[0], w.inserted[1], 0.1f);
    const float biker_donut = nearest_between(w, w.inserted[0], w.inserted[2], 0.1f);
    const float guitar_donut = nearest_between(w, w.inserted[1], w.inserted[2], 0.1f);
    CHECK(biker_guitar > 0.01f);
    CHECK(biker_donut > 0.03f);
    CHECK(guitar_donut > 0.03f);
    CHECK(std::min({biker_guitar, biker_donut, guitar_donut}) < 0.06f);  // and close: one segmenter box can take in two
  }
}

TEST_CASE("the nine-donuts stage: the copies stand apart, none inside a neighbour") {
  // The stage's claim (its comment): centres 0.47 m apart, each copy's outermost Gaussians about
  // 0.215 m from its axis, so no two copies meet. For any Gaussians a of copy i and b of copy j,
  // |a - b| >= |c_i - c_j| - r_i - r_j on the floor plane (c: the copy's axis, r: its outermost
  // Gaussian's distance from it), so that bound > 0 for every pair proves it. Until 2026-12-06
  // the centres stood 0.39 m apart and the copies interpenetrated by 4-5 cm.
  const auto stage = example_stage("nine_donuts.json");
  if (!stage) return;
  const StageFile& sf = *stage;
  REQUIRE(sf.stage.objects.size() == 9);
  for (std::uint64_t seed : {1u, 11u}) {
    INFO("seed " << seed);
    const World w = make_stage(sf.stage, seed);
    REQUIRE(w.inserted.size() == 9);
    std::vector<Eigen::Vector2f> c(9);
    std::vector<float> r(9, 0.f);
    for (std::size_t k = 0; k < 9; ++k) {
      const auto& in = w.inserted[k];
      c[k] = w.bounds(in.object_id).first.head<2>();  // the axis: its robust box's middle (a ring's centre)
      for (std::size_t i = in.begin; i < in.begin + in.count; ++i)
        r[k] = std::max(r[k], (w.scene.mu(i).head<2>() - c[k]).norm());
    }
    float closest = INFINITY;
    for (std::size_t i = 0; i < 9; ++i)
      for (std::size_t j = i + 1; j < 9; ++j) closest = std::min(closest, (c[i] - c[j]).norm() - r[i] - r[j]);
    CHECK(closest > 0.f);
    CHECK(closest < 0.06f);  // and close: a few centimetres between neighbours (3.0 and 3.8 cm)
  }
}
