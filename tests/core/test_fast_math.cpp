// atan2_fast against std::atan2: the error bound its per-point callers rely on.
#include <catch2/catch.hpp>

#include <semlio/core/fast_math.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>
#include <limits>
#include <numbers>
#include <random>

namespace test_fast_math {  // one namespace per test file: the area compiles as one TU

// Random (y, x) over every octant at scales 1e-6 .. 1e4.
struct RandomPoint {
  explicit RandomPoint(unsigned seed) : rng(seed) {}
  std::array<double, 2> operator()() {
    const double s = std::pow(10.0, scale_exp(rng));
    const double y = s * u(rng);
    return {y, s * u(rng)};
  }
  std::mt19937 rng;
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  std::uniform_real_distribution<double> scale_exp{-6.0, 4.0};
};

TEST_CASE("atan2_fast stays within 5e-9 rad of std::atan2 over every octant", "[core][fast_math]") {
  RandomPoint random_point(7);
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const auto [y, x] = random_point();
    worst = std::max(worst, std::abs(semlio::atan2_fast(y, x) - std::atan2(y, x)));
  }
  CHECK(worst < 5e-9);
  // The reduction's seams and the octant edges, where a sign or offset slip shows.
  const double t8 = std::tan(std::numbers::pi / 8.0);
  for (const double a : {0.0, 1e-12, t8 - 1e-12, t8, t8 + 1e-12, 1.0 - 1e-12, 1.0}) {
    for (const int sy : {-1, 1}) {
      for (const int sx : {-1, 1}) {
        for (const bool swap : {false, true}) {
          const double y = sy * (swap ? 1.0 : a);
          const double x = sx * (swap ? a : 1.0);
          if (y == 0.0 && x < 0.0) continue;  // signed zero: documented difference
          CHECK(std::abs(semlio::atan2_fast(y, x) - std::atan2(y, x)) < 5e-9);
        }
      }
    }
  }
}

TEST_CASE("atan2_fast special inputs", "[core][fast_math]") {
  CHECK(semlio::atan2_fast(0.0, 0.0) == 0.0);
  CHECK(semlio::atan2_fast(0.0, -2.0) == Approx(std::numbers::pi).margin(1e-15));
  CHECK(semlio::atan2_fast(3.0, 0.0) == Approx(std::numbers::pi / 2.0).margin(1e-15));
  CHECK(semlio::atan2_fast(-3.0, 0.0) == Approx(-std::numbers::pi / 2.0).margin(1e-15));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(std::isnan(semlio::atan2_fast(nan, 1.0)));
  CHECK(std::isnan(semlio::atan2_fast(1.0, nan)));
  // Monotone in the azimuth within a half-turn, as feature ordering needs.
  double prev = semlio::atan2_fast(-1e-9, -1.0);
  for (int k = 1; k < 20000; ++k) {
    const double ang = -std::numbers::pi + 2.0 * std::numbers::pi * k / 20000.0;
    const double v = semlio::atan2_fast(std::sin(ang), std::cos(ang));
    CHECK(v > prev);
    prev = v;
  }
}

// Bit equality, so that a caller may switch between the two freely: random
// pairs over every octant and scale, the reduction seam, axes, zeros of both
// signs, NaN and subnormals, each combined with every other in one pair.
TEST_CASE("atan2_fast_pair equals two atan2_fast calls bit for bit", "[core][fast_math]") {
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  const auto same = [&](double y0, double x0, double y1, double x1) {
    const std::array<double, 2> pair = semlio::atan2_fast_pair(y0, x0, y1, x1);
    return bits(pair[0]) == bits(semlio::atan2_fast(y0, x0)) && bits(pair[1]) == bits(semlio::atan2_fast(y1, x1));
  };
  RandomPoint random_point(11);
  int mismatches = 0;
  for (int i = 0; i < 200000; ++i) {
    const auto [y0, x0] = random_point();
    const auto [y1, x1] = random_point();
    // KITTI coordinates are floats: half the pairs come rounded to float.
    double v[4] = {y0, x0, y1, x1};
    if (i % 2 == 0) {
      for (double& c : v) c = static_cast<double>(static_cast<float>(c));
    }
    if (!same(v[0], v[1], v[2], v[3])) ++mismatches;
  }
  CHECK(mismatches == 0);
  const double t8 = std::tan(std::numbers::pi / 8.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double tiny = std::numeric_limits<double>::denorm_min();
  std::vector<double> special = {0.0, -0.0, 1.0, -1.0, t8, -t8, std::nextafter(t8, 2.0), std::nextafter(t8, 0.0),
                                 tiny, -tiny, 1e-300, 3.5e38, nan};
  std::vector<std::array<double, 2>> inputs;
  for (const double y : special) {
    for (const double x : special) inputs.push_back({y, x});
  }
  for (const auto& a : inputs) {
    for (const auto& b : inputs) {
      if (!same(a[0], a[1], b[0], b[1])) ++mismatches;
    }
  }
  CHECK(mismatches == 0);
  CHECK(inputs.size() == 169);
}

}  // namespace test_fast_math
