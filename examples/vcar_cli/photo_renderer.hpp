#pragma once
// PhotoRenderer: `vcar segment --images`.
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "cli_common.hpp"
#include "vcar/backends/cpu/tiled_renderer.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/io/image_file.hpp"

namespace vcar::cli {

// The training views' photographs stand in for renders of the whole scene (the coarse round);
// renders of subsets (SSS views of G_coarse, the fine round) and unknown cameras go to the
// CPU renderer. Files are matched to views up front, so a missing image fails before any work.
class PhotoRenderer {
public:
  PhotoRenderer(cpu::TiledRenderer& inner, const std::filesystem::path& dir, const std::vector<Camera>& cams)
      : inner_(&inner) {
    if (!std::filesystem::is_directory(dir)) throw CliError(exit_bad_input, "not a directory", dir.string() + " (--images)");
    for (const Camera& c : cams) {
      const std::filesystem::path f = find_image(dir, c.name);
      if (f.empty())
        throw CliError(exit_bad_input, "no image for view '" + c.name + "' (tried the name with and without "
                                       ".png/.jpg/.jpeg)", dir.string() + " (--images)");
      files_[c.name] = f;
    }
  }

  RenderOutput render(const RenderRequest& q) {
    const auto it = files_.find(q.camera->name);
    if (q.subset || q.log_scale || it == files_.end()) return inner_->render(q);
    const ImageRGB8 img = io::read_image_rgb8(it->second);
    const Camera& c = *q.camera;
    if (img.width != c.width || img.height != c.height)
      throw CliError(exit_bad_input, "image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                                         ", view '" + c.name + "' is " + std::to_string(c.width) + "x" +
                                         std::to_string(c.height) + " (images are not resized)",
                     it->second.string());
    RenderOutput out;
    out.rgb = ImageF(img.width, img.height, 3);
    for (std::size_t k = 0; k < img.data.size(); ++k) out.rgb.data[k] = static_cast<float>(img.data[k]) / 255.f;
    out.alpha = ImageF(img.width, img.height, 1, 1.f);
    if (q.want_depth) out.depth = inner_->render(q).depth;
    return out;
  }

  static std::filesystem::path find_image(const std::filesystem::path& dir, const std::string& name) {
    std::error_code ec;
    const std::filesystem::path direct = dir / name;
    if (std::filesystem::is_regular_file(direct, ec)) return direct;
    const std::string stem = std::filesystem::path(name).stem().string();
    for (const char* ext : {".png", ".jpg", ".jpeg", ".PNG", ".JPG", ".JPEG"}) {
      for (const std::string& base : {name, stem}) {
        const std::filesystem::path f = dir / (base + ext);
        if (std::filesystem::is_regular_file(f, ec)) return f;
      }
    }
    return {};
  }

private:
  cpu::TiledRenderer* inner_;
  std::unordered_map<std::string, std::filesystem::path> files_;
};
static_assert(Renderer<PhotoRenderer>);


}  // namespace vcar::cli
