// The external segmenter protocol, end to end with examples/segmenters/colour_picker.py.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vcar/io/external_segmenter.hpp"

namespace fs = std::filesystem;
using vcar::io::ExternalSegmenter;
using vcar::io::split_command_line;

namespace {

const std::string picker = std::string(VCAR_TEST_DATA_DIR) + "/../../examples/segmenters/colour_picker.py";

// Frame k: columns x < 10 + 2k are red, the rest blue (so each frame's mask differs).
vcar::ImageRGB8 frame_image(std::size_t k, int w, int h) {
  vcar::ImageRGB8 img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool red = x < 10 + 2 * static_cast<int>(k);
      img(x, y, 0) = red ? 200 : 10;
      img(x, y, 2) = red ? 10 : 200;
    }
  return img;
}

struct Fixture {
  std::vector<vcar::Camera> cams;
  vcar::Prompt prompt;
  fs::path work = fs::temp_directory_path() / ("vcar-test-extseg-" + std::to_string(::getpid()));
  Fixture() {
    for (int k = 0; k < 3; ++k) {
      vcar::Intrinsics K{32, 24, 30.f, 31.f, 16.f, 12.f};
      cams.push_back(vcar::Camera::look_at({2.f * k, -1.f, -4.f}, {0, 0, 0}, {0, -1, 0}, K,
                                           "view_" + std::to_string(k)));
    }
    prompt.points = {{3.5f, 5.5f}};
    prompt.point_labels = {1};
    prompt.text = "the red part";
  }
  ~Fixture() { std::error_code ec; fs::remove_all(work, ec); }
  vcar::FrameSequence frames() const {
    vcar::FrameSequence f;
    f.cameras = cams;
    f.image = [](std::size_t k) { return frame_image(k, 32, 24); };
    return f;
  }
  vcar::io::ExternalSegmenterOptions options() const {
    vcar::io::ExternalSegmenterOptions o;
    o.work_dir = work;
    return o;
  }
};

std::string message_of(ExternalSegmenter& s, const vcar::FrameSequence& f, const vcar::Prompt& p) {
  try {
    vcar::segment_all(s, f, p);
  } catch (const vcar::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("split_command_line honours quotes and backslashes like a shell") {
  using V = std::vector<std::string>;
  CHECK(split_command_line("a b  c") == V{"a", "b", "c"});
  CHECK(split_command_line("  python3 'my script.py' --x \"a b\"") == V{"python3", "my script.py", "--x", "a b"});
  CHECK(split_command_line(R"(a\ b "q\"uote" 'it''s' "\$HOME" '\n')") == V{"a b", "q\"uote", "its", "$HOME", "\\n"});
  CHECK(split_command_line("x''") == V{"x"});
  CHECK(split_command_line("'' y") == V{"", "y"});
  CHECK(split_command_line("").empty());
  CHECK_THROWS_AS(split_command_line("a 'b"), vcar::Error);
  CHECK_THROWS_AS(split_command_line("a \"b"), vcar::Error);
  CHECK_THROWS_WITH(split_command_line("a\\", "--segmenter-cmd"), Catch::Contains("--segmenter-cmd"));
}

TEST_CASE("ExternalSegmenter runs the program and reads its masks") {
  Fixture fx;
  auto o = fx.options();
  o.keep_requests = true;
  ExternalSegmenter s("/usr/bin/python3 " + picker + " --skip 2", o);
  static_assert(vcar::Segmenter<ExternalSegmenter>);
  const auto masks = vcar::segment_all(s, fx.frames(), fx.prompt);
  REQUIRE(masks.size() == 3);
  CHECK(s.rounds() == 1);
  CHECK(s.failure() == ExternalSegmenter::Failure::none);
  for (std::size_t k = 0; k < 2; ++k) {
    REQUIRE(masks[k].has_value());
    CHECK(masks[k]->width == 32);
    CHECK(masks[k]->height == 24);
    std::size_t wrong = 0;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 32; ++x)
        wrong += ((*masks[k])(x, y) != 0) != (x < 10 + 2 * static_cast<int>(k));
    CHECK(wrong == 0);
  }
  CHECK_FALSE(masks[2].has_value());  // --skip 2: missing file = no mask

  // The request: frames, cameras.json in Inria layout (camera-to-world), prompt.json.
  const fs::path req = s.last_request_dir();
  CHECK(fs::exists(req / "frames" / "00002.png"));
  std::ifstream cj(req / "cameras.json");
  const auto cams = nlohmann::json::parse(cj);
  REQUIRE(cams.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    CHECK(cams[k]["img_name"] == ExternalSegmenter::frame_stem(k));
    CHECK(cams[k]["view"] == fx.cams[k].name);
    // position = camera centre; rotation rows r: R_c2w(r, c) = R_w(c, r).
    const Eigen::Vector3f eye(2.f * k, -1.f, -4.f);
    for (int d = 0; d < 3; ++d) CHECK(cams[k]["position"][d].get<float>() == Approx(eye[d]).margin(1e-5));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        CHECK(cams[k]["rotation"][r][c].get<float>() == Approx(fx.cams[k].R_w(c, r)).margin(1e-6));
    CHECK(cams[k]["fx"].get<float>() == Approx(30.f));
    CHECK(cams[k]["fy"].get<float>() == Approx(31.f));
  }
  std::ifstream pj(req / "prompt.json");
  const auto p = nlohmann::json::parse(pj);
  CHECK(p["points"][0][0].get<float>() == Approx(3.5f));
  CHECK(p["point_labels"][0] == 1);
  CHECK(p["text"] == "the red part");
  CHECK(p["box"].is_null());
  CHECK_FALSE(p.contains("boxes"));  // no boxes unless a caller sets them

  // Second round: a fresh directory and the round counter moves on.
  vcar::segment_all(s, fx.frames(), fx.prompt);
  CHECK(s.rounds() == 2);
  CHECK(s.last_request_dir() != req);
}

TEST_CASE("ExternalSegmenter removes the request directory after a good round") {
  Fixture fx;
  ExternalSegmenter s("/usr/bin/python3 " + picker, fx.options());
  vcar::segment_all(s, fx.frames(), fx.prompt);
  CHECK_FALSE(fs::exists(s.last_request_dir()));
}

TEST_CASE("ExternalSegmenter failures name the round and the frame") {
  Fixture fx;
  SECTION("non-zero exit") {
    ExternalSegmenter s("/usr/bin/python3 " + picker + " --fail 7", fx.options());
    const std::string msg = message_of(s, fx.frames(), fx.prompt);
    CHECK_THAT(msg, Catch::Contains("segmenter round 1") && Catch::Contains("status 7") &&
                        Catch::Contains("failing on purpose"));
    CHECK(s.failure() == ExternalSegmenter::Failure::exit_status);
    CHECK(fs::exists(s.last_request_dir()));  // kept for debugging
  }
  SECTION("timeout") {
    auto o = fx.options();
    o.timeout_s = 0.3;
    ExternalSegmenter s("/usr/bin/python3 " + picker + " --sleep 20", o);
    const std::string msg = message_of(s, fx.frames(), fx.prompt);
    CHECK_THAT(msg, Catch::Contains("timed out") && Catch::Contains("segmenter round 1"));
    CHECK(s.failure() == ExternalSegmenter::Failure::timeout);
  }
  SECTION("cancel") {
    auto o = fx.options();
    o.cancelled = [] { return true; };
    ExternalSegmenter s("/usr/bin/python3 " + picker + " --sleep 20", o);
    CHECK_THAT(message_of(s, fx.frames(), fx.prompt), Catch::Contains("interrupted"));
    CHECK(s.failure() == ExternalSegmenter::Failure::cancelled);
  }
  SECTION("wrong-size mask") {
    ExternalSegmenter s("/usr/bin/python3 " + picker + " --bad-size", fx.options());
    const std::string msg = message_of(s, fx.frames(), fx.prompt);
    CHECK_THAT(msg, Catch::Contains("frame 0") && Catch::Contains("view_0") && Catch::Contains("33x24"));
    CHECK(s.failure() == ExternalSegmenter::Failure::bad_mask);
  }
  SECTION("undecodable mask") {
    ExternalSegmenter s("/usr/bin/python3 " + picker + " --garbage", fx.options());
    const std::string msg = message_of(s, fx.frames(), fx.prompt);
    CHECK_THAT(msg, Catch::Contains("frame 0") && Catch::Contains("00000.png") && Catch::Contains("decode"));
    CHECK(s.failure() == ExternalSegmenter::Failure::bad_mask);
  }
  SECTION("program not found") {
    ExternalSegmenter s("/nonexistent/segmenter --x", fx.options());
    CHECK_THAT(message_of(s, fx.frames(), fx.prompt), Catch::Contains("/nonexistent/segmenter"));
    CHECK(s.failure() == ExternalSegmenter::Failure::start);
  }
  SECTION("empty command and bad timeout") {
    CHECK_THROWS_AS(ExternalSegmenter("   ", fx.options()), vcar::Error);
    auto o = fx.options();
    o.timeout_s = 0;
    CHECK_THROWS_WITH(ExternalSegmenter("x", o), Catch::Contains("timeout"));
  }
}

TEST_CASE("ExternalSegmenter reports progress: frames rendered, then masks written") {
  Fixture fx;
  auto o = fx.options();
  std::vector<vcar::io::ExternalProgress> seen;
  o.progress = [&](const vcar::io::ExternalProgress& p) { seen.push_back(p); };
  // Sleeps before writing, so the wait loop reports while no mask exists yet.
  ExternalSegmenter s("/usr/bin/python3 " + picker + " --sleep 0.6", o);
  const auto masks = vcar::segment_all(s, fx.frames(), fx.prompt);
  REQUIRE(masks.size() == 3);
  using Phase = vcar::io::ExternalProgress::Phase;
  std::vector<std::size_t> rendered;
  std::size_t running = 0;
  for (const auto& p : seen) {
    CHECK(p.round == 1);
    CHECK(p.frames == 3);
    if (p.phase == Phase::rendering) {
      CHECK(running == 0);  // every frame is rendered before the program starts
      rendered.push_back(p.done);
    } else {
      ++running;
      CHECK(p.done <= 3);
    }
  }
  CHECK(rendered == std::vector<std::size_t>{0, 1, 2});
  CHECK(running >= 2);  // about every 0.25 s while the program sleeps 0.6 s
  CHECK(seen[rendered.size()].done == 0);  // the first report of the running phase: no mask yet
}

namespace {
// The colour picker keeping its requests, and two prompts: red on frame 0, blue on frame 2 (x = 30).
struct TwoObjects {
  Fixture fx;
  ExternalSegmenter s{"/usr/bin/python3 " + picker, kept(fx)};
  vcar::Prompt red = fx.prompt, blue = with_point(fx.prompt, 30.5f, 5.5f, 2);
  static vcar::io::ExternalSegmenterOptions kept(const Fixture& f) {
    auto o = f.options();
    o.keep_requests = true;
    return o;
  }
  static vcar::Prompt with_point(vcar::Prompt p, float x, float y, std::size_t frame) {
    p.points = {{x, y}};
    p.reference_view = frame;
    return p;
  }
};
}  // namespace

TEST_CASE("ExternalSegmenter::segment_objects: every object in one request, masks/<name>/") {
  TwoObjects t;
  Fixture& fx = t.fx;
  ExternalSegmenter& s = t.s;
  const vcar::Prompt &red = t.red, &blue = t.blue;
  std::vector<std::vector<std::optional<vcar::Mask>>> got(2, std::vector<std::optional<vcar::Mask>>(3));
  std::vector<std::pair<std::size_t, std::size_t>> order;
  s.segment_objects(fx.frames(), {{"red", red}, {"blue", blue}}, [&](std::size_t k, std::size_t q, const vcar::Mask* m) {
    order.emplace_back(k, q);
    if (m) got[q][k] = *m;
  });
  CHECK(order == std::vector<std::pair<std::size_t, std::size_t>>{{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 0}, {2, 1}});
  for (std::size_t k = 0; k < 3; ++k) {
    REQUIRE(got[0][k]);
    REQUIRE(got[1][k]);
    std::size_t wrong = 0;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 32; ++x) {
        const bool is_red = x < 10 + 2 * static_cast<int>(k);
        wrong += ((*got[0][k])(x, y) != 0) != is_red;
        wrong += ((*got[1][k])(x, y) != 0) == is_red;
      }
    CHECK(wrong == 0);
  }
  const fs::path req = s.last_request_dir();
  CHECK(fs::exists(req / "masks" / "red" / "00000.png"));
  CHECK(fs::exists(req / "masks" / "blue" / "00002.png"));
  std::ifstream pj(req / "prompt.json");
  const auto p = nlohmann::json::parse(pj);
  REQUIRE(p["objects"].size() == 2);
  CHECK(p["objects"][1]["name"] == "blue");
  CHECK(p["objects"][1]["frame"] == 2);
  CHECK(p["objects"][1]["points"][0][0].get<float>() == Approx(30.5f));
  CHECK(p["points"][0][0].get<float>() == Approx(3.5f));  // the top level: the first object's prompt

  auto bad = [&](const std::string& name) {
    try {
      s.segment_objects(fx.frames(), {{name, red}}, [](std::size_t, std::size_t, const vcar::Mask*) {});
    } catch (const vcar::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK_THAT(bad("../x"), Catch::Contains("not a folder name"));
  CHECK_THAT(bad(""), Catch::Contains("not a folder name"));
}

TEST_CASE("ExternalSegmenter::segment_objects: a batched round asks each object about its own frames") {
  // red: frames 0-1 (prompt on frame 0); blue: frame 2 alone (prompt on it, at x = 30).
  TwoObjects t;
  Fixture& fx = t.fx;
  ExternalSegmenter& s = t.s;
  const vcar::Prompt &red = t.red, &blue = t.blue;
  std::vector<std::pair<std::size_t, std::size_t>> order;
  std::vector<std::optional<vcar::Mask>> got(3);
  s.segment_objects(fx.frames(), {{"red", red, 0, 2}, {"blue", blue, 2, 1}},
                    [&](std::size_t k, std::size_t q, const vcar::Mask* m) {
                      order.emplace_back(k, q);
                      if (m) got[k] = *m;
                    });
  CHECK(order == std::vector<std::pair<std::size_t, std::size_t>>{{0, 0}, {1, 0}, {2, 1}});
  REQUIRE(got[0]);
  REQUIRE(got[2]);
  CHECK((*got[0])(0, 0) != 0);   // red at x = 0 on frame 0
  CHECK((*got[2])(31, 0) != 0);  // blue at x = 31 on frame 2
  CHECK((*got[2])(0, 0) == 0);
  const fs::path req = s.last_request_dir();
  CHECK(fs::exists(req / "masks" / "red" / "00001.png"));
  CHECK_FALSE(fs::exists(req / "masks" / "red" / "00002.png"));  // outside red's frames: not asked
  CHECK_FALSE(fs::exists(req / "masks" / "blue" / "00000.png"));
  std::ifstream pj(req / "prompt.json");
  const auto p = nlohmann::json::parse(pj);
  CHECK(p["objects"][0]["frames"] == nlohmann::json::array({0, 2}));
  CHECK(p["objects"][1]["frames"] == nlohmann::json::array({2, 1}));
  // A range past the last frame, or a prompt frame outside the object's frames: errors.
  auto bad = [&](ExternalSegmenter::Object ob) {
    try {
      s.segment_objects(fx.frames(), {ob}, [](std::size_t, std::size_t, const vcar::Mask*) {});
    } catch (const vcar::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK_THAT(bad({"red", red, 1, 5}), Catch::Contains("frames out of range"));
  CHECK_THAT(bad({"red", red, 4, 1}), Catch::Contains("first frame out of range"));
  CHECK_THAT(bad({"blue", blue, 0, 2}), Catch::Contains("prompt frame outside its frames"));
}

TEST_CASE("ExternalSegmenter writes one box per frame to prompt.json when given boxes") {
  Fixture fx;
  auto o = fx.options();
  o.keep_requests = true;
  ExternalSegmenter s("/usr/bin/python3 " + picker, o);
  std::vector<std::string> asked;  // the frames' views, in the order asked
  s.set_boxes([&](std::size_t k, const vcar::Camera& c) -> std::optional<Eigen::Vector4f> {
    asked.push_back(c.name);
    if (k == 1) return std::nullopt;  // out of view
    return Eigen::Vector4f(1.5f + static_cast<float>(k), 2.f, 20.f, 22.25f);
  });
  vcar::segment_all(s, fx.frames(), fx.prompt);
  CHECK(asked == std::vector<std::string>{"view_0", "view_1", "view_2"});
  std::ifstream pj(s.last_request_dir() / "prompt.json");
  const auto p = nlohmann::json::parse(pj);
  REQUIRE(p["boxes"].size() == 3);
  CHECK(p["boxes"][0] == nlohmann::json{1.5, 2.0, 20.0, 22.25});
  CHECK(p["boxes"][1].is_null());
  CHECK(p["boxes"][2] == nlohmann::json{3.5, 2.0, 20.0, 22.25});
}
