#pragma once
/// \file
/// Named spinning-lidar profiles: beam table, rotation rate, range limits,
/// a typical mount height, what a driver's message stamp means, and the spin
/// direction and sweep start azimuth that per-point time from azimuth needs
/// (rings.hpp, assign_times_from_azimuth).
///
/// Beam tables and where they come from (elevations in degrees, ascending):
/// - hdl64e, hdl32e: SensorModel::hdl64e() / hdl32e() (sensor_model.hpp;
///   hdl64e is nominal -- KITTI's per-unit calibration spreads it).
/// - vlp16: -15 .. +15 by 2 (Velodyne VLP-16 manual; exact by design).
/// - vlp32c: Velodyne's non-uniform VLP-32C table (-25 .. +15, densest near
///   the horizon, 0.333 deg there), as in the velodyne_pointcloud VLP-32C
///   calibration file.
/// - os0/os1/os2-32/64/128: NOMINAL. Ouster's "uniform" beam configuration
///   spaces the beams evenly over the vertical field of view (OS0 90 deg,
///   OS1 45 deg, OS2 22.5 deg, centred on the horizon). Real units report
///   their own beam_altitude_angles (sensor metadata); gradient and
///   below-horizon variants exist. Use beam detection (beam_detection.hpp)
///   or a YAML table when the metadata is at hand.
/// - pandar-xt32: -16 .. +15 by 1 (Hesai PandarXT-32 manual: 31 deg, 1 deg
///   resolution).
/// - pandar64: Hesai's Pandar64 angle table (-24.897 .. +14.882; 0.167 deg
///   between -6 and +2 deg), nominal: each unit ships a correction file.
///
/// Header stamps (what a ROS driver's PointCloud2 header.stamp means):
/// - Velodyne (ros-drivers/velodyne, velodyne_driver): the scan is stamped
///   with the time of its LAST packet unless the driver's
///   `timestamp_first_packet` parameter is true (its default is false): kSweepEnd.
/// - Ouster (ouster-lidar/ouster-ros, issue #114 by the maintainers): "we use
///   the timestamp value of the first valid column in the scan as the point
///   cloud timestamp": kSweepStart.
/// - Hesai: assumed kSweepStart (the Hesai ROS drivers also write an absolute
///   per-point `timestamp`; prefer it when present). Not verified here.
///
/// Spin: every Velodyne spins clockwise seen from above (rings.hpp measures
/// it on KITTI raw). The Ouster recording in the shared data set (BALM, OS0
/// class) stores its points column by column with atan2(y, x) decreasing from
/// +174 deg: clockwise from the rear (x points away from the connector; the
/// first column of an Ouster frame is at the back), so Ouster profiles use
/// start azimuth pi, clockwise. Velodyne: the sweep is cut where the driver
/// cuts it (default: facing forward), start azimuth 0 as KITTI raw.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_model.hpp>

namespace semlio {

/// What a lidar driver's message stamp refers to within its sweep.
enum class StampMeaning : std::uint8_t {
  kSweepStart,   ///< time of the first point (Ouster)
  kSweepMiddle,  ///< middle of the sweep (KITTI raw's timestamps.txt)
  kSweepEnd,     ///< time of the last point (Velodyne ROS driver default)
};

/// Name of a StampMeaning, as written to YAML and report.json.
constexpr const char* to_string(StampMeaning s) noexcept {
  switch (s) {
    case StampMeaning::kSweepStart: return "start";
    case StampMeaning::kSweepMiddle: return "middle";
    case StampMeaning::kSweepEnd: return "end";
  }
  return "unknown";
}

/// A spinning lidar model with the facts the pipeline's settings derive from.
struct SensorProfile {
  std::string name;                    ///< profile name (lower case, e.g. "os0-64")
  SensorModel beams;                   ///< beam elevation table and rotation rate
  double min_range_m = 1.0;            ///< nearest usable return [m]
  double max_range_m = 100.0;          ///< farthest usable return [m]
  double mount_height_m = 1.73;        ///< typical height above the ground (ground segmenter) [m]
  StampMeaning header_stamp = StampMeaning::kSweepEnd;  ///< meaning of a driver's message stamp
  bool counter_clockwise = false;      ///< spin direction seen from above (atan2(y, x) increasing)
  double sweep_start_azimuth_rad = 0.0;  ///< atan2(y, x) where a sweep starts [rad]
  bool nominal_table = false;          ///< the table is a datasheet's nominal one (units differ)

  /// Vertical field of view: highest minus lowest beam elevation [rad].
  [[nodiscard]] double vertical_fov_rad() const {
    return beams.elevations_rad.empty() ? 0.0 : beams.elevations_rad.back() - beams.elevations_rad.front();
  }

  /// Sweep duration 1 / rotation rate [s].
  [[nodiscard]] double sweep_period_s() const { return 1.0 / beams.rotation_rate_hz; }

  /// Per-point time from azimuth for this sensor (rings.hpp).
  [[nodiscard]] PointTimeConfig point_time_config() const {
    return PointTimeConfig{.sweep_period_s = sweep_period_s(),
                           .start_azimuth_rad = sweep_start_azimuth_rad,
                           .counter_clockwise = counter_clockwise};
  }

  /// Throws ConfigError naming the profile and the bad field unless the beam
  /// table is valid (SensorModel::validate), 0 <= min_range_m < max_range_m,
  /// the mount height is finite and the start azimuth is finite.
  void validate() const {
    try {
      beams.validate();
    } catch (const ConfigError& e) {
      throw ConfigError("SensorProfile '" + name + "': " + e.what());
    }
    if (!(min_range_m >= 0.0) || !(max_range_m > min_range_m) || !std::isfinite(max_range_m)) {
      throw ConfigError("SensorProfile '" + name + "': ranges must satisfy 0 <= min_range_m < max_range_m, got " +
                        std::to_string(min_range_m) + " and " + std::to_string(max_range_m));
    }
    if (!std::isfinite(mount_height_m)) {
      throw ConfigError("SensorProfile '" + name + "': mount_height_m must be finite, got " +
                        std::to_string(mount_height_m));
    }
    if (!std::isfinite(sweep_start_azimuth_rad)) {
      throw ConfigError("SensorProfile '" + name + "': sweep_start_azimuth_rad must be finite");
    }
  }
};

namespace detail {

/// Degrees (ascending) to a beam table.
inline SensorModel table_from_degrees(const std::vector<double>& deg, double rate_hz) {
  SensorModel m;
  m.rotation_rate_hz = rate_hz;
  m.elevations_rad.reserve(deg.size());
  for (const double d : deg) m.elevations_rad.push_back(d * std::numbers::pi / 180.0);
  std::sort(m.elevations_rad.begin(), m.elevations_rad.end());
  return m;
}

/// `beams` elevations evenly spaced from -fov/2 to +fov/2 (Ouster "uniform").
inline SensorModel uniform_table(int beams, double fov_deg, double rate_hz) {
  std::vector<double> deg;
  for (int i = 0; i < beams; ++i) deg.push_back(-fov_deg / 2.0 + fov_deg * i / (beams - 1));
  return table_from_degrees(deg, rate_hz);
}

/// An Ouster profile: nominal uniform table, 10 Hz, stamped at sweep start,
/// clockwise from the rear (file comment).
inline SensorProfile ouster(const std::string& name, int beams, double fov_deg, double min_m, double max_m) {
  SensorProfile p;
  p.name = name;
  p.beams = uniform_table(beams, fov_deg, 10.0);
  p.min_range_m = min_m;
  p.max_range_m = max_m;
  p.mount_height_m = 1.0;  // robots and hand-held rigs; no single typical mount
  p.header_stamp = StampMeaning::kSweepStart;
  p.counter_clockwise = false;
  p.sweep_start_azimuth_rad = std::numbers::pi;
  p.nominal_table = true;
  return p;
}

/// A Velodyne profile: 10 Hz, stamped at sweep end, clockwise from the front.
inline SensorProfile velodyne(const std::string& name, SensorModel table, double min_m, double max_m,
                              double height_m, bool nominal) {
  SensorProfile p;
  p.name = name;
  p.beams = std::move(table);
  p.min_range_m = min_m;
  p.max_range_m = max_m;
  p.mount_height_m = height_m;
  p.header_stamp = StampMeaning::kSweepEnd;
  p.counter_clockwise = false;
  p.sweep_start_azimuth_rad = kKittiSweepStartAzimuthRad;
  p.nominal_table = nominal;
  return p;
}

/// A Hesai profile: 10 Hz, stamp assumed at sweep start (file comment).
inline SensorProfile hesai(const std::string& name, SensorModel table, double min_m, double max_m) {
  SensorProfile p;
  p.name = name;
  p.beams = std::move(table);
  p.min_range_m = min_m;
  p.max_range_m = max_m;
  p.mount_height_m = 1.8;
  p.header_stamp = StampMeaning::kSweepStart;
  p.counter_clockwise = false;
  p.sweep_start_azimuth_rad = 0.0;
  p.nominal_table = true;
  return p;
}

}  // namespace detail

/// Names accepted by sensor_profile(), in a stable order.
inline const std::vector<std::string>& sensor_profile_names() {
  static const std::vector<std::string> names = {
      "hdl64e", "hdl32e", "vlp16",   "vlp32c",   "os0-32",   "os0-64",      "os0-128", "os1-32",
      "os1-64", "os1-128", "os2-32", "os2-64", "os2-128", "pandar-xt32", "pandar64"};
  return names;
}

/// The named profile (case-sensitive, as sensor_profile_names()); throws
/// ConfigError listing the known names for any other name.
inline SensorProfile sensor_profile(std::string_view name) {
  using detail::ouster;
  using detail::velodyne;
  const std::string n(name);
  if (n == "hdl64e") return velodyne(n, SensorModel::hdl64e(), 0.9, 120.0, 1.73, true);
  if (n == "hdl32e") return velodyne(n, SensorModel::hdl32e(), 1.0, 100.0, 1.8, false);
  if (n == "vlp16") {
    std::vector<double> deg;
    for (int k = -15; k <= 15; k += 2) deg.push_back(k);
    return velodyne(n, detail::table_from_degrees(deg, 10.0), 0.4, 100.0, 1.0, false);
  }
  if (n == "vlp32c") {
    const std::vector<double> deg = {-25.0,  -15.639, -11.31, -8.843, -7.254, -6.148, -5.333, -4.667,
                                     -4.0,   -3.667,  -3.333, -3.0,   -2.667, -2.333, -2.0,   -1.667,
                                     -1.333, -1.0,    -0.667, -0.333, 0.0,    0.333,  0.667,  1.0,
                                     1.333,  1.667,   2.333,  3.333,  4.667,  7.0,    10.333, 15.0};
    return velodyne(n, detail::table_from_degrees(deg, 10.0), 1.0, 200.0, 1.8, false);
  }
  // Ouster ranges: datasheet minimum and maximum (OS0 50 m, OS1 120 m, OS2 240 m at 10 Hz).
  if (n == "os0-32") return ouster(n, 32, 90.0, 0.3, 50.0);
  if (n == "os0-64") return ouster(n, 64, 90.0, 0.3, 50.0);
  if (n == "os0-128") return ouster(n, 128, 90.0, 0.3, 50.0);
  if (n == "os1-32") return ouster(n, 32, 45.0, 0.5, 120.0);
  if (n == "os1-64") return ouster(n, 64, 45.0, 0.5, 120.0);
  if (n == "os1-128") return ouster(n, 128, 45.0, 0.5, 120.0);
  if (n == "os2-32") return ouster(n, 32, 22.5, 1.0, 240.0);
  if (n == "os2-64") return ouster(n, 64, 22.5, 1.0, 240.0);
  if (n == "os2-128") return ouster(n, 128, 22.5, 1.0, 240.0);
  if (n == "pandar-xt32") {
    std::vector<double> deg;
    for (int k = -16; k <= 15; ++k) deg.push_back(k);
    return detail::hesai(n, detail::table_from_degrees(deg, 10.0), 0.05, 120.0);
  }
  if (n == "pandar64") {
    const std::vector<double> deg = {
        14.882, 11.032, 8.059,  5.057,  3.04,   2.028,  1.86,   1.688,   1.522,   1.351,   1.184,  1.013,  0.846,
        0.675,  0.508,  0.337,  0.169,  0.0,    -0.169, -0.337, -0.508,  -0.675,  -0.845,  -1.013, -1.184, -1.351,
        -1.522, -1.688, -1.86,  -2.028, -2.198, -2.365, -2.536, -2.7,    -2.873,  -3.04,   -3.21,  -3.375, -3.548,
        -3.712, -3.884, -4.05,  -4.221, -4.385, -4.558, -4.72,  -4.892,  -5.057,  -5.229,  -5.391, -5.565, -5.726,
        -5.898, -6.061, -7.063, -8.059, -9.06,  -9.885, -11.032, -12.006, -12.974, -13.93, -18.889, -24.897};
    return detail::hesai(n, detail::table_from_degrees(deg, 10.0), 0.3, 200.0);
  }
  std::string known;
  for (const std::string& k : sensor_profile_names()) known += (known.empty() ? "" : ", ") + k;
  throw ConfigError("unknown sensor profile '" + n + "'; known profiles: " + known);
}

}  // namespace semlio
