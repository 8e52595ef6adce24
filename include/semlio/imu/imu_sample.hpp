#pragma once
/// \file
/// One inertial measurement.

#include <Eigen/Core>

namespace semlio {

/// One IMU measurement in the IMU body frame (x forward, y left, z up for
/// KITTI's OXTS unit). `accel_mps2` is specific force as an accelerometer
/// measures it (at rest it reads +g upwards, about (0, 0, 9.81)).
struct ImuSample {
  double stamp_s = 0.0;                                  ///< time [s]
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();  ///< angular rate [rad/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  ///< specific force [m/s^2]
};

}  // namespace semlio
