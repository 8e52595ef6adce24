#pragma once
/// \file
/// Deterministic random numbers for the sensor-noise models: xoshiro256**
/// (Blackman & Vigna) seeded through splitmix64, with our own uniform and
/// Box-Muller normal transforms, so a seed gives the same numbers on every
/// platform and standard library (std distributions are
/// implementation-defined). Written for semlio; see random.hpp for the world
/// builder's counter-based hashes.

#include <cmath>
#include <cstdint>
#include <numbers>

namespace semlio::sim {

/// xoshiro256** generator with portable uniform/normal draws. Value type; not
/// thread-safe (one per thread or per stream).
class Xoshiro256 {
 public:
  /// Seeds the 256-bit state from (seed, stream) through splitmix64, so
  /// different streams of one seed are independent.
  explicit Xoshiro256(std::uint64_t seed, std::uint64_t stream = 0) {
    std::uint64_t x = seed ^ (stream * 0xD1B54A32D192ED03ULL);
    for (auto& w : s_) w = splitmix(x);
  }

  /// Next raw 64 bits.
  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5U, 7) * 9U;
    const std::uint64_t t = s_[1] << 17U;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11U) * 0x1.0p-53; }

  /// Standard normal (Box-Muller; the second value of each pair is kept for
  /// the next call).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u = 1.0 - uniform();  // (0, 1], never log(0)
    const double v = uniform();
    const double r = std::sqrt(-2.0 * std::log(u));
    const double a = 2.0 * std::numbers::pi * v;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }

  /// splitmix64 step: advances x and returns a well-mixed 64-bit value.
  static std::uint64_t splitmix(std::uint64_t& x) {
    x += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = x;
    z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31U);
  }

  /// One splitmix64 output for a key (stateless, bijective mix).
  static std::uint64_t mix(std::uint64_t key) {
    std::uint64_t x = key;
    return splitmix(x);
  }

  /// Uniform in [0, 1) from 64 hash bits (top 53 bits).
  static double to_unit(std::uint64_t bits) { return static_cast<double>(bits >> 11U) * 0x1.0p-53; }

  /// 64 hash bits of two keys.
  static std::uint64_t hashed_uniform_bits(std::uint64_t a, std::uint64_t b) { return mix(mix(a) ^ b); }

  /// Uniform in [0, 1) from a hash of up to four keys (counter-based: no state,
  /// order-independent draws for per-pixel or per-region decisions).
  static double hashed_uniform(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0, std::uint64_t d = 0) {
    std::uint64_t x = a;
    std::uint64_t h = splitmix(x);
    x = h ^ b;
    h = splitmix(x);
    x = h ^ c;
    h = splitmix(x);
    x = h ^ d;
    h = splitmix(x);
    return static_cast<double>(h >> 11U) * 0x1.0p-53;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) {
    return (x << static_cast<unsigned>(k)) | (x >> static_cast<unsigned>(64 - k));
  }

  std::uint64_t s_[4]{};
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace semlio::sim
