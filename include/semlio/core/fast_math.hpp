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

#include <array>
#include <cmath>
#include <numbers>

// Two-lane SSE2 forms of per-point arithmetic that must equal the scalar
// form bit for bit: only where the compiler cannot contract the scalar form's
// a * b + c into an FMA (which the intrinsics never do).
#if defined(__SSE2__) && !defined(__FMA__)
#include <emmintrin.h>
#define SEMLIO_EXACT_SSE2 1
#endif

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

/// {atan2_fast(y0, x0), atan2_fast(y1, x1)}, bit for bit (tests/core), two
/// lanes at once where SSE2 allows: the same IEEE operations in the same
/// order, both branches computed and selected by masks. Builds that may
/// contract a * b + c into an FMA (__FMA__) take the scalar path, so that
/// the pair always equals two scalar calls of the same build.
inline std::array<double, 2> atan2_fast_pair(double y0, double x0, double y1, double x1) noexcept {
#if defined(SEMLIO_EXACT_SSE2)
  const __m128d y = _mm_set_pd(y1, y0);
  const __m128d x = _mm_set_pd(x1, x0);
  const __m128d sign = _mm_set1_pd(-0.0);
  const __m128d ax = _mm_andnot_pd(sign, x);
  const __m128d ay = _mm_andnot_pd(sign, y);
  const __m128d x_wider = _mm_cmpgt_pd(ax, ay);
  const __m128d mx = _mm_or_pd(_mm_and_pd(x_wider, ax), _mm_andnot_pd(x_wider, ay));
  const __m128d mn = _mm_or_pd(_mm_and_pd(x_wider, ay), _mm_andnot_pd(x_wider, ax));
  // (0, 0) and NaN lanes: the scalar function's early return.
  if (_mm_movemask_pd(_mm_cmpgt_pd(mx, _mm_setzero_pd())) != 3) return {atan2_fast(y0, x0), atan2_fast(y1, x1)};
  const __m128d one = _mm_set1_pd(1.0);
  __m128d a = _mm_div_pd(mn, mx);
  const __m128d reduce = _mm_cmpgt_pd(a, _mm_set1_pd(0.41421356237309503));
  const __m128d reduced = _mm_div_pd(_mm_sub_pd(a, one), _mm_add_pd(a, one));
  a = _mm_or_pd(_mm_and_pd(reduce, reduced), _mm_andnot_pd(reduce, a));
  const __m128d offset = _mm_and_pd(reduce, _mm_set1_pd(std::numbers::pi / 4.0));
  const __m128d s = _mm_mul_pd(a, a);
  __m128d p = _mm_set1_pd(-1.0 / 19.0);
  p = _mm_add_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 17.0));
  p = _mm_sub_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 15.0));
  p = _mm_add_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 13.0));
  p = _mm_sub_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 11.0));
  p = _mm_add_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 9.0));
  p = _mm_sub_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 7.0));
  p = _mm_add_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 5.0));
  p = _mm_sub_pd(_mm_mul_pd(p, s), _mm_set1_pd(1.0 / 3.0));
  __m128d r = _mm_add_pd(_mm_add_pd(offset, a), _mm_mul_pd(_mm_mul_pd(a, s), p));
  const __m128d y_wider = _mm_cmpgt_pd(ay, ax);
  r = _mm_or_pd(_mm_and_pd(y_wider, _mm_sub_pd(_mm_set1_pd(std::numbers::pi / 2.0), r)), _mm_andnot_pd(y_wider, r));
  const __m128d x_negative = _mm_cmplt_pd(x, _mm_setzero_pd());
  r = _mm_or_pd(_mm_and_pd(x_negative, _mm_sub_pd(_mm_set1_pd(std::numbers::pi), r)), _mm_andnot_pd(x_negative, r));
  // y < 0: flip the sign bit (-r), as the scalar negation does.
  r = _mm_xor_pd(r, _mm_and_pd(_mm_cmplt_pd(y, _mm_setzero_pd()), sign));
  std::array<double, 2> out;
  _mm_storeu_pd(out.data(), r);
  return out;
#else
  return {atan2_fast(y0, x0), atan2_fast(y1, x1)};
#endif
}

}  // namespace semlio
