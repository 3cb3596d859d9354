// WebAssembly build only: emscripten has no zlib or zstd here (its zlib port is downloaded at
// build time; zstd has none), so the few entry points vcar's SPZ reader names are answered with
// errors. The page inflates gzip SPZ (v2, v3) with the browser's DecompressionStream before
// handing it over, so read_scene never meets gzip; SPZ v4 (zstd streams) ends in
// "SPZ v4 stream 0: <message below>".
#include <cstddef>

#include <zlib.h>
#include <zstd.h>

extern "C" {
int inflateInit2_(z_streamp, int, const char*, int) { return Z_VERSION_ERROR; }
int inflate(z_streamp, int) { return Z_STREAM_ERROR; }
int inflateEnd(z_streamp) { return Z_OK; }
size_t ZSTD_decompress(void*, size_t, const void*, size_t) { return static_cast<size_t>(-1); }
unsigned ZSTD_isError(size_t code) { return code == static_cast<size_t>(-1); }
const char* ZSTD_getErrorName(size_t) { return "zstd is not available in the browser build (convert SPZ v4 to PLY or SPZ v3)"; }
}
