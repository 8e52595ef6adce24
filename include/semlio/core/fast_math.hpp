#pragma once
/// \file
/// atan2 for per-point work (azimuths and elevations of every point of every
/// scan). glibc's atan2 is correctly rounded and costs ~110 instructions a
/// call; ring inference, feature ordering and sweep times call it two or
/// three times per point, ~10 % of a frame on KITTI scans. Those uses need a
/// few micro-radians at most (the HDL-64E's azimuth step is 3e-3 rad, its
/// beam spacing 7e-3 rad), so a short polynomial with an error below 5e-9 rad
/// serves them at a third of the cost. Pure function of its inputs: the same
/// result on every run and thread.

#include <cmath>
#include <numbers>

namespace semlio {

/// atan2(y, x) in [-pi, pi] with |error| < 5e-9 rad (tests/core compare it
/// with std::atan2); atan2(0, 0) = 0; NaN input gives NaN. Signed zeros
/// are not distinguished (atan2(-0, -1) = pi), infinities are not handled.
inline double atan2_fast(double y, double x) noexcept {
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  const double mx = ax > ay ? ax : ay;
  const double mn = ax > ay ? ay : ax;
  if (!(mx > 0.0)) return mx == 0.0 ? 0.0 : y + x;  // (0, 0) -> 0; NaN propagates
  double a = mn / mx;  // in [0, 1]
  // Reduce to |t| <= tan(pi/8) with atan(a) = pi/4 + atan((a - 1) / (a + 1)).
  constexpr double kTanPi8 = 0.41421356237309503;
  double offset = 0.0;
  if (a > kTanPi8) {
    a = (a - 1.0) / (a + 1.0);
    offset = std::numbers::pi / 4.0;
  }
  // Taylor series of atan to t^19: the first omitted term is below
  // 0.4143^21 / 21 < 5e-10 there.
  const double s = a * a;
  double p = -1.0 / 19.0;
  p = p * s + 1.0 / 17.0;
  p = p * s - 1.0 / 15.0;
  p = p * s + 1.0 / 13.0;
  p = p * s - 1.0 / 11.0;
  p = p * s + 1.0 / 9.0;
  p = p * s - 1.0 / 7.0;
  p = p * s + 1.0 / 5.0;
  p = p * s - 1.0 / 3.0;
  double r = offset + a + a * s * p;
  if (ay > ax) r = std::numbers::pi / 2.0 - r;
  if (x < 0.0) r = std::numbers::pi - r;
  return y < 0.0 ? -r : r;
}

}  // namespace semlio
