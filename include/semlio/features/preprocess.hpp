#pragma once
/// \file
/// Scan clean-up before feature extraction: drops non-finite and exact
/// (0,0,0) points (sensor "no return"), points closer than min_range_m or
/// farther than max_range_m, and points inside an ego-vehicle box; counts
/// every reason; optionally applies KITTI's vertical-angle correction to the
/// kept points. In place, order kept, all optional fields kept in step.
/// Rings (rings.hpp) may be inferred before or after: filtering keeps the
/// point order, and on the real KITTI scans both orders give identical rings
/// (checked in test_preprocess.cpp).

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/rings.hpp>

namespace semlio {

/// Settings of preprocess(). Ranges are Euclidean distances from the sensor
/// origin. The default box is a Passat-sized car (KITTI's) around an HDL-64E
/// on its roof, in the lidar frame (x forward, y left, z up; sensor 1.73 m
/// above the road): it removes returns from the vehicle and the roof rack.
struct PreprocessConfig {
  double min_range_m = 1.0;    ///< drop nearer points [m] (LIO-SAM's lidarMinRange)
  double max_range_m = 100.0;  ///< drop farther points [m] (KISS-ICP's KITTI default)
  bool crop_ego_box = true;    ///< drop points inside the box below
  Eigen::Vector3d ego_box_min_m{-2.7, -1.1, -1.8};  ///< box corner, lidar frame [m]
  Eigen::Vector3d ego_box_max_m{1.9, 1.1, 0.3};     ///< box corner, lidar frame [m]
  double vertical_correction_rad = 0.0;  ///< elevation added to kept points [rad]; KITTI: kKittiVerticalCorrectionRad

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    if (!(min_range_m >= 0.0) || !std::isfinite(min_range_m)) {
      throw ConfigError("PreprocessConfig.min_range_m must be >= 0, got " + std::to_string(min_range_m));
    }
    if (!(max_range_m > min_range_m)) {
      throw ConfigError("PreprocessConfig.max_range_m must exceed min_range_m, got " +
                        std::to_string(max_range_m));
    }
    if (crop_ego_box && !(ego_box_min_m.array() <= ego_box_max_m.array()).all()) {
      throw ConfigError("PreprocessConfig.ego_box_min_m must be <= ego_box_max_m per axis");
    }
    if (!std::isfinite(vertical_correction_rad) || std::abs(vertical_correction_rad) > 0.1) {
      throw ConfigError("PreprocessConfig.vertical_correction_rad must be within +-0.1 rad, got " +
                        std::to_string(vertical_correction_rad));
    }
  }
};

/// Counts of what preprocess() dropped, by first failing reason in the order
/// non-finite, zero, min range, max range, ego box.
struct PreprocessReport {
  std::size_t input = 0;              ///< points before
  std::size_t kept = 0;               ///< points after
  std::size_t dropped_nonfinite = 0;  ///< NaN / Inf coordinate
  std::size_t dropped_zero = 0;       ///< exactly (0,0,0)
  std::size_t dropped_min_range = 0;  ///< range < min_range_m
  std::size_t dropped_max_range = 0;  ///< range > max_range_m
  std::size_t dropped_ego_box = 0;    ///< inside the ego-vehicle box
};

/// Filters scan in place (see PreprocessConfig); allocates nothing.
inline PreprocessReport preprocess(Scan& scan, const PreprocessConfig& config = {}) {
  config.validate();
  scan.validate();
  PreprocessReport report;
  report.input = scan.size();
  const double min2 = config.min_range_m * config.min_range_m;
  const double max2 = config.max_range_m * config.max_range_m;
  const Eigen::Vector3f lo = config.ego_box_min_m.cast<float>();
  const Eigen::Vector3f hi = config.ego_box_max_m.cast<float>();
  filter_in_place(scan, [&](std::size_t i) {
    const Eigen::Vector3f& p = scan.points[i];
    if (!p.allFinite()) {
      ++report.dropped_nonfinite;
      return false;
    }
    if (p.x() == 0.0F && p.y() == 0.0F && p.z() == 0.0F) {
      ++report.dropped_zero;
      return false;
    }
    const double r2 = p.cast<double>().squaredNorm();
    if (r2 < min2) {
      ++report.dropped_min_range;
      return false;
    }
    if (r2 > max2) {
      ++report.dropped_max_range;
      return false;
    }
    if (config.crop_ego_box && (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) {
      ++report.dropped_ego_box;
      return false;
    }
    return true;
  });
  report.kept = scan.size();
  if (config.vertical_correction_rad != 0.0) correct_kitti_vertical_angle(scan, config.vertical_correction_rad);
  return report;
}

/// The defaults for KITTI scans: as PreprocessConfig{} plus the 0.205 deg
/// vertical-angle correction (METHOD.md: on for KITTI).
inline PreprocessConfig kitti_preprocess_config() {
  PreprocessConfig config;
  config.vertical_correction_rad = kKittiVerticalCorrectionRad;
  return config;
}

}  // namespace semlio
