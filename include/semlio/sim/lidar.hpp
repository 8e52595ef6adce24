#pragma once
/// \file
/// A Velodyne HDL-64E model as mounted on KITTI's car: beam layout, firing
/// times, and the per-return model (range noise, dropouts, intensity).
///
/// Conventions (the lidar frame is KITTI's velodyne frame: x forward, y left,
/// z up):
/// - Ring 0 is the lowest beam (-24.9 deg), ring 63 the highest (+2 deg). The
///   lower 32 beams are spaced evenly from -24.9 to -8.83 deg (~0.52 deg), the
///   upper 32 from -8.33 to +2.0 deg (~1/3 deg), as in KITTI's layout.
/// - The head spins clockwise seen from above (azimuth atan2(y, x)
///   decreasing), like the real HDL-64E. A sweep starts facing backwards
///   (azimuth +180 deg) at the sweep start time, faces forward at half the
///   period and ends facing backwards again; this is also the time model
///   KITTI tools (e.g. KISS-ICP) assume. Column c fires at c / (steps * rate).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/random.hpp>

namespace semlio::sim {

/// Settings of the lidar model; defaults reproduce KITTI's HDL-64E.
struct LidarConfig {
  int beams = 64;                        ///< number of rings (lower + upper block, split in half)
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
    if (config_.beams < 2 || config_.beams % 2 != 0) {
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

}  // namespace semlio::sim
