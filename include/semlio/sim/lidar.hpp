#pragma once
/// \file
/// Spinning-lidar models: beam layout, firing times, and the per-return model
/// (range noise, dropouts, intensity). The default LidarConfig is the Velodyne
/// HDL-64E as mounted on KITTI's car; lidar_config_for() gives the other
/// sensors users drive with (VLP-16, VLP-32C, HDL-32E, Ouster OS1-64 and
/// OS0-128). These tables are the simulator's own; the library-wide sensor
/// profiles (features/) are kept separately and should agree with them.
///
/// Conventions (the lidar frame is KITTI's velodyne frame: x forward, y left,
/// z up):
/// - Ring 0 is the lowest beam. The HDL-64E (default): the lower 32 beams are
///   spaced evenly from -24.9 to -8.83 deg (~0.52 deg), the upper 32 from
///   -8.33 to +2.0 deg (~1/3 deg), as in KITTI's layout. Other sensors either
///   fit the same two evenly spaced blocks (every uniform table does) or give
///   an explicit table (LidarConfig::elevations_deg, e.g. the VLP-32C).
/// - The head spins clockwise seen from above (azimuth atan2(y, x)
///   decreasing). A sweep starts facing backwards (azimuth +180 deg) at the
///   sweep start time, faces forward at half the period and ends facing
///   backwards again; this is also the time model KITTI tools (e.g. KISS-ICP)
///   assume. Column c fires at c / (steps * rate), all beams of a column at
///   that one time. Ouster sensors spin the same way: the Ouster SDK's
///   make_xyz_lut (ouster_client/src/lidar_scan.cpp) sets the encoder angle of
///   column v to 2 pi - v * 2 pi / w, i.e. clockwise, starting at the lidar
///   frame's +x, which points at the connector (the back of a forward-facing
///   mount, azimuth 180 deg in the sensor frame); all 64/128 pixels of a column
///   share one timestamp. Velodyne fires the beams of a column one after the
///   other (VLP-16/32C: 2.304 us apart, HDL-32E: 1.152 us; VLP-32C user manual
///   63-9325 Rev. C, section "Firing timing"): at most 37 us inside a 55 us
///   column, i.e. < 0.5 mm of travel at 11 m/s, so it is not modelled. Nor are
///   the per-beam azimuth offsets (VLP-32C +-1.4/4.2 deg, Ouster ~+-3 deg):
///   the simulator's rays lie on a regular range image.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/random.hpp>

namespace semlio::sim {

/// Settings of the lidar model; defaults reproduce KITTI's HDL-64E.
struct LidarConfig {
  int beams = 64;                        ///< number of rings (lower + upper block, split in half; = elevations_deg.size() when given)
  /// Explicit beam elevations [deg], strictly ascending (ring 0 = lowest),
  /// for sensors whose table is not two evenly spaced blocks (VLP-32C).
  /// Empty: the two-block layout of the four fields below.
  std::vector<double> elevations_deg;
  double upper_top_deg = 2.0;            ///< elevation of the highest beam [deg]
  double upper_bottom_deg = -8.33;       ///< elevation of the lowest upper-block beam [deg]
  double lower_top_deg = -8.83;          ///< elevation of the highest lower-block beam [deg]
  double lower_bottom_deg = -24.9;       ///< elevation of the lowest beam [deg]
  int azimuth_steps = 2160;              ///< firings per ring per sweep (~0.167 deg; KITTI keeps <= ~2150 per ring)
  double rate_hz = 10.0;                 ///< rotation rate [Hz]
  double max_range_m = 120.0;            ///< no return beyond this range [m]
  double min_range_m = 2.0;              ///< returns closer than this are dropped [m]
  double mount_height_m = 1.73;          ///< lidar origin above the ground under the vehicle [m]
  double range_noise_sigma_m = 0.02;     ///< Gaussian range noise [m]
  double intensity_noise_sigma = 0.02;   ///< Gaussian intensity noise
  double dropout_base = 0.01;            ///< drop probability of any return
  double grazing_cos = 0.12;             ///< below this cos(incidence) returns drop increasingly
  double far_dropout_start_m = 50.0;     ///< beyond this range the drop probability grows [m]
  bool noise = true;                     ///< false: exact ranges, no dropouts, noise-free intensity
  /// Ego-vehicle body in the lidar frame (box corners) [m]: beams that enter
  /// it never return (KITTI's car hides about half of the lowest ring, front
  /// and back). Set max <= min to disable.
  Eigen::Vector3d self_box_min = Eigen::Vector3d(-2.9, -0.95, -1.8);
  Eigen::Vector3d self_box_max = Eigen::Vector3d(2.0, 0.95, -0.7);
};

/// One candidate return before the noise model.
struct ReturnModel {
  bool keep = false;       ///< false: the return is dropped
  double range_m = 0.0;    ///< measured (noisy) range [m]
  float intensity = 0.0F;  ///< reflectance in [0, 0.99]
};

/// Beam geometry and return model. Immutable after construction; all methods
/// are const and thread-safe.
class Lidar {
 public:
  using Config = LidarConfig;

  /// Validates the config (throws ConfigError naming the field) and builds
  /// the beam tables.
  explicit Lidar(const LidarConfig& config = {}) : config_(config) {
    const bool table = !config_.elevations_deg.empty();
    if (table) {
      if (config_.beams != static_cast<int>(config_.elevations_deg.size())) {
        throw ConfigError("LidarConfig.beams (" + std::to_string(config_.beams) +
                          ") must equal the size of LidarConfig.elevations_deg (" +
                          std::to_string(config_.elevations_deg.size()) + ")");
      }
      for (std::size_t r = 0; r < config_.elevations_deg.size(); ++r) {
        const double e = config_.elevations_deg[r];
        if (!std::isfinite(e) || std::abs(e) >= 90.0 || (r > 0 && !(e > config_.elevations_deg[r - 1]))) {
          throw ConfigError("LidarConfig.elevations_deg[" + std::to_string(r) + "] = " + std::to_string(e) +
                            " is not finite, within (-90, 90) deg and strictly ascending");
        }
      }
    } else if (config_.beams < 2 || config_.beams % 2 != 0) {
      throw ConfigError("LidarConfig.beams must be even and >= 2, got " + std::to_string(config_.beams));
    }
    if (config_.azimuth_steps < 8) {
      throw ConfigError("LidarConfig.azimuth_steps must be >= 8, got " +
                        std::to_string(config_.azimuth_steps));
    }
    if (!(config_.rate_hz > 0.0)) {
      throw ConfigError("LidarConfig.rate_hz must be > 0, got " + std::to_string(config_.rate_hz));
    }
    if (!(config_.max_range_m > config_.min_range_m) || config_.min_range_m < 0.0) {
      throw ConfigError("LidarConfig range limits invalid: min " + std::to_string(config_.min_range_m) +
                        ", max " + std::to_string(config_.max_range_m));
    }
    const int half = config_.beams / 2;
    elevation_rad_.resize(static_cast<std::size_t>(config_.beams));
    for (int r = 0; r < config_.beams; ++r) {
      if (table) {
        elevation_rad_[static_cast<std::size_t>(r)] =
            config_.elevations_deg[static_cast<std::size_t>(r)] * std::numbers::pi / 180.0;
        continue;
      }
      const bool upper = r >= half;
      const double lo = upper ? config_.upper_bottom_deg : config_.lower_bottom_deg;
      const double hi = upper ? config_.upper_top_deg : config_.lower_top_deg;
      const int k = upper ? r - half : r;
      const double deg = half > 1 ? lo + (hi - lo) * k / (half - 1) : lo;
      elevation_rad_[static_cast<std::size_t>(r)] = deg * std::numbers::pi / 180.0;
    }
    const auto steps = static_cast<std::size_t>(config_.azimuth_steps);
    cos_az_.resize(steps);
    sin_az_.resize(steps);
    for (std::size_t c = 0; c < steps; ++c) {
      const double az = azimuth_rad(static_cast<int>(c));
      cos_az_[c] = std::cos(az);
      sin_az_[c] = std::sin(az);
    }
    // Self-occlusion mask: does the beam from the origin enter the body box?
    blocked_.assign(static_cast<std::size_t>(config_.beams) * steps, 0);
    const Eigen::Vector3d& lo = config_.self_box_min;
    const Eigen::Vector3d& hi = config_.self_box_max;
    if ((hi - lo).minCoeff() > 0.0) {
      for (int r = 0; r < config_.beams; ++r) {
        for (std::size_t c = 0; c < steps; ++c) {
          const Eigen::Vector3d d = direction(r, static_cast<int>(c));
          double t0 = 0.0;
          double t1 = 1e9;
          for (int k = 0; k < 3; ++k) {
            if (d[k] == 0.0) {
              if (lo[k] > 0.0 || hi[k] < 0.0) t0 = 2e9;
              continue;
            }
            double a = lo[k] / d[k];
            double b = hi[k] / d[k];
            if (a > b) std::swap(a, b);
            t0 = std::max(t0, a);
            t1 = std::min(t1, b);
          }
          blocked_[static_cast<std::size_t>(r) * steps + c] = t0 <= t1 ? 1 : 0;
        }
      }
    }
  }

  /// True when the beam (ring, column) is hidden by the ego vehicle's body.
  [[nodiscard]] bool self_occluded(int ring, int column) const {
    return blocked_[static_cast<std::size_t>(ring) * static_cast<std::size_t>(config_.azimuth_steps) +
                    static_cast<std::size_t>(column)] != 0;
  }

  /// The configuration.
  [[nodiscard]] const LidarConfig& config() const noexcept { return config_; }
  /// Number of rings.
  [[nodiscard]] int rings() const noexcept { return config_.beams; }
  /// Firings per ring per sweep.
  [[nodiscard]] int columns() const noexcept { return config_.azimuth_steps; }
  /// Sweep period [s].
  [[nodiscard]] double period_s() const noexcept { return 1.0 / config_.rate_hz; }
  /// Elevation of a ring [rad] (ring 0 = lowest).
  [[nodiscard]] double elevation_rad(int ring) const { return elevation_rad_[static_cast<std::size_t>(ring)]; }
  /// Azimuth of column c [rad]: +pi at c = 0, decreasing (clockwise spin).
  [[nodiscard]] double azimuth_rad(int column) const {
    return std::numbers::pi - 2.0 * std::numbers::pi * column / config_.azimuth_steps;
  }
  /// Firing time of column c since sweep start [s].
  [[nodiscard]] double column_time_s(int column) const {
    return static_cast<double>(column) / (config_.azimuth_steps * config_.rate_hz);
  }
  /// Unit direction of (ring, column) in the lidar frame.
  [[nodiscard]] Eigen::Vector3d direction(int ring, int column) const {
    const double el = elevation_rad(ring);
    const double ce = std::cos(el);
    const auto c = static_cast<std::size_t>(column);
    return {ce * cos_az_[c], ce * sin_az_[c], std::sin(el)};
  }

  /// Applies the sensor model to an exact hit at `range_m` with incidence
  /// cosine `cos_incidence` (|n . d|) on a surface of `reflectivity`; `key`
  /// identifies the ray (seed, frame, ring, column) for the noise draws.
  [[nodiscard]] ReturnModel measure(double range_m, double cos_incidence, double reflectivity,
                                    std::uint64_t key) const {
    ReturnModel out;
    if (range_m > config_.max_range_m || range_m < config_.min_range_m) return out;
    const double refl = std::clamp(reflectivity, 0.0, 1.0);
    const double ci = std::clamp(cos_incidence, 0.0, 1.0);
    // Intensity: Lambertian-like falloff with incidence, mild range falloff.
    double intensity = refl * (0.45 + 0.55 * ci) * (1.0 - 0.3 * range_m / config_.max_range_m);
    if (!config_.noise) {
      out.keep = true;
      out.range_m = range_m;
      out.intensity = static_cast<float>(std::clamp(intensity, 0.0, 0.99));
      return out;
    }
    const std::uint64_t h0 = mix64(key);
    const std::uint64_t h1 = mix64(h0);
    const std::uint64_t h2 = mix64(h1);
    const std::uint64_t h3 = mix64(h2);
    const std::uint64_t h4 = mix64(h3);
    // Dropouts: a floor, grazing incidence, and weak far returns (dark
    // surfaces drop first).
    double p_drop = config_.dropout_base;
    if (ci < config_.grazing_cos) p_drop += 0.85 * (config_.grazing_cos - ci) / config_.grazing_cos;
    if (range_m > config_.far_dropout_start_m) {
      const double u = (range_m - config_.far_dropout_start_m) /
                       std::max(config_.max_range_m - config_.far_dropout_start_m, 1e-6);
      p_drop += u * u * (1.0 - 0.6 * refl);
    }
    if (unit_from_bits(h0) < p_drop) return out;
    out.keep = true;
    out.range_m = range_m + config_.range_noise_sigma_m * normal_from_bits(h1, h2);
    intensity += config_.intensity_noise_sigma * normal_from_bits(h3, h4);
    out.intensity = static_cast<float>(std::clamp(intensity, 0.0, 0.99));
    return out;
  }

 private:
  LidarConfig config_;
  std::vector<double> elevation_rad_;
  std::vector<double> cos_az_;
  std::vector<double> sin_az_;
  std::vector<std::uint8_t> blocked_;
};

/// Names lidar_config_for() accepts, the default (KITTI's HDL-64E) first.
inline constexpr std::array<std::string_view, 6> kLidarSensors = {"hdl64e", "vlp16",  "vlp32c",
                                                                 "hdl32e", "os1-64", "os0-128"};

/// True for the Ouster sensors of kLidarSensors ("os1-64", "os0-128"): their
/// driver publishes per-point time as `t` (uint32 ns), Velodyne's as `time`
/// (float32 s).
[[nodiscard]] inline bool lidar_is_ouster(std::string_view sensor) noexcept { return sensor.substr(0, 2) == "os"; }

namespace detail {

/// `beams` evenly spaced beams from bottom_deg to top_deg as the two-block
/// layout (both blocks share the spacing, so the table is uniform).
inline void set_uniform_beams(LidarConfig& c, int beams, double bottom_deg, double top_deg) {
  const double step = (top_deg - bottom_deg) / (beams - 1);
  const int half = beams / 2;
  c.beams = beams;
  c.elevations_deg.clear();
  c.lower_bottom_deg = bottom_deg;
  c.lower_top_deg = bottom_deg + step * (half - 1);
  c.upper_bottom_deg = bottom_deg + step * half;
  c.upper_top_deg = top_deg;
}

}  // namespace detail

/// The simulator's model of a named sensor (one of kLidarSensors; throws
/// ConfigError naming the value otherwise), at 10 Hz on a car roof (mount
/// height 1.8 m; the HDL-64E keeps KITTI's 1.73 m). Every field stays
/// editable afterwards (e.g. azimuth_steps = 2048 for Ouster's 2048x10 mode).
/// Sources (datasheets / user manuals):
/// - hdl64e: KITTI's layout (see the file comment), 2160 columns, 120 m.
/// - vlp16: 16 beams -15..+15 deg, 2 deg apart; 0.2 deg azimuth at 10 Hz
///   (1800 columns); 100 m; +-3 cm.
/// - vlp32c: 32 beams -25..+15 deg on the non-uniform table of the VLP-32C
///   user manual (63-9325 Rev. C; dense, 1/3 deg, around the horizon); 0.2 deg
///   at 10 Hz (1800 columns); 200 m; +-3 cm.
/// - hdl32e: 32 beams from -30.67 deg, 4/3 deg apart (to +10.67); a 46.08 us
///   firing cycle, i.e. 2170 columns at 10 Hz; 100 m; +-2 cm.
/// - os1-64: 64 beams uniform over 45 deg (+-22.5), 1024 columns (1024x10
///   mode); 120 m (Rev 6, 80 % reflectance); +-3 cm.
/// - os0-128: 128 beams uniform over 90 deg (+-45), 1024 columns; 50 m.
/// The far-dropout onset scales with the range (0.4 of it, as the HDL-64E's
/// 50 of 120 m). The ego-vehicle box stays KITTI's car.
[[nodiscard]] inline LidarConfig lidar_config_for(std::string_view sensor) {
  LidarConfig c;
  if (sensor == "hdl64e") return c;
  c.mount_height_m = 1.8;
  if (sensor == "vlp16") {
    detail::set_uniform_beams(c, 16, -15.0, 15.0);
    c.azimuth_steps = 1800;
    c.max_range_m = 100.0;
    c.min_range_m = 0.9;
    c.range_noise_sigma_m = 0.03;
  } else if (sensor == "vlp32c") {
    c.elevations_deg = {-25.0,  -15.639, -11.31, -8.843, -7.254, -6.148, -5.333, -4.667,
                        -4.0,   -3.667,  -3.333, -3.0,   -2.667, -2.333, -2.0,   -1.667,
                        -1.333, -1.0,    -0.667, -0.333, 0.0,    0.333,  0.667,  1.0,
                        1.333,  1.667,   2.333,  3.333,  4.667,  7.0,    10.333, 15.0};
    c.beams = static_cast<int>(c.elevations_deg.size());
    // The block fields are unused with a table; they keep its limits so that
    // anything printing them (sim.json) stays truthful about the extent.
    c.lower_bottom_deg = c.elevations_deg.front();
    c.lower_top_deg = c.elevations_deg[15];
    c.upper_bottom_deg = c.elevations_deg[16];
    c.upper_top_deg = c.elevations_deg.back();
    c.azimuth_steps = 1800;
    c.max_range_m = 200.0;
    c.min_range_m = 0.9;
    c.range_noise_sigma_m = 0.03;
  } else if (sensor == "hdl32e") {
    detail::set_uniform_beams(c, 32, -30.67, -30.67 + 31.0 * 4.0 / 3.0);
    c.azimuth_steps = 2170;
    c.max_range_m = 100.0;
    c.min_range_m = 1.0;
  } else if (sensor == "os1-64") {
    detail::set_uniform_beams(c, 64, -22.5, 22.5);
    c.azimuth_steps = 1024;
    c.max_range_m = 120.0;
    c.min_range_m = 0.8;
    c.range_noise_sigma_m = 0.03;
  } else if (sensor == "os0-128") {
    detail::set_uniform_beams(c, 128, -45.0, 45.0);
    c.azimuth_steps = 1024;
    c.max_range_m = 50.0;
    c.min_range_m = 0.5;
    c.range_noise_sigma_m = 0.03;
  } else {
    std::string names;
    for (const std::string_view n : kLidarSensors) {
      if (!names.empty()) names += ", ";
      names += n;
    }
    throw ConfigError("unknown lidar sensor '" + std::string(sensor) + "' (expected one of " + names + ")");
  }
  c.far_dropout_start_m = 0.4 * c.max_range_m;
  return c;
}

}  // namespace semlio::sim
