#pragma once
/// \file
/// A spinning lidar described by its table of beam elevations. Ring i is the
/// i-th beam counted from the lowest (Scan::rings convention: 0 = lowest).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>

namespace semlio {

/// Beam elevations of a spinning lidar and its rotation rate.
struct SensorModel {
  std::vector<double> elevations_rad;  ///< one per beam, strictly ascending (ring 0 = lowest) [rad]
  double rotation_rate_hz = 10.0;      ///< sweeps per second [Hz]

  /// Number of beams (rings).
  [[nodiscard]] std::size_t beams() const { return elevations_rad.size(); }

  /// Throws ConfigError unless there are 1..65535 finite, strictly ascending
  /// elevations within (-pi/2, pi/2) and a positive finite rotation rate.
  void validate() const {
    if (elevations_rad.empty() || elevations_rad.size() > 65535) {
      throw ConfigError("SensorModel.elevations_rad must hold 1..65535 beams, got " +
                        std::to_string(elevations_rad.size()));
    }
    for (std::size_t i = 0; i < elevations_rad.size(); ++i) {
      const double e = elevations_rad[i];
      if (!std::isfinite(e) || std::abs(e) >= std::numbers::pi / 2.0 ||
          (i > 0 && !(e > elevations_rad[i - 1]))) {
        throw ConfigError("SensorModel.elevations_rad[" + std::to_string(i) + "] = " +
                          std::to_string(e) + " is not finite, within (-pi/2, pi/2) and ascending");
      }
    }
    if (!(rotation_rate_hz > 0.0) || !std::isfinite(rotation_rate_hz)) {
      throw ConfigError("SensorModel.rotation_rate_hz must be positive, got " +
                        std::to_string(rotation_rate_hz));
    }
  }

  /// Ring (beam index) whose elevation is nearest to elevation_rad; elevations
  /// outside the table map to the lowest / highest beam. O(log beams).
  [[nodiscard]] std::uint16_t nearest_ring(double elevation_rad) const {
    const auto it = std::lower_bound(elevations_rad.begin(), elevations_rad.end(), elevation_rad);
    if (it == elevations_rad.begin()) return 0;
    if (it == elevations_rad.end()) return static_cast<std::uint16_t>(elevations_rad.size() - 1);
    const auto hi = static_cast<std::size_t>(it - elevations_rad.begin());
    const bool lower_is_nearer = (elevation_rad - *(it - 1)) <= (*it - elevation_rad);
    return static_cast<std::uint16_t>(lower_is_nearer ? hi - 1 : hi);
  }

  /// Nominal Velodyne HDL-64E S2 (KITTI): 32 upper beams from -8.33 to +2.0
  /// deg (1/3 deg apart) and 32 lower beams from -24.33 to -8.83 deg (1/2 deg
  /// apart), 10 Hz. KITTI's per-unit calibration differs from these nominal
  /// angles by up to ~0.6 deg (and elevation seen from the sensor origin varies
  /// with range), so on KITTI infer rings from point order (rings.hpp), not
  /// from this table.
  static SensorModel hdl64e() {
    SensorModel m;
    constexpr double kDeg = std::numbers::pi / 180.0;
    for (int k = 31; k >= 0; --k) m.elevations_rad.push_back((-8.83 - 0.5 * k) * kDeg);
    for (int k = 31; k >= 0; --k) m.elevations_rad.push_back((2.0 - k / 3.0) * kDeg);
    return m;
  }

  /// Velodyne HDL-32E: 32 beams from -30.67 to +10.67 deg, 4/3 deg apart, 10 Hz
  /// (the real scan pair in tests/data/scan_pair matches it to 0.01 deg).
  static SensorModel hdl32e() {
    SensorModel m;
    constexpr double kDeg = std::numbers::pi / 180.0;
    for (int k = 0; k < 32; ++k) m.elevations_rad.push_back((-30.67 + k * 4.0 / 3.0) * kDeg);
    return m;
  }
};

}  // namespace semlio
