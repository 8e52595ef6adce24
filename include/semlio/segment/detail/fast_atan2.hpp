#pragma once
/// \file
/// A branch-light atan2 approximation for binning points by azimuth. The
/// maximum error is about 2e-4 rad (0.012 deg), far below a sector width, and
/// the result is a pure function of its inputs (bit-reproducible).

#include <cmath>
#include <numbers>

namespace semlio::detail {

/// atan2(y, x) in [-pi, pi] with |error| < ~2.1e-4 rad; returns 0 for (0, 0).
inline float fast_atan2(float y, float x) noexcept {
  const float ax = std::fabs(x);
  const float ay = std::fabs(y);
  const float mx = ax > ay ? ax : ay;
  const float mn = ax > ay ? ay : ax;
  if (!(mx > 0.0F)) return 0.0F;
  const float a = mn / mx;
  const float s = a * a;
  // Odd minimax polynomial for atan on [0, 1].
  float r = ((-0.0464964749F * s + 0.15931422F) * s - 0.327622764F) * s * a + a;
  if (ay > ax) r = std::numbers::pi_v<float> * 0.5F - r;
  if (x < 0.0F) r = std::numbers::pi_v<float> - r;
  if (y < 0.0F) r = -r;
  return r;
}

}  // namespace semlio::detail
