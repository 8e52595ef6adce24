#pragma once
/// \file
/// The two ROS message types semlio reads from bags, as plain values that do
/// not depend on how they were serialised: sensor_msgs/PointCloud2 and
/// sensor_msgs/Imu (identical fields in ROS 1 and ROS 2). The ROS 1 and CDR
/// (ROS 2) deserialisers fill these; io/pointcloud2.hpp turns a cloud into a
/// Scan. Stamps are the message header's, in seconds.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace semlio::io {

/// sensor_msgs/PointField datatype codes (the same numbers in ROS 1 and ROS 2).
enum class PointFieldType : std::uint8_t {
  kInt8 = 1,
  kUint8 = 2,
  kInt16 = 3,
  kUint16 = 4,
  kInt32 = 5,
  kUint32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};

/// One sensor_msgs/PointField: a named field at a byte offset inside a point.
struct PointField {
  std::string name;            ///< e.g. "x", "intensity", "ring", "time", "t"
  std::uint32_t offset = 0;    ///< byte offset inside one point
  std::uint8_t datatype = 0;   ///< PointFieldType code (0 = invalid)
  std::uint32_t count = 1;     ///< elements (1 for every field semlio reads)
};

/// A sensor_msgs/PointCloud2 message, header included, data still packed.
struct PointCloud2Msg {
  double stamp_s = 0.0;                ///< header.stamp [s]
  std::string frame_id;                ///< header.frame_id
  std::uint32_t height = 0;            ///< rows (1 for unorganised clouds)
  std::uint32_t width = 0;             ///< points per row
  std::vector<PointField> fields;      ///< field layout of one point
  bool is_bigendian = false;           ///< byte order of `data`
  std::uint32_t point_step = 0;        ///< bytes per point (may include padding)
  std::uint32_t row_step = 0;          ///< bytes per row (may include padding)
  std::vector<std::uint8_t> data;      ///< height * row_step bytes
  bool is_dense = true;                ///< false: may hold NaN points
};

/// A sensor_msgs/Imu message. Covariances are kept as published (row-major
/// 3x3; element 0 = -1 means "not provided", by the message's convention).
struct ImuMsg {
  double stamp_s = 0.0;                                         ///< header.stamp [s]
  std::string frame_id;                                         ///< header.frame_id
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< as published (may be unset)
  std::array<double, 9> orientation_covariance{};               ///< row-major
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();       ///< [rad/s]
  std::array<double, 9> angular_velocity_covariance{};          ///< row-major
  Eigen::Vector3d linear_acceleration_mps2 = Eigen::Vector3d::Zero();     ///< [m/s^2]
  std::array<double, 9> linear_acceleration_covariance{};       ///< row-major
};

}  // namespace semlio::io
