#pragma once
// Counter-based random numbers: every draw is a pure function of (seed, stream, counter), so
// generation is parallel and bit-identical for any thread count and call order.
#include <cstdint>
#include <string_view>

namespace vcar::synth {

// SplitMix64 finaliser: a strong 64-bit mix (Steele et al. 2014).
constexpr std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

constexpr std::uint64_t hash_combine(std::uint64_t a, std::uint64_t b) {
  return mix64(a ^ (mix64(b) + 0x632BE59BD9B4E019ull));
}

// FNV-1a of a string (camera names), then mixed.
constexpr std::uint64_t hash_string(std::string_view s) {
  std::uint64_t h = 0xCBF29CE484222325ull;
  for (char c : s) { h ^= static_cast<unsigned char>(c); h *= 0x100000001B3ull; }
  return mix64(h);
}

// A small stream of draws keyed by a 64-bit key; cheap to create per Gaussian or per frame.
class Rng {
public:
  explicit constexpr Rng(std::uint64_t key) : key_(key) {}
  Rng(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0)
      : key_(hash_combine(hash_combine(seed, a), b)) {}

  std::uint64_t next_u64() { return mix64(key_ ^ mix64(++counter_)); }
  // Uniform in [0, 1) with 24 random bits (exact in float).
  float uniform() { return static_cast<float>(next_u64() >> 40) * (1.f / 16777216.f); }
  double uniform_d() { return static_cast<double>(next_u64() >> 11) * (1.0 / 9007199254740992.0); }
  // In [lo, hi): the product of two floats is exact in double, so the sum is rounded once
  // whether or not the compiler contracts it into a fused multiply-add (float a * b + c is not:
  // one translation unit fused it and another did not, and their worlds differed by an ulp).
  float uniform(float lo, float hi) { return static_cast<float>(lo + static_cast<double>(hi - lo) * uniform()); }
  // Integer in [lo, hi] inclusive.
  int uniform_int(int lo, int hi) {
    const std::uint64_t span = static_cast<std::uint64_t>(hi - lo) + 1;
    return lo + static_cast<int>(next_u64() % span);
  }

private:
  std::uint64_t key_;
  std::uint64_t counter_ = 0;
};

}  // namespace vcar::synth
