// WebAssembly build only: emscripten has no zlib or zstd here (its zlib port is downloaded at
// build time; zstd has none). The page inflates gzip SPZ (v2, v3) with the browser's
// DecompressionStream before handing it over, so read_scene never meets gzip and the zlib entry
// points vcar's SPZ reader names answer with errors. SPZ v4's zstd streams are decompressed by
// fzstd (npm, MIT), which the worker loads as `self.fzstd` (build.sh copies it to
// dist/vendor/fzstd/): ZSTD_decompress below hands each stream to it, so vcar's own SPZ reader,
// with all its checks, reads v4 in the browser as it does natively.
#include <cstddef>

#include <emscripten.h>
#include <zlib.h>
#include <zstd.h>

// Decompresses src[0, n) into dst[0, cap) with globalThis.fzstd; the byte count, or a negative
// code: -2 no decoder loaded, -3 the decoder failed (corrupt stream), -4 more than cap bytes.
EM_JS(int, vcar_fzstd_decompress, (void* dst, int cap, const void* src, int n), {
  const z = globalThis.fzstd;
  if (!z || typeof z.decompress !== 'function') return -2;
  let out;
  try {
    out = z.decompress(HEAPU8.slice(src, src + n));
  } catch (e) {
    return -3;
  }
  if (out.length > cap) return -4;
  HEAPU8.set(out, dst);
  return out.length;
});

namespace {
// zstd's convention: error codes are the largest size_t values.
constexpr std::size_t error_code(int code) { return static_cast<std::size_t>(0) - static_cast<std::size_t>(-code); }
}  // namespace

extern "C" {
int inflateInit2_(z_streamp, int, const char*, int) { return Z_VERSION_ERROR; }
int inflate(z_streamp, int) { return Z_STREAM_ERROR; }
int inflateEnd(z_streamp) { return Z_OK; }
size_t ZSTD_decompress(void* dst, size_t cap, const void* src, size_t n) {
  if (cap > 0x7fffffffu || n > 0x7fffffffu) return error_code(-4);
  const int got = vcar_fzstd_decompress(dst, static_cast<int>(cap), src, static_cast<int>(n));
  return got < 0 ? error_code(got) : static_cast<size_t>(got);
}
unsigned ZSTD_isError(size_t code) { return code >= error_code(-4); }
const char* ZSTD_getErrorName(size_t code) {
  if (code == error_code(-2)) return "no zstd decoder in this page (the worker loads fzstd: vendor/fzstd/fzstd.js)";
  if (code == error_code(-3)) return "corrupt zstd stream (fzstd failed)";
  if (code == error_code(-4)) return "the zstd stream holds more bytes than its table of contents declares";
  return "not a zstd error";
}
}
