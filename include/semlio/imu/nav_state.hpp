#pragma once
/// \file
/// Navigation state and IMU bias: the values an IMU prediction and an IMU
/// factor talk about. Frames: world z up (gravity (0, 0, -g)); body = the IMU.

#include <Eigen/Core>

#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

namespace semlio {

/// Gyroscope and accelerometer biases, in the IMU frame. A measurement is
/// truth + bias + noise, so the bias is subtracted from each sample.
struct ImuBias {
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();  ///< gyro bias [rad/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  ///< accelerometer bias [m/s^2]
};

/// Pose and velocity of the IMU in the world frame at one time.
struct NavState {
  SO3d R_world_imu;                                       ///< orientation (maps IMU vectors to world)
  Eigen::Vector3d p_world_m = Eigen::Vector3d::Zero();    ///< IMU position in the world [m]
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();  ///< IMU velocity in the world [m/s]

  /// The pose T_world_imu.
  [[nodiscard]] SE3d pose() const { return SE3d(R_world_imu, p_world_m); }
};

}  // namespace semlio
