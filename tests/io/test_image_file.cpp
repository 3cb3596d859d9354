#include <catch2/catch.hpp>

#include <cstdint>

#include "io_test_util.hpp"
#include "vcar/io/image_file.hpp"

using vcar_test::TempDir;
using vcar_test::require_error;
using vcar_test::write_bytes;

namespace {

// A minimal PNG encoder written here, independent of stb: stored (uncompressed) deflate blocks.
std::uint32_t crc32(const std::string& s) {
  std::uint32_t c = 0xffffffffu;
  for (unsigned char b : s) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}
void be32(std::string& s, std::uint32_t v) {
  for (int k = 3; k >= 0; --k) s.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
}
void chunk(std::string& png, const std::string& type, const std::string& data) {
  be32(png, static_cast<std::uint32_t>(data.size()));
  const std::string td = type + data;
  png += td;
  be32(png, crc32(td));
}
// rows: already-serialised scanlines without the filter byte.
std::string make_png(int w, int h, int bit_depth, int colour_type, const std::vector<std::string>& rows,
                     const std::string& palette = {}) {
  std::string raw;
  for (const auto& r : rows) { raw.push_back(0); raw += r; }
  std::string z = "\x78\x01";
  for (std::size_t off = 0; off < raw.size() || off == 0; off += 65535) {
    const std::size_t len = std::min<std::size_t>(65535, raw.size() - off);
    z.push_back(off + len >= raw.size() ? 1 : 0);
    z.push_back(static_cast<char>(len & 0xff)); z.push_back(static_cast<char>(len >> 8));
    z.push_back(static_cast<char>(~len & 0xff)); z.push_back(static_cast<char>((~len >> 8) & 0xff));
    z += raw.substr(off, len);
    if (off + len >= raw.size()) break;
  }
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) { a = (a + c) % 65521; b = (b + a) % 65521; }
  be32(z, (b << 16) | a);
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string ihdr;
  be32(ihdr, static_cast<std::uint32_t>(w)); be32(ihdr, static_cast<std::uint32_t>(h));
  ihdr.push_back(static_cast<char>(bit_depth)); ihdr.push_back(static_cast<char>(colour_type));
  ihdr.append(3, '\0');
  chunk(png, "IHDR", ihdr);
  if (!palette.empty()) chunk(png, "PLTE", palette);
  chunk(png, "IDAT", z);
  chunk(png, "IEND", "");
  return png;
}

}  // namespace

TEST_CASE("8-bit PNG round trip, 1/3/4 channels, and RGB reading") {
  TempDir tmp;
  for (int ch : {1, 3, 4}) {
    vcar::Image<std::uint8_t> img(5, 3, ch);
    for (std::size_t k = 0; k < img.data.size(); ++k) img.data[k] = static_cast<std::uint8_t>(k * 17 % 256);
    const auto p = tmp / ("c" + std::to_string(ch) + ".png");
    vcar::io::write_png(p, img);
    int w, h, n;
    stbi_uc* px = stbi_load(p.string().c_str(), &w, &h, &n, 0);
    REQUIRE(px);
    CHECK(w == 5); CHECK(h == 3); CHECK(n == ch);
    CHECK(std::vector<std::uint8_t>(px, px + img.data.size()) == img.data);
    stbi_image_free(px);
    const auto rgb = vcar::io::read_image_rgb8(p);
    REQUIRE(rgb.channels == 3);
    CHECK(rgb(4, 2, 0) == img(4, 2, 0));
    CHECK(rgb(4, 2, 2) == img(4, 2, ch == 1 ? 0 : 2));
  }
  vcar::Image<std::uint8_t> two(2, 2, 2);
  require_error([&] { vcar::io::write_png(tmp / "two.png", two); }, {"two.png", "channels"});
  CHECK(!std::filesystem::exists(tmp / "two.png"));
}

TEST_CASE("float images are clamped and rounded to 8 bits") {
  TempDir tmp;
  vcar::ImageF f(3, 1, 1);
  f.data = {-0.5f, 0.5f, 2.f};
  vcar::io::write_png(tmp / "f.png", f);
  const auto m = vcar::io::read_image_rgb8(tmp / "f.png");
  CHECK(m(0, 0) == 0);
  CHECK(m(1, 0) == 128);  // round(127.5)
  CHECK(m(2, 0) == 255);
}

TEST_CASE("masks: 8-bit, 16-bit, paletted, RGBA; foreground from half range") {
  TempDir tmp;
  SECTION("8-bit grey: >= 128 is foreground") {
    vcar::Mask src(4, 2, 1);
    src.data = {0, 1, 127, 200, 128, 0, 255, 0};
    vcar::io::write_png(tmp / "m.png", src);
    const auto m = vcar::io::read_mask(tmp / "m.png", 4, 2);
    CHECK(m.channels == 1);
    CHECK(m.data == std::vector<std::uint8_t>{0, 0, 0, 255, 255, 0, 255, 0});
  }
  SECTION("8-bit grey holding only 0 and 1: a 0/1 label mask") {
    vcar::Mask src(3, 1, 1);
    src.data = {0, 1, 1};
    vcar::io::write_png(tmp / "l.png", src);
    CHECK(vcar::io::read_mask(tmp / "l.png").data == std::vector<std::uint8_t>{0, 255, 255});
  }
  SECTION("16-bit grey: >= 32768 is foreground") {
    std::string r0, r1;
    for (std::uint16_t v : {0, 1, 32767}) { r0.push_back(static_cast<char>(v >> 8)); r0.push_back(static_cast<char>(v & 0xff)); }
    for (std::uint16_t v : {65535, 0, 32768}) { r1.push_back(static_cast<char>(v >> 8)); r1.push_back(static_cast<char>(v & 0xff)); }
    write_bytes(tmp / "m16.png", make_png(3, 2, 16, 0, {r0, r1}));
    const auto m = vcar::io::read_mask(tmp / "m16.png", 3, 2);
    CHECK(m.data == std::vector<std::uint8_t>{0, 0, 0, 255, 0, 255});
  }
  SECTION("JPEG mask: compression noise around the edge is not foreground") {
    // A white square on black, JPEG at low quality: ringing puts small nonzero values in the
    // background; the half-range threshold gives back the square.
    vcar::Image<std::uint8_t> img(32, 32, 1, 0);
    for (int y = 5; y < 21; ++y) for (int x = 5; x < 21; ++x) img(x, y, 0) = 255;  // across 8x8 blocks
    REQUIRE(stbi_write_jpg((tmp / "m.jpg").string().c_str(), 32, 32, 1, img.data.data(), 50));
    const auto raw = vcar::io::read_image_rgb8(tmp / "m.jpg");
    std::size_t noisy = 0;  // background pixels the old "nonzero" rule would have counted
    for (int y = 0; y < 32; ++y) for (int x = 0; x < 32; ++x) noisy += img(x, y, 0) == 0 && raw(x, y, 0) != 0;
    REQUIRE(noisy > 0);
    const auto m = vcar::io::read_mask(tmp / "m.jpg", 32, 32);
    std::size_t wrong = 0;
    for (int y = 0; y < 32; ++y) for (int x = 0; x < 32; ++x) wrong += (m(x, y, 0) != 0) != (img(x, y, 0) != 0);
    CHECK(wrong == 0);
  }
  SECTION("paletted (DAVIS style: index 0 black, others coloured)") {
    const std::string pal("\x00\x00\x00\x80\x00\x00\x00\x80\x00", 9);
    write_bytes(tmp / "mp.png", make_png(3, 1, 8, 3, {std::string("\x00\x01\x02", 3)}, pal));
    const auto m = vcar::io::read_mask(tmp / "mp.png");
    CHECK(m.width == 3);
    CHECK(m.data == std::vector<std::uint8_t>{0, 255, 255});
  }
  SECTION("paletted: by index (conventions §4), whatever the colours") {
    // Index 0 white, index 1 black (a writer's padding colour), index 2 red: by colour the
    // mask would read {255, 0, 255}; by index it is {0, 255, 255}.
    const std::string pal("\xff\xff\xff\x00\x00\x00\xff\x00\x00", 9);
    write_bytes(tmp / "mi.png", make_png(3, 1, 8, 3, {std::string("\x00\x01\x02", 3)}, pal));
    CHECK(vcar::io::read_mask(tmp / "mi.png").data == std::vector<std::uint8_t>{0, 255, 255});
    // 4 bits per index, eight pixels in one row (indices 0 1 2 0 1 2 0 0), the same palette.
    write_bytes(tmp / "m4.png", make_png(8, 1, 4, 3, {std::string("\x01\x20\x12\x00", 4)}, pal));
    CHECK(vcar::io::read_mask(tmp / "m4.png").data == std::vector<std::uint8_t>{0, 255, 255, 0, 255, 255, 0, 0});
  }
  SECTION("RGBA: opaque black background is background; black-only colour uses alpha") {
    vcar::Image<std::uint8_t> a(2, 1, 4);
    a.data = {0, 0, 0, 255, 0, 200, 0, 255};
    vcar::io::write_png(tmp / "a.png", a);
    CHECK(vcar::io::read_mask(tmp / "a.png").data == std::vector<std::uint8_t>{0, 255});
    a.data = {0, 0, 0, 255, 0, 9, 0, 255};  // dark colour: background, and alpha is not used
    vcar::io::write_png(tmp / "c.png", a);
    CHECK(vcar::io::read_mask(tmp / "c.png").data == std::vector<std::uint8_t>{0, 0});
    a.data = {0, 0, 0, 0, 0, 0, 0, 255};
    vcar::io::write_png(tmp / "b.png", a);
    CHECK(vcar::io::read_mask(tmp / "b.png").data == std::vector<std::uint8_t>{0, 255});
  }
  SECTION("JPEG") {
    vcar::Image<std::uint8_t> img(16, 16, 3, 0);
    for (int y = 0; y < 16; ++y) for (int x = 8; x < 16; ++x) for (int c = 0; c < 3; ++c) img(x, y, c) = 255;
    REQUIRE(stbi_write_jpg((tmp / "j.jpg").string().c_str(), 16, 16, 3, img.data.data(), 95));
    const auto rgb = vcar::io::read_image_rgb8(tmp / "j.jpg");
    CHECK(rgb.width == 16);
    CHECK(rgb(12, 8, 1) > 200);
    CHECK(rgb(2, 8, 1) < 50);
  }
  SECTION("wrong size and unreadable files") {
    vcar::io::write_png(tmp / "m.png", vcar::Mask(4, 2, 1));
    require_error([&] { vcar::io::read_mask(tmp / "m.png", 5, 2); }, {"m.png", "4 x 2", "5 x 2"});
    write_bytes(tmp / "junk.png", "not a png at all");
    require_error([&] { vcar::io::read_mask(tmp / "junk.png"); }, {"junk.png"});
    require_error([&] { vcar::io::read_image_rgb8(tmp / "none.jpg"); }, {"none.jpg"});
  }
}

TEST_CASE("write_image: PNG or JPEG by extension, others refused") {
  TempDir tmp;
  vcar::Image<std::uint8_t> img(16, 8, 3, 0);
  for (int y = 0; y < 8; ++y) for (int x = 8; x < 16; ++x) for (int c = 0; c < 3; ++c) img(x, y, c) = 250;
  auto head = [](const std::filesystem::path& f) {
    std::ifstream in(f, std::ios::binary);
    std::string h(3, '\0');
    in.read(h.data(), 3);
    return h;
  };
  vcar::io::write_image(tmp / "a.jpg", img);
  vcar::io::write_image(tmp / "b.JPEG", img);
  vcar::io::write_image(tmp / "c.png", img);
  CHECK(head(tmp / "a.jpg") == std::string("\xff\xd8\xff", 3));  // JPEG SOI marker
  CHECK(head(tmp / "b.JPEG") == std::string("\xff\xd8\xff", 3));
  CHECK(head(tmp / "c.png") == std::string("\x89PN", 3));
  const auto back = vcar::io::read_image_rgb8(tmp / "a.jpg");
  CHECK(back.width == 16);
  CHECK(back(12, 4, 0) > 200);
  CHECK(back(3, 4, 0) < 50);
  require_error([&] { vcar::io::write_image(tmp / "d.bmp", img); }, {"d.bmp", ".bmp"});
  CHECK_FALSE(std::filesystem::exists(tmp / "d.bmp"));
  vcar::Image<std::uint8_t> rgba(2, 2, 4, 0);
  require_error([&] { vcar::io::write_jpg(tmp / "e.jpg", rgba); }, {"e.jpg", "channels"});
}
