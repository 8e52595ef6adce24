#pragma once
/// \file
/// Ring (beam) inference, per-point time from azimuth, and KITTI's
/// vertical-angle correction -- what KITTI .bin scans lack (METHOD.md "Rings
/// for KITTI", "KITTI intrinsic fix").
///
/// Azimuth convention: az = atan2(y, x) in the sensor frame (x forward, y left,
/// z up), so it grows counter-clockwise seen from above.
///
/// KITTI point order, verified on tests/data/kitti (odometry 00/000000-1 and
/// the raw snippet): the .bin holds the 64 rings one after the other, the
/// highest beam first; within a ring az mod 2pi grows from ~0 (straight ahead)
/// to ~2pi: every ring of the raw snippet starts within 0.2 deg of az = 0
/// (the few upper/lowest rings with no return straight ahead start later).
///
/// KITTI raw time convention (measured on the 22-frame raw snippet, see
/// scripts/kitti_raw_consistency.sh and tests/pipeline/test_deskew_pipeline.cpp):
/// the HDL-64E spins CLOCKWISE seen from above (az decreasing, like the
/// simulator and every Velodyne), so time runs AGAINST the stored point order,
/// and a sweep starts and ends facing FORWARD (az = 0, where the file cuts each
/// ring and where the cameras are triggered): t = period * frac(-az / 2pi).
/// Evidence: (1) deskewing clockwise lowers the point-to-plane residual of
/// near structure between scans 2 frames apart on all 6 pairs tried (mean
/// 4.15 -> 4.06 cm) while counter-clockwise raises it (4.31 cm); (2) with the
/// clockwise spin, the forward/backward odometry runs agree best when the
/// sweep seam is at the front (mean 1.9-2.6 cm for seams at -10/0/+10 deg)
/// and worse than without deskew when it is at the rear (3.9-4.5 cm for
/// 170/180 deg, KISS-ICP's and CT-ICP's choice). The seam cannot be seen
/// directly in the snippet: the road ahead and behind is open (no point above
/// the road within 3 deg of 0 or 180 deg). Hence the KITTI time defaults of
/// PointTimeConfig: start azimuth 0, clockwise, 0.1 s.
///
/// The 32-beam real scan pair (tests/data/scan_pair) is stored differently:
/// column by column (32 interleaved beams per firing), clockwise from +y, with
/// elevations exactly on the HDL-32E table; there rings come from elevation.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/fast_math.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/sensor_model.hpp>

namespace semlio {

/// How rings are inferred.
enum class RingMethod : std::uint8_t {
  kAuto,        ///< point order when it yields exactly sensor.beams() rings, else elevation
  kPointOrder,  ///< azimuth wrap-around in point order (KITTI .bin); throws if the count mismatches
  kElevation,   ///< nearest beam of the sensor table by elevation
  kFromScan,    ///< the scan's own ring field (a ROS driver's `ring`); throws if absent or out of the table
};

/// Settings of infer_rings().
struct RingConfig {
  RingMethod method = RingMethod::kAuto;  ///< see RingMethod
  /// Keep a ring field the scan already carries (a ROS driver's `ring`) when
  /// every ring is below the table's beam count, whatever the method. Off by
  /// default: infer_rings is also called again on scans whose rings an
  /// earlier call filled, expecting them re-inferred. settings_for_sensor
  /// (pipeline/presets.hpp) turns it on.
  bool prefer_scan_rings = false;
};

/// What infer_rings() did.
struct RingReport {
  RingMethod used = RingMethod::kElevation;  ///< kFromScan, kPointOrder or kElevation
  std::size_t order_rings = 0;               ///< rings found from point order (0 if not tried)
};

/// Azimuth atan2(y, x) at which a KITTI raw HDL-64E sweep starts and ends:
/// facing forward (see the file comment) [rad].
inline constexpr double kKittiSweepStartAzimuthRad = 0.0;

/// Settings of assign_times_from_azimuth(). Defaults: KITTI raw's HDL-64E,
/// clockwise from the front at 10 Hz (see the file comment). The simulator
/// spins clockwise from the rear: start_azimuth_rad = pi.
struct PointTimeConfig {
  double sweep_period_s = 0.1;                            ///< duration of one sweep (10 Hz) [s]
  double start_azimuth_rad = kKittiSweepStartAzimuthRad;  ///< azimuth where a sweep starts (t = 0) [rad]
  bool counter_clockwise = false;                         ///< direction of rotation seen from above
};

/// KISS-ICP / CT-ICP's KITTI vertical-angle correction [rad] (0.205 deg).
inline constexpr double kKittiVerticalCorrectionRad = 0.205 * std::numbers::pi / 180.0;

namespace detail {

/// Azimuth in [0, 2pi) (atan2_fast: per-point work, see core/fast_math.hpp).
inline double azimuth_0_2pi(const Eigen::Vector3f& p) {
  const double a = atan2_fast(static_cast<double>(p.y()), static_cast<double>(p.x()));
  return a < 0.0 ? a + 2.0 * std::numbers::pi : a;
}

/// azimuth_0_2pi(p) in (pi/2, 3pi/2), decided by the sign of x wherever
/// |x| > 1e-6 |y| (atan2_fast's result then lies at least ~1e-6 rad inside
/// its half-plane, far beyond its rounding), by the azimuth itself only near
/// the y axis or for non-finite input.
inline bool in_rear_half(const Eigen::Vector3f& p) {
  const auto x = static_cast<double>(p.x());
  const double ax = std::abs(x);
  if (ax > 1e-6 * std::abs(static_cast<double>(p.y()))) return x < 0.0;
  const double a = azimuth_0_2pi(p);
  return a > std::numbers::pi / 2.0 && a < 1.5 * std::numbers::pi;
}

/// azimuth_0_2pi(c) < azimuth_0_2pi(p) - pi, the azimuths computed only
/// where the answer can be true. Why that is only when p.y() < 0 <= c.y():
/// for y >= 0 atan2_fast returns r in [0, pi], so az(p) <= pi makes the
/// right side <= 0 and no azimuth is below it; for y < 0 (a float, so
/// r > 0 unless x is infinite) az = 2pi - r >= pi, so with both below the x
/// axis az(c) >= pi >= az(p) - pi. NaN input compares false either way.
inline bool wraps_around(const Eigen::Vector3f& p, const Eigen::Vector3f& c) {
  if (!(p.y() < 0.0F)) return false;
  if (c.y() < 0.0F && std::abs(c.x()) <= std::numeric_limits<float>::max()) return false;
  return azimuth_0_2pi(c) < azimuth_0_2pi(p) - std::numbers::pi;
}

}  // namespace detail

/// Start index of every ring found in point order: a new ring starts where az
/// mod 2pi drops by more than pi, once the current ring has reached the rear
/// half (az in (pi/2, 3pi/2)) -- so a stray point just below 2pi at a ring's
/// start cannot split it. begins is cleared; begins[0] = 0 when pts is not empty.
/// Cost: sign tests per point, atan2_fast only where a ring can wrap (the
/// points that cross the x axis from y < 0) or near the y axis -- the same
/// decisions as comparing every point's azimuth (detail::in_rear_half,
/// detail::wraps_around; tests compare with that literal form). On the
/// KITTI raw snippet this took the preprocessing stage from 2.28 to 1.17 ms
/// a frame (bench_features BM_RingInferenceFromOrder_KittiScan; bench_frame_time).
inline void ring_starts_from_order(const std::vector<Eigen::Vector3f>& pts,
                                   std::vector<std::size_t>& begins) {
  begins.clear();
  if (pts.empty()) return;
  begins.push_back(0);
  bool passed_rear = false;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if (!passed_rear && detail::in_rear_half(pts[i - 1])) passed_rear = true;
    if (passed_rear && detail::wraps_around(pts[i - 1], pts[i])) {
      begins.push_back(i);
      passed_rear = false;
    }
  }
}

/// Whether scan carries a ring field with one ring per point, each below
/// `beams` (a driver's ring field that the table can hold).
inline bool has_valid_rings(const Scan& scan, std::size_t beams) {
  if (!scan.has_rings() || scan.rings.size() != scan.size()) return false;
  return std::all_of(scan.rings.begin(), scan.rings.end(), [&](std::uint16_t r) { return r < beams; });
}

/// Fills scan.rings (0 = lowest beam) by config.method, using `begins` as the
/// workspace for ring starts (reused: no allocation once it has grown; the
/// per-frame pipeline keeps one). A ring field the scan already carries (a
/// ROS driver's `ring`) is kept by kFromScan, and by any method with
/// RingConfig::prefer_scan_rings, when every ring is below sensor.beams()
/// (report.used = kFromScan). Only the grouping into rings matters to the
/// features (loam_features.hpp), so a driver that counts rings from the top
/// (Ouster's row 0 is the highest beam) works as well. Throws ConfigError
/// for an invalid sensor, ValueError when kPointOrder finds a ring count
/// other than sensor.beams() (the message names both counts) and when
/// kFromScan finds no valid ring field.
inline RingReport infer_rings(Scan& scan, const SensorModel& sensor, const RingConfig& config,
                              std::vector<std::size_t>& begins) {
  sensor.validate();
  RingReport report;
  if (config.prefer_scan_rings || config.method == RingMethod::kFromScan) {
    if (has_valid_rings(scan, sensor.beams())) {
      report.used = RingMethod::kFromScan;
      return report;
    }
    if (config.method == RingMethod::kFromScan) {
      throw ValueError("infer_rings: kFromScan needs a ring field with one ring per point below " +
                       std::to_string(sensor.beams()) + ", got " + std::to_string(scan.rings.size()) +
                       " rings for " + std::to_string(scan.size()) + " points");
    }
  }
  scan.rings.resize(scan.size());
  if (config.method != RingMethod::kElevation) {
    ring_starts_from_order(scan.points, begins);
    report.order_rings = begins.size();
    if (begins.size() == sensor.beams()) {
      // Orient: the stored order may run top-down (KITTI) or bottom-up.
      const auto mean_sin_elevation = [&](std::size_t b, std::size_t e) {
        double s = 0.0;
        for (std::size_t i = b; i < e; ++i) {
          const double n = static_cast<double>(scan.points[i].norm());
          if (n > 0.0) s += static_cast<double>(scan.points[i].z()) / n;
        }
        return s / static_cast<double>(e - b);
      };
      const std::size_t r = begins.size();
      const bool top_down = mean_sin_elevation(0, begins.size() > 1 ? begins[1] : scan.size()) >
                            mean_sin_elevation(begins[r - 1], scan.size());
      for (std::size_t k = 0; k < r; ++k) {
        const std::size_t e = (k + 1 < r) ? begins[k + 1] : scan.size();
        const auto ring = static_cast<std::uint16_t>(top_down ? r - 1 - k : k);
        for (std::size_t i = begins[k]; i < e; ++i) scan.rings[i] = ring;
      }
      report.used = RingMethod::kPointOrder;
      return report;
    }
    if (config.method == RingMethod::kPointOrder) {
      scan.rings.clear();
      throw ValueError("infer_rings: point order gives " + std::to_string(begins.size()) +
                       " rings but the sensor has " + std::to_string(sensor.beams()) + " beams");
    }
  }
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Eigen::Vector3f& p = scan.points[i];
    // Float coordinates square exactly in double: no hypot needed.
    const auto x = static_cast<double>(p.x());
    const auto y = static_cast<double>(p.y());
    scan.rings[i] = sensor.nearest_ring(atan2_fast(static_cast<double>(p.z()), std::sqrt(x * x + y * y)));
  }
  report.used = RingMethod::kElevation;
  return report;
}

/// As infer_rings(scan, sensor, config, workspace) with a local workspace
/// (allocates a little per call).
inline RingReport infer_rings(Scan& scan, const SensorModel& sensor, const RingConfig& config = {}) {
  std::vector<std::size_t> begins;
  return infer_rings(scan, sensor, config, begins);
}

/// Fills scan.times_s with each point's time since sweep start from its
/// azimuth: t = period * frac(+-(az - start) / 2pi), in [0, period). Only for
/// sensors whose sweep is one revolution (every spinning lidar).
inline void assign_times_from_azimuth(Scan& scan, const PointTimeConfig& config = {}) {
  if (!(config.sweep_period_s > 0.0) || !std::isfinite(config.sweep_period_s)) {
    throw ConfigError("PointTimeConfig.sweep_period_s must be positive, got " +
                      std::to_string(config.sweep_period_s));
  }
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  // Largest float time below the period (a time rounding up to it would
  // belong to the next sweep).
  const float t_last = std::nextafter(static_cast<float>(config.sweep_period_s), 0.0F);
  scan.times_s.resize(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Eigen::Vector3f& p = scan.points[i];
    double turned = atan2_fast(static_cast<double>(p.y()), static_cast<double>(p.x())) -
                    config.start_azimuth_rad;
    if (!config.counter_clockwise) turned = -turned;
    double frac = turned / kTwoPi;
    frac -= std::floor(frac);
    if (frac >= 1.0) frac = 0.0;  // rounding at the seam
    scan.times_s[i] = std::min(static_cast<float>(frac * config.sweep_period_s), t_last);
  }
}

/// Rotates point p about the horizontal axis perpendicular to its azimuth,
/// (y, -x, 0) / ||(x, y)||, by the angle whose cosine and sine are given: its
/// elevation grows by that angle while range and azimuth stay. Points on the
/// z axis are returned unchanged. (Per-point form: the caller evaluates the
/// trigonometry once per scan.)
inline Eigen::Vector3f correct_vertical_angle(const Eigen::Vector3f& p, double cos_angle, double sin_angle) {
  const Eigen::Vector3d q = p.cast<double>();
  const double h = std::sqrt(q.x() * q.x() + q.y() * q.y());  // float inputs: exact squares, no hypot needed
  if (!(h > 0.0)) return p;
  // Rodrigues with axis a = (y, -x, 0)/h, a.p = 0: p' = p cos + (a x p) sin,
  // a x p = (-x z / h, -y z / h, h).
  const Eigen::Vector3d axp(-q.x() * q.z() / h, -q.y() * q.z() / h, h);
  return (q * cos_angle + axp * sin_angle).cast<float>();
}

/// As above for an angle in radians.
inline Eigen::Vector3f correct_vertical_angle(const Eigen::Vector3f& p, double angle_rad) {
  return correct_vertical_angle(p, std::cos(angle_rad), std::sin(angle_rad));
}

/// KITTI's intrinsic fix (METHOD.md): raises every point's elevation by
/// angle_rad (default 0.205 deg as KISS-ICP and CT-ICP; IMLS-SLAM uses 0.195).
inline void correct_kitti_vertical_angle(Scan& scan, double angle_rad = kKittiVerticalCorrectionRad) {
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  std::vector<Eigen::Vector3f>& pts = scan.points;
  std::size_t i = 0;
#if defined(SEMLIO_EXACT_SSE2)
  // Two points at once, bit for bit the scalar correct_vertical_angle (the
  // same double operations in the same order; tests/features): ~1 % of a
  // frame on KITTI scans otherwise.
  const __m128d cv = _mm_set1_pd(c);
  const __m128d sv = _mm_set1_pd(s);
  const __m128d sign = _mm_set1_pd(-0.0);
  for (; i + 1 < pts.size(); i += 2) {
    Eigen::Vector3f& p = pts[i];
    Eigen::Vector3f& q = pts[i + 1];
    const __m128d x = _mm_set_pd(static_cast<double>(q.x()), static_cast<double>(p.x()));
    const __m128d y = _mm_set_pd(static_cast<double>(q.y()), static_cast<double>(p.y()));
    const __m128d z = _mm_set_pd(static_cast<double>(q.z()), static_cast<double>(p.z()));
    const __m128d h = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(x, x), _mm_mul_pd(y, y)));
    if (_mm_movemask_pd(_mm_cmpgt_pd(h, _mm_setzero_pd())) != 3) {  // a point on the z axis (or NaN)
      p = correct_vertical_angle(p, c, s);
      q = correct_vertical_angle(q, c, s);
      continue;
    }
    const __m128d ax = _mm_div_pd(_mm_mul_pd(_mm_xor_pd(x, sign), z), h);
    const __m128d ay = _mm_div_pd(_mm_mul_pd(_mm_xor_pd(y, sign), z), h);
    std::array<float, 4> ox;
    std::array<float, 4> oy;
    std::array<float, 4> oz;
    _mm_storeu_ps(ox.data(), _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x, cv), _mm_mul_pd(ax, sv))));
    _mm_storeu_ps(oy.data(), _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(y, cv), _mm_mul_pd(ay, sv))));
    _mm_storeu_ps(oz.data(), _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(z, cv), _mm_mul_pd(h, sv))));
    p = Eigen::Vector3f(ox[0], oy[0], oz[0]);
    q = Eigen::Vector3f(ox[1], oy[1], oz[1]);
  }
#endif
  for (; i < pts.size(); ++i) pts[i] = correct_vertical_angle(pts[i], c, s);
}

}  // namespace semlio
