#pragma once
/// \file
/// ROS 1 deserialisation of sensor_msgs/PointCloud2 and sensor_msgs/Imu into
/// the values of io/ros_msgs.hpp, without ROS. ROS 1 serialisation is
/// little-endian and packed: uint32/float64 as raw bytes, strings and
/// variable arrays as a uint32 length then the elements, fixed arrays
/// (float64[9]) without a length, bool as one byte. Every length is checked
/// against the bytes present: a truncated or lying message throws
/// FormatError, never reads out of bounds; trailing bytes are an error too (the
/// message is then not the type its connection claims).

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/io/ros_msgs.hpp>

namespace semlio::io {

/// md5sum of sensor_msgs/PointCloud2 (ROS 1 connection records carry it).
inline constexpr const char* kRos1PointCloud2Md5 = "1158d486dd51d683ce2f1be655c3c181";
/// md5sum of sensor_msgs/Imu.
inline constexpr const char* kRos1ImuMd5 = "6a62c6daae103f4ff57a132d6f95cec2";

namespace detail::ros1 {

/// Bounds-checked little-endian reader over one serialised message.
class Cursor {
 public:
  Cursor(const std::uint8_t* data, std::size_t size, const char* type) : data_(data), size_(size), type_(type) {}

  /// Throws FormatError unless `n` more bytes are present for `field`.
  void need(std::size_t n, const char* field) const {
    if (n > size_ - pos_) {
      throw FormatError(std::string("ROS 1 ") + type_ + ": truncated at byte " + std::to_string(pos_) +
                        " reading '" + field + "' (needs " + std::to_string(n) + " bytes, " +
                        std::to_string(size_ - pos_) + " left)");
    }
  }
  std::uint8_t u8(const char* field) {
    need(1, field);
    return data_[pos_++];
  }
  std::uint32_t u32(const char* field) { return fixed<std::uint32_t>(field); }
  double f64(const char* field) { return fixed<double>(field); }
  /// A header stamp (uint32 sec, uint32 nsec) as double(sec) + double(nsec) / 1e9.
  double stamp(const char* field) {
    const std::uint32_t sec = u32(field);
    const std::uint32_t nsec = u32(field);
    return static_cast<double>(sec) + static_cast<double>(nsec) / 1e9;
  }
  std::string string(const char* field) {
    const std::uint32_t n = u32(field);
    need(n, field);
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return s;
  }
  /// Skips a uint8[], returning where its bytes lie (offset into the message, count).
  void skip_bytes(std::size_t& offset, std::size_t& n, const char* field) {
    n = u32(field);
    need(n, field);
    offset = pos_;
    pos_ += n;
  }
  /// Throws FormatError when bytes remain after the last field.
  void finish() const {
    if (pos_ != size_) {
      throw FormatError(std::string("ROS 1 ") + type_ + ": " + std::to_string(size_ - pos_) +
                        " bytes left after the last field (message is " + std::to_string(size_) +
                        " bytes; not this type?)");
    }
  }
  [[nodiscard]] std::size_t remaining() const noexcept { return size_ - pos_; }

 private:
  template <typename T>
  T fixed(const char* field) {
    need(sizeof(T), field);
    // ROS 1 is little-endian on the wire; semlio's hosts are too.
    static_assert(std::endian::native == std::endian::little, "ROS 1 deserialisation assumes a little-endian host");
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  const char* type_;
};

/// std_msgs/Header: seq, stamp, frame_id.
inline void header(Cursor& in, double& stamp_s, std::string& frame_id) {
  (void)in.u32("header.seq");
  stamp_s = in.stamp("header.stamp");
  frame_id = in.string("header.frame_id");
}

}  // namespace detail::ros1

namespace detail::ros1 {

/// Every PointCloud2 field but `data`, whose place in the message is returned.
inline void pointcloud2_fields(const std::uint8_t* data, std::size_t size, PointCloud2Msg& out,
                               std::size_t& data_offset, std::size_t& data_size) {
  Cursor in(data, size, "sensor_msgs/PointCloud2");
  detail::ros1::header(in, out.stamp_s, out.frame_id);
  out.height = in.u32("height");
  out.width = in.u32("width");
  const std::uint32_t nfields = in.u32("fields");
  // Each PointField takes at least 13 bytes (empty name): a count the bytes
  // cannot hold is rejected before anything is allocated for it.
  if (std::uint64_t{nfields} * 13 > in.remaining()) {
    throw FormatError("ROS 1 sensor_msgs/PointCloud2: " + std::to_string(nfields) + " fields cannot fit in the " +
                      std::to_string(in.remaining()) + " bytes left");
  }
  out.fields.resize(nfields);
  for (PointField& f : out.fields) {
    f.name = in.string("fields[].name");
    f.offset = in.u32("fields[].offset");
    f.datatype = in.u8("fields[].datatype");
    f.count = in.u32("fields[].count");
  }
  out.is_bigendian = in.u8("is_bigendian") != 0;
  out.point_step = in.u32("point_step");
  out.row_step = in.u32("row_step");
  in.skip_bytes(data_offset, data_size, "data");
  out.is_dense = in.u8("is_dense") != 0;
  in.finish();
}

}  // namespace detail::ros1

/// Deserialises a ROS 1 sensor_msgs/PointCloud2 into `out` (reusing its
/// buffers). Throws FormatError on truncated, lying or trailing bytes. The
/// point layout itself is checked by pointcloud2_to_scan().
inline void parse_ros1_pointcloud2(const std::uint8_t* data, std::size_t size, PointCloud2Msg& out) {
  std::size_t offset = 0;
  std::size_t n = 0;
  detail::ros1::pointcloud2_fields(data, size, out, offset, n);
  out.data.assign(data + offset, data + offset + n);
}

/// Deserialises a ROS 1 sensor_msgs/PointCloud2 (see the overload above).
inline PointCloud2Msg parse_ros1_pointcloud2(const std::vector<std::uint8_t>& bytes) {
  PointCloud2Msg msg;
  parse_ros1_pointcloud2(bytes.data(), bytes.size(), msg);
  return msg;
}

/// Deserialises a ROS 1 sensor_msgs/PointCloud2 and decodes it into `out`
/// without copying its points into a PointCloud2Msg (see
/// pointcloud2_data_to_scan()); `header` receives every other field (its
/// `data` is left empty). Throws FormatError like the two steps it replaces.
inline void ros1_pointcloud2_to_scan(const std::uint8_t* data, std::size_t size, Scan& out,
                                     const PointCloud2Config& config = {}, PointCloud2Layout* layout = nullptr,
                                     ReadStats* stats = nullptr, PointCloud2Msg* header = nullptr) {
  PointCloud2Msg local;
  PointCloud2Msg& msg = header != nullptr ? *header : local;
  std::size_t offset = 0;
  std::size_t n = 0;
  detail::ros1::pointcloud2_fields(data, size, msg, offset, n);
  msg.data.clear();
  pointcloud2_data_to_scan(msg, data + offset, n, out, config, layout, stats);
}

/// Deserialises a ROS 1 sensor_msgs/Imu into `out`. Throws FormatError on
/// truncated or trailing bytes.
inline void parse_ros1_imu(const std::uint8_t* data, std::size_t size, ImuMsg& out) {
  detail::ros1::Cursor in(data, size, "sensor_msgs/Imu");
  detail::ros1::header(in, out.stamp_s, out.frame_id);
  // geometry_msgs/Quaternion is x, y, z, w on the wire; Eigen's constructor takes w first.
  const double qx = in.f64("orientation.x");
  const double qy = in.f64("orientation.y");
  const double qz = in.f64("orientation.z");
  const double qw = in.f64("orientation.w");
  out.orientation = Eigen::Quaterniond(qw, qx, qy, qz);
  for (double& v : out.orientation_covariance) v = in.f64("orientation_covariance");
  for (int i = 0; i < 3; ++i) out.angular_velocity_radps[i] = in.f64("angular_velocity");
  for (double& v : out.angular_velocity_covariance) v = in.f64("angular_velocity_covariance");
  for (int i = 0; i < 3; ++i) out.linear_acceleration_mps2[i] = in.f64("linear_acceleration");
  for (double& v : out.linear_acceleration_covariance) v = in.f64("linear_acceleration_covariance");
  in.finish();
}

/// Deserialises a ROS 1 sensor_msgs/Imu (see the overload above).
inline ImuMsg parse_ros1_imu(const std::vector<std::uint8_t>& bytes) {
  ImuMsg msg;
  parse_ros1_imu(bytes.data(), bytes.size(), msg);
  return msg;
}

/// Throws FormatError when a connection of type sensor_msgs/PointCloud2 or
/// sensor_msgs/Imu states another md5sum than the one semlio deserialises
/// ("*" -- any -- is accepted); other types are not checked. `what` names
/// the file and topic.
inline void check_ros1_md5sum(const std::string& type, const std::string& md5sum, const std::string& what) {
  const char* want = nullptr;
  if (type == "sensor_msgs/PointCloud2") want = kRos1PointCloud2Md5;
  if (type == "sensor_msgs/Imu") want = kRos1ImuMd5;
  if (want == nullptr || md5sum == "*" || md5sum == want) return;
  throw FormatError(what + ": type " + type + " has md5sum " + md5sum + ", expected " + want +
                    " (a different message definition)");
}

}  // namespace semlio::io
