#pragma once
/// \file
/// What every bag container reader (ROS 1 bag, MCAP, rosbag2 sqlite3) hands
/// out: its topics, and raw serialised messages in log-time order. The
/// message bytes are then deserialised by io/ros1_msgs.hpp (ROS 1) or
/// io/cdr_msgs.hpp (ROS 2 CDR) into the values of io/ros_msgs.hpp.
///
/// Every container reader has the same shape:
///
///     explicit Reader(const std::string& path);   // IoError / FormatError
///     const std::vector<BagTopic>& topics() const;
///     void select(const std::vector<std::string>& topic_names);  // restart, these topics only
///     bool next(BagMessage& out);                 // false at the end
///
/// next() returns the selected topics' messages in non-decreasing log time
/// (ties in file order), reading the file piece by piece: a bag is never
/// loaded into memory whole.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace semlio::io {

/// How a topic's messages are serialised.
enum class MessageEncoding : std::uint8_t {
  kRos1,  ///< ROS 1 serialisation (rosbag 2.0)
  kCdr,   ///< OMG CDR with its 4-byte encapsulation header (ROS 2: MCAP profile ros2, rosbag2 sqlite3)
};

/// One topic of a bag.
struct BagTopic {
  std::string name;                        ///< e.g. "/velodyne_points"
  std::string type;                        ///< ROS type name as stored, e.g. "sensor_msgs/PointCloud2" or "sensor_msgs/msg/PointCloud2"
  MessageEncoding encoding = MessageEncoding::kRos1;  ///< how its messages are serialised
  std::size_t message_count = 0;           ///< messages on this topic (from the index or a scan of the file)
};

/// One serialised message.
struct BagMessage {
  std::size_t topic = 0;                   ///< index into the reader's topics()
  std::int64_t log_time_ns = 0;            ///< time the recorder logged it [ns]
  std::vector<std::uint8_t> data;          ///< the serialised message (reused between calls)
};

/// True for "sensor_msgs/PointCloud2" and "sensor_msgs/msg/PointCloud2".
inline bool is_pointcloud2_type(const std::string& type) {
  return type == "sensor_msgs/PointCloud2" || type == "sensor_msgs/msg/PointCloud2";
}
/// True for "sensor_msgs/Imu" and "sensor_msgs/msg/Imu".
inline bool is_imu_type(const std::string& type) {
  return type == "sensor_msgs/Imu" || type == "sensor_msgs/msg/Imu";
}

}  // namespace semlio::io
