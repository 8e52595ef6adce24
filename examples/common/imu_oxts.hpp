#pragma once
// KITTI raw OXTS -> the inputs of semlio::LidarInertialOdometry, shared by
// semlio_kitti and semlio_lio: IMU samples, the INS velocity in the IMU frame
// (an optional start-up hint, LidarInertialOdometry::push_velocity) and the
// lidar-IMU clock offset.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <string>
#include <vector>

#include <semlio/imu/imu_sample.hpp>
#include <semlio/io/oxts.hpp>

namespace semlio_examples {

/// One INS velocity of the IMU in its own frame at an OXTS stamp.
struct OxtsVelocity {
  double stamp_s = 0.0;
  Eigen::Vector3d v_imu_mps = Eigen::Vector3d::Zero();
};

/// OXTS vf, vl, vu (forward/left parallel to the earth surface, up) rotated
/// into the IMU frame: v_imu = (Ry(pitch) Rx(roll))^T v_flu, the heading frame
/// being Rz(yaw) of the OXTS orientation R = Rz Ry Rx.
inline std::vector<OxtsVelocity> oxts_velocities(const std::vector<semlio::io::OxtsRecord>& records) {
  std::vector<OxtsVelocity> out;
  out.reserve(records.size());
  for (const semlio::io::OxtsRecord& r : records) {
    const Eigen::Matrix3d R_heading_imu = (Eigen::AngleAxisd(r.pitch_rad, Eigen::Vector3d::UnitY()) *
                                           Eigen::AngleAxisd(r.roll_rad, Eigen::Vector3d::UnitX()))
                                              .toRotationMatrix();
    out.push_back({r.stamp_s, R_heading_imu.transpose() * r.velocity_flu_mps});
  }
  return out;
}

/// t_imu = t_lidar + offset: 0 when the clocks agree, else (the simulator's
/// OXTS carries a date while times.txt starts at 0; both start together)
/// first OXTS stamp - first scan stamp when they are more than 1000 s apart.
inline double auto_imu_time_offset(const std::vector<semlio::ImuSample>& imu, double first_scan_stamp_s,
                                   double sequence_start_stamp_s) {
  if (imu.empty()) return 0.0;
  const double d = imu.front().stamp_s - first_scan_stamp_s;
  return std::abs(d) > 1000.0 ? imu.front().stamp_s - sequence_start_stamp_s : 0.0;
}

}  // namespace semlio_examples
