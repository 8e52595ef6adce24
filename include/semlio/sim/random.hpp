#pragma once
/// \file
/// Portable deterministic randomness for the simulator. Sequential draws use
/// std::mt19937_64 (its raw output is specified by the standard) with our own
/// uniform/normal transforms, because std distributions are
/// implementation-defined. Per-ray noise uses a counter-based hash
/// (splitmix64 finaliser) of (seed, frame, ring, column), so results do not
/// depend on the order or the thread in which rays are cast.
///
/// One rule for callers: never make two draws from one Rng as arguments of
/// the same call. The order in which a call's arguments are evaluated is
/// unspecified (GCC goes right to left, clang left to right), so such a
/// call builds a different world per compiler; draw into named values
/// first (the worlds do so in GCC's order, which kept earlier drives).

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace semlio::sim {

/// splitmix64 finaliser: a bijective 64-bit mix.
constexpr std::uint64_t mix64(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31U);
}

/// Hash of several 64-bit keys (order matters).
constexpr std::uint64_t hash_keys(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0,
                                  std::uint64_t d = 0) noexcept {
  return mix64(mix64(mix64(mix64(a) ^ b) ^ c) ^ d);
}

/// Uniform double in [0, 1) from 64 random bits (top 53 bits).
constexpr double unit_from_bits(std::uint64_t bits) noexcept {
  return static_cast<double>(bits >> 11U) * 0x1.0p-53;
}

/// Standard normal from two 64-bit words (Box-Muller; never log(0)).
inline double normal_from_bits(std::uint64_t u_bits, std::uint64_t v_bits) noexcept {
  const double u = 1.0 - unit_from_bits(u_bits);  // (0, 1]
  const double v = unit_from_bits(v_bits);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
}

/// Sequential generator for world building: explicit seed, portable draws.
/// Not thread-safe (one per thread).
class Rng {
 public:
  /// Seeds std::mt19937_64 with `seed` mixed with `stream` (independent streams).
  explicit Rng(std::uint64_t seed, std::uint64_t stream = 0) : engine_(hash_keys(seed, stream)) {}
  /// Raw 64 bits.
  std::uint64_t bits() { return engine_(); }
  /// Uniform in [0, 1).
  double uniform() { return unit_from_bits(engine_()); }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer uniform in [lo, hi] (tiny modulo bias is irrelevant here).
  int integer(int lo, int hi) {
    const auto span = static_cast<std::uint64_t>(hi - lo + 1);
    return lo + static_cast<int>(engine_() % span);
  }
  /// True with probability p.
  bool chance(double p) { return uniform() < p; }
  /// Standard normal.
  double normal() {
    const std::uint64_t a = engine_();
    return normal_from_bits(a, engine_());
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace semlio::sim
