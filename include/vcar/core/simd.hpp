#pragma once
// The one place that knows the target's instruction set. Algorithms and the CPU backend write
// their loops over vcar::simd::batch<float> / batch<std::int32_t> and the functions below; no
// other header names an instruction set or tests an architecture macro.
//
// Two implementations, chosen at compile time:
// - xsimd (x86-64 with SSE2 or better, AArch64 with NEON): batch<T> is xsimd::batch<T>, whose
//   width follows the compiler's target flags (SSE2 and NEON: 4 floats, AVX2: 8, AVX-512: 16).
// - scalar: batch<T> is four plain values with element-wise operators written as loops and no
//   intrinsics. Chosen when VCAR_SIMD_SCALAR is defined (CMake: -DVCAR_SIMD=OFF, which also
//   drops the xsimd dependency) or when the target is neither of the above (WebAssembly,
//   RISC-V, 32-bit ARM): this is the path a WebAssembly build takes.
// Both give the same selections; floats can differ in the last bits where the target fuses
// multiply-adds or where xsimd's exp differs from std::exp (docs/embedding.md has the numbers).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#if !defined(VCAR_SIMD_SCALAR) && !(defined(__SSE2__) || defined(_M_X64) || defined(__aarch64__))
#define VCAR_SIMD_SCALAR 1
#endif

#if !defined(VCAR_SIMD_SCALAR)
// GCC 12's AVX-512 intrinsics read an "undefined" register on purpose and then warn about it
// (-W(maybe-)uninitialized, GCC bug 105593, fixed in GCC 13) wherever they are inlined, and
// Eigen's 512-bit stores in small fixed-size decompositions (<Eigen/Eigenvalues> on a 2 x 2)
// trip -Warray-bounds in dead branches: the warnings are silenced for code in the intrinsic
// headers, so hosts building with -Wall see none when those headers are first included
// through this one (include a vcar header before <Eigen/...> or <immintrin.h>).
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12 && defined(__AVX512F__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Warray-bounds"
#define VCAR_SIMD_POP_DIAGNOSTICS 1
#endif
#include <xsimd/xsimd.hpp>
#if defined(__AVX2__) || defined(__AVX512F__)
#include <immintrin.h>  // the gathers below: xsimd 8.1 never selects its own AVX2 gather
#elif defined(__SSE2__)
#include <emmintrin.h>  // nonzero_bytes_64
#endif
#endif

// VCAR_FORCE_INLINE, written after a lambda's parameter list: GCC keeps a lambda that a loop
// calls twice (the compositor's blend) as a call, passing batches through the stack and reading
// every capture through the closure; forced inline, compositing ran 1.12x faster.
#if defined(__GNUC__) || defined(__clang__)
#define VCAR_FORCE_INLINE __attribute__((always_inline))
#else
#define VCAR_FORCE_INLINE
#endif

namespace vcar::simd {

#if !defined(VCAR_SIMD_SCALAR)

template <class T>
using batch = xsimd::batch<T>;
template <class T>
using batch_bool = xsimd::batch_bool<T>;

// Name of the instruction set in use ("sse2", "fma3+avx2", "avx512bw", "neon64", "scalar").
inline const char* isa_name() { return xsimd::default_arch::name(); }

template <class T>
inline batch<T> fma(const batch<T>& a, const batch<T>& b, const batch<T>& c) { return xsimd::fma(a, b, c); }
template <class T>
inline batch<T> min(const batch<T>& a, const batch<T>& b) { return xsimd::min(a, b); }
template <class T>
inline batch<T> max(const batch<T>& a, const batch<T>& b) { return xsimd::max(a, b); }
inline batch<float> exp(const batch<float>& a) { return xsimd::exp(a); }
// Correctly rounded, as std::sqrt. (xsimd 8's NEON sqrt is a reciprocal estimate refined twice,
// a few ulp off: AArch64 has the exact instruction.)
inline batch<float> sqrt(const batch<float>& a) {
#if defined(__aarch64__)
  return batch<float>(vsqrtq_f32(a));
#else
  return xsimd::sqrt(a);
#endif
}
inline batch<float> log(const batch<float>& a) { return xsimd::log(a); }
inline batch<float> floor(const batch<float>& a) { return xsimd::floor(a); }
inline batch<float> ceil(const batch<float>& a) { return xsimd::ceil(a); }
template <class T>
inline batch<T> select(const batch_bool<T>& c, const batch<T>& a, const batch<T>& b) { return xsimd::select(c, a, b); }
template <class T>
inline bool any(const batch_bool<T>& c) { return xsimd::any(c); }
inline batch<std::int32_t> to_int(const batch<float>& a) { return xsimd::to_int(a); }  // truncates
template <class T>
inline T reduce_add(const batch<T>& a) { return xsimd::hadd(a); }

// words[idx] per lane.
inline batch<std::int32_t> gather(const std::int32_t* words, const batch<std::int32_t>& idx) {
  // A non-template function compiles both branches of an if constexpr: the preprocessor picks.
#if defined(__AVX512F__)
  static_assert(batch<std::int32_t>::size == 16);
  return batch<std::int32_t>(_mm512_i32gather_epi32(idx, words, 4));
#elif defined(__AVX2__)
  static_assert(batch<std::int32_t>::size == 8);
  return batch<std::int32_t>(_mm256_i32gather_epi32(words, idx, 4));
#else
  alignas(64) std::int32_t i[batch<std::int32_t>::size], out[batch<std::int32_t>::size];
  idx.store_aligned(i);
  for (std::size_t l = 0; l < batch<std::int32_t>::size; ++l) out[l] = words[i[l]];
  return batch<std::int32_t>::load_aligned(out);
#endif
}

// a >> s per lane (arithmetic). xsimd 8.1 has AVX2's variable shift but none for AVX-512, where
// its operator>> falls back to one scalar shift per lane.
inline batch<std::int32_t> shift_right(const batch<std::int32_t>& a, const batch<std::int32_t>& s) {
#if defined(__AVX512F__)
  return batch<std::int32_t>(_mm512_srav_epi32(a, s));
#else
  return a >> s;
#endif
}

#if defined(VCAR_SIMD_POP_DIAGNOSTICS)
#pragma GCC diagnostic pop
#undef VCAR_SIMD_POP_DIAGNOSTICS
#endif

#else  // scalar

inline constexpr std::size_t scalar_width = 4;  // as SSE2 and NEON; the renderer needs >= 4

template <class T>
struct batch_bool {
  static constexpr std::size_t size = scalar_width;
  bool v[size] = {};
  friend batch_bool operator&(const batch_bool& a, const batch_bool& b) { return zip(a, b, [](bool x, bool y) { return x && y; }); }
  friend batch_bool operator|(const batch_bool& a, const batch_bool& b) { return zip(a, b, [](bool x, bool y) { return x || y; }); }
  friend batch_bool operator&&(const batch_bool& a, const batch_bool& b) { return a & b; }
  friend batch_bool operator||(const batch_bool& a, const batch_bool& b) { return a | b; }
  friend batch_bool operator!(const batch_bool& a) {
    batch_bool r;
    for (std::size_t l = 0; l < size; ++l) r.v[l] = !a.v[l];
    return r;
  }

private:
  template <class F>
  static batch_bool zip(const batch_bool& a, const batch_bool& b, F f) {
    batch_bool r;
    for (std::size_t l = 0; l < size; ++l) r.v[l] = f(a.v[l], b.v[l]);
    return r;
  }
};

template <class T>
struct batch {
  static constexpr std::size_t size = scalar_width;
  T v[size] = {};

  batch() = default;
  batch(T x) {  // broadcast, implicit as xsimd's
    for (auto& e : v) e = x;
  }
  static batch load_unaligned(const T* p) {
    batch r;
    for (std::size_t l = 0; l < size; ++l) r.v[l] = p[l];
    return r;
  }
  static batch load_aligned(const T* p) { return load_unaligned(p); }
  void store_unaligned(T* p) const {
    for (std::size_t l = 0; l < size; ++l) p[l] = v[l];
  }
  void store_aligned(T* p) const { store_unaligned(p); }

  template <class F>
  static batch map(const batch& a, F f) {
    batch r;
    for (std::size_t l = 0; l < size; ++l) r.v[l] = f(a.v[l]);
    return r;
  }
  template <class F>
  static batch zip(const batch& a, const batch& b, F f) {
    batch r;
    for (std::size_t l = 0; l < size; ++l) r.v[l] = f(a.v[l], b.v[l]);
    return r;
  }
  template <class F>
  static batch_bool<T> test(const batch& a, const batch& b, F f) {
    batch_bool<T> r;
    for (std::size_t l = 0; l < size; ++l) r.v[l] = f(a.v[l], b.v[l]);
    return r;
  }

  friend batch operator+(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x + y); }); }
  friend batch operator-(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x - y); }); }
  friend batch operator*(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x * y); }); }
  friend batch operator/(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x / y); }); }
  friend batch operator-(const batch& a) { return map(a, [](T x) { return T(-x); }); }
  friend batch operator&(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x & y); }); }
  friend batch operator|(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x | y); }); }
  friend batch operator>>(const batch& a, const batch& b) { return zip(a, b, [](T x, T y) { return T(x >> y); }); }
  friend batch operator>>(const batch& a, int s) { return map(a, [s](T x) { return T(x >> s); }); }
  friend batch operator<<(const batch& a, int s) { return map(a, [s](T x) { return T(x << s); }); }
  batch& operator+=(const batch& b) { return *this = *this + b; }

  friend batch_bool<T> operator<(const batch& a, const batch& b) { return test(a, b, [](T x, T y) { return x < y; }); }
  friend batch_bool<T> operator<=(const batch& a, const batch& b) { return test(a, b, [](T x, T y) { return x <= y; }); }
  friend batch_bool<T> operator>(const batch& a, const batch& b) { return test(a, b, [](T x, T y) { return x > y; }); }
  friend batch_bool<T> operator>=(const batch& a, const batch& b) { return test(a, b, [](T x, T y) { return x >= y; }); }
};

inline const char* isa_name() { return "scalar"; }

// Not fused: a * b + c rounded twice, as xsimd's fma on SSE2 (the compiler may still contract
// it where the target has FMA and -ffp-contract allows).
template <class T>
inline batch<T> fma(const batch<T>& a, const batch<T>& b, const batch<T>& c) { return a * b + c; }
// min/max pick b when either is NaN, as SSE's minps/maxps (and xsimd on them).
template <class T>
inline batch<T> min(const batch<T>& a, const batch<T>& b) { return batch<T>::zip(a, b, [](T x, T y) { return x < y ? x : y; }); }
template <class T>
inline batch<T> max(const batch<T>& a, const batch<T>& b) { return batch<T>::zip(a, b, [](T x, T y) { return x > y ? x : y; }); }
inline batch<float> exp(const batch<float>& a) { return batch<float>::map(a, [](float x) { return std::exp(x); }); }
inline batch<float> sqrt(const batch<float>& a) { return batch<float>::map(a, [](float x) { return std::sqrt(x); }); }
inline batch<float> log(const batch<float>& a) { return batch<float>::map(a, [](float x) { return std::log(x); }); }
inline batch<float> floor(const batch<float>& a) { return batch<float>::map(a, [](float x) { return std::floor(x); }); }
inline batch<float> ceil(const batch<float>& a) { return batch<float>::map(a, [](float x) { return std::ceil(x); }); }
template <class T>
inline batch<T> select(const batch_bool<T>& c, const batch<T>& a, const batch<T>& b) {
  batch<T> r;
  for (std::size_t l = 0; l < scalar_width; ++l) r.v[l] = c.v[l] ? a.v[l] : b.v[l];
  return r;
}
template <class T>
inline bool any(const batch_bool<T>& c) {
  for (bool b : c.v)
    if (b) return true;
  return false;
}
inline batch<std::int32_t> to_int(const batch<float>& a) {  // truncates
  batch<std::int32_t> r;
  for (std::size_t l = 0; l < scalar_width; ++l) r.v[l] = static_cast<std::int32_t>(a.v[l]);
  return r;
}
template <class T>
inline T reduce_add(const batch<T>& a) {  // pairwise, as the 4-lane SIMD horizontal adds
  return (a.v[0] + a.v[2]) + (a.v[1] + a.v[3]);
}
inline batch<std::int32_t> gather(const std::int32_t* words, const batch<std::int32_t>& idx) {
  batch<std::int32_t> r;
  for (std::size_t l = 0; l < scalar_width; ++l) r.v[l] = words[idx.v[l]];
  return r;
}
inline batch<std::int32_t> shift_right(const batch<std::int32_t>& a, const batch<std::int32_t>& s) { return a >> s; }

#endif

// Lanes of a float batch on this target.
inline constexpr std::size_t width = batch<float>::size;

// Bit j set iff byte j of v (little-endian) is nonzero: the high bit of each byte marks a
// nonzero byte (no carry crosses a byte), and the multiply gathers the 8 high bits into the top
// byte (byte j -> bit 56 + j, distinct partial products).
inline std::uint8_t nonzero_bytes_8(std::uint64_t v) {
  const std::uint64_t nz = (v | ((v & 0x7f7f7f7f7f7f7f7fULL) + 0x7f7f7f7f7f7f7f7fULL)) & 0x8080808080808080ULL;
  return static_cast<std::uint8_t>(((nz >> 7) * 0x0102040810204080ULL) >> 56);
}

// Bit j set iff byte p[j] is nonzero, for the 64 bytes at p (mask packing: MaskTiles): one
// AVX-512BW test, two AVX2 or four SSE2 compares with movemask, elsewhere nonzero_bytes_8 eight
// times. The same bits on every target.
inline std::uint64_t nonzero_bytes_64(const std::uint8_t* p) {
#if !defined(VCAR_SIMD_SCALAR) && defined(__AVX512BW__)
  const __m512i v = _mm512_loadu_si512(p);
  return _mm512_test_epi8_mask(v, v);
#elif !defined(VCAR_SIMD_SCALAR) && defined(__AVX2__)
  const __m256i z = _mm256_setzero_si256();
  const auto zero_bits = [&](int k) {  // bit j: byte 32 k + j is zero
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32 * k));
    return static_cast<std::uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(v, z)));
  };
  return ~(static_cast<std::uint64_t>(zero_bits(0)) | static_cast<std::uint64_t>(zero_bits(1)) << 32);
#elif !defined(VCAR_SIMD_SCALAR) && defined(__SSE2__)
  const __m128i z = _mm_setzero_si128();
  std::uint64_t zero = 0;
  for (int k = 0; k < 4; ++k) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * k));
    zero |= static_cast<std::uint64_t>(static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_cmpeq_epi8(v, z)))) << (16 * k);
  }
  return ~zero;
#else
  std::uint64_t bits = 0;
  for (int k = 0; k < 8; ++k) {
    std::uint64_t v;
    std::memcpy(&v, p + 8 * k, 8);
    bits |= static_cast<std::uint64_t>(nonzero_bytes_8(v)) << (8 * k);
  }
  return bits;
#endif
}


// Bit l set iff lane l of v is nonzero: one AVX-512 test, an AVX2 or SSE2 compare with
// movemask, elsewhere lane by lane. The same bits on every target.
inline std::uint32_t nonzero_lanes(const batch<std::int32_t>& v) {
#if !defined(VCAR_SIMD_SCALAR) && defined(__AVX512F__)
  const __m512i x = v;
  return _mm512_test_epi32_mask(x, x);
#elif !defined(VCAR_SIMD_SCALAR) && defined(__AVX2__)
  const __m256i x = v;
  return ~static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(x, _mm256_setzero_si256())))) & 0xffu;
#elif !defined(VCAR_SIMD_SCALAR) && defined(__SSE2__)
  const __m128i x = v;
  return ~static_cast<std::uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(x, _mm_setzero_si128())))) & 0xfu;
#else
  alignas(64) std::int32_t a[batch<std::int32_t>::size];
  v.store_aligned(a);
  std::uint32_t bits = 0;
  for (std::size_t l = 0; l < batch<std::int32_t>::size; ++l) bits |= static_cast<std::uint32_t>(a[l] != 0) << l;
  return bits;
#endif
}

}  // namespace vcar::simd
