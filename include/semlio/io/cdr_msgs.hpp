#pragma once
/// \file
/// ROS 2 (CDR) deserialisation of sensor_msgs/msg/PointCloud2 and
/// sensor_msgs/msg/Imu into the values of io/ros_msgs.hpp, without ROS.
///
/// A ROS 2 message as rosbag2 and MCAP (profile "ros2", encoding "cdr") store
/// it is plain OMG CDR (XCDR version 1, what rmw_fastrtps and rmw_cyclonedds
/// write) behind a 4-byte encapsulation header: {0x00, kind, options(2)}, kind
/// 0x00 = big-endian, 0x01 = little-endian. Every primitive is aligned to its
/// own size (1, 2, 4, 8) counted from the end of that header, not from the
/// start of the buffer. Strings are a uint32 length that includes the
/// terminating NUL, then the bytes and the NUL; sequences a uint32 element
/// count then the elements; fixed arrays (float64[9]) have no length; bool is
/// one byte 0 or 1. XCDR2 and parameter-list encapsulations are rejected with
/// a FormatError that says so (ROS 2 types are final structs, written as
/// plain XCDR1 by every rmw semlio knows).
///
/// Every length is checked against the bytes present: a truncated or lying
/// message throws FormatError naming the field and the byte, never reads out
/// of bounds. Up to 3 bytes after the last field are accepted (writers may pad
/// the payload to a multiple of 4; the header's options say by how much);
/// more are an error (the message is then not the type its channel claims).
/// The point layout itself (data.size() vs height * row_step, field offsets)
/// is checked by pointcloud2_to_scan(), not here.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/ros_msgs.hpp>

namespace semlio::io {
namespace detail::cdr {

/// Bytes of the encapsulation header in front of every CDR payload.
inline constexpr std::size_t kEncapsulationBytes = 4;

/// Bounds-checked CDR reader over one serialised message (after checking its
/// encapsulation header).
class Cursor {
 public:
  /// Reads the encapsulation header; throws FormatError for a buffer shorter
  /// than it or an encapsulation other than plain little/big-endian CDR.
  Cursor(const std::uint8_t* data, std::size_t size, const char* type) : data_(data), size_(size), type_(type) {
    if (size < kEncapsulationBytes) {
      fail("message is " + std::to_string(size) + " bytes, shorter than the 4-byte CDR encapsulation header");
    }
    if (data[0] != 0x00 || data[1] > 0x01) {
      fail("encapsulation kind 0x" + hex(data[0]) + hex(data[1]) +
           " is not plain CDR (0x0000 big-endian or 0x0001 little-endian); XCDR2 and parameter lists are not supported");
    }
    big_endian_ = data[1] == 0x00;
    pos_ = kEncapsulationBytes;
  }

  /// Throws FormatError("CDR <type>: <what>").
  [[noreturn]] void fail(const std::string& what) const {
    throw FormatError(std::string("CDR ") + type_ + ": " + what);
  }

  /// Throws FormatError unless `n` more bytes are present for `field`.
  void need(std::size_t n, const char* field) const {
    if (n > size_ - pos_) {
      fail("truncated at byte " + std::to_string(pos_) + " reading '" + field + "' (needs " + std::to_string(n) +
           " bytes, " + std::to_string(size_ - pos_) + " left)");
    }
  }

  std::uint8_t u8(const char* field) {
    need(1, field);
    return data_[pos_++];
  }
  bool boolean(const char* field) {
    const std::uint8_t v = u8(field);
    if (v > 1) fail("'" + std::string(field) + "' at byte " + std::to_string(pos_ - 1) + " is " + std::to_string(v) + ", not a bool (0 or 1)");
    return v == 1;
  }
  std::int32_t i32(const char* field) { return std::bit_cast<std::int32_t>(fixed<std::uint32_t>(field)); }
  std::uint32_t u32(const char* field) { return fixed<std::uint32_t>(field); }
  double f64(const char* field) { return std::bit_cast<double>(fixed<std::uint64_t>(field)); }

  /// builtin_interfaces/Time (int32 sec, uint32 nanosec) as double(sec) + double(nanosec) / 1e9.
  double stamp(const char* field) {
    const std::int32_t sec = i32(field);
    const std::uint32_t nanosec = u32(field);
    return static_cast<double>(sec) + static_cast<double>(nanosec) / 1e9;
  }

  /// A string into `out`: uint32 length including the NUL, the bytes, the NUL.
  void string(std::string& out, const char* field) {
    const std::uint32_t n = u32(field);
    need(n, field);
    if (n == 0) {  // not valid CDR (the NUL is counted), but harmless: read as ""
      out.clear();
      return;
    }
    if (data_[pos_ + n - 1] != 0) {
      fail("string '" + std::string(field) + "' at byte " + std::to_string(pos_) + " (length " + std::to_string(n) +
           ") does not end with a NUL");
    }
    out.assign(reinterpret_cast<const char*>(data_ + pos_), n - 1);
    pos_ += n;
  }

  /// A sequence<uint8> into `out` (reusing its capacity).
  void bytes(std::vector<std::uint8_t>& out, const char* field) {
    const std::uint32_t n = u32(field);
    need(n, field);
    out.assign(data_ + pos_, data_ + pos_ + n);
    pos_ += n;
  }

  /// A float64[N] fixed array (no length on the wire).
  template <std::size_t N>
  void f64_array(std::array<double, N>& out, const char* field) {
    for (double& v : out) v = f64(field);
  }

  /// Throws FormatError when more than alignment padding remains after the last field.
  void finish() const {
    if (size_ - pos_ > 3) {
      fail(std::to_string(size_ - pos_) + " bytes left after the last field (message is " + std::to_string(size_) +
           " bytes; not this type?)");
    }
  }
  [[nodiscard]] std::size_t remaining() const noexcept { return size_ - pos_; }
  [[nodiscard]] bool big_endian() const noexcept { return big_endian_; }

 private:
  static std::string hex(std::uint8_t b) {
    const char* digits = "0123456789abcdef";
    return {digits[b >> 4], digits[b & 0x0f]};
  }

  /// Skips padding to a multiple of `n` counted from the end of the encapsulation header.
  void align(std::size_t n, const char* field) {
    const std::size_t rel = pos_ - kEncapsulationBytes;
    const std::size_t pad = (n - rel % n) % n;
    need(pad, field);
    pos_ += pad;
  }

  template <typename U>
  U fixed(const char* field) {
    static_assert(std::endian::native == std::endian::little, "CDR deserialisation assumes a little-endian host");
    align(sizeof(U), field);
    need(sizeof(U), field);
    U v;
    std::memcpy(&v, data_ + pos_, sizeof(U));
    pos_ += sizeof(U);
    if (big_endian_) v = byteswap(v);
    return v;
  }

  template <typename U>
  static U byteswap(U v) noexcept {
    if constexpr (sizeof(U) == 4) {
      return __builtin_bswap32(v);
    } else {
      static_assert(sizeof(U) == 8);
      return __builtin_bswap64(v);
    }
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  const char* type_;
  bool big_endian_ = false;
};

/// std_msgs/Header: stamp, frame_id.
inline void header(Cursor& in, double& stamp_s, std::string& frame_id) {
  stamp_s = in.stamp("header.stamp");
  in.string(frame_id, "header.frame_id");
}

/// geometry_msgs/Vector3 (x, y, z float64).
inline Eigen::Vector3d vector3(Cursor& in, const char* field) {
  const double x = in.f64(field);
  const double y = in.f64(field);
  const double z = in.f64(field);
  return {x, y, z};
}

}  // namespace detail::cdr

/// Deserialises a CDR sensor_msgs/msg/PointCloud2 (encapsulation header
/// included) into `out`, reusing its buffers. Throws FormatError on a bad
/// header, truncated or lying lengths, or trailing bytes.
inline void parse_cdr_pointcloud2(const std::uint8_t* data, std::size_t size, PointCloud2Msg& out) {
  detail::cdr::Cursor in(data, size, "sensor_msgs/msg/PointCloud2");
  detail::cdr::header(in, out.stamp_s, out.frame_id);
  out.height = in.u32("height");
  out.width = in.u32("width");
  const std::uint32_t n_fields = in.u32("fields");
  // A PointField takes at least 13 bytes (4 name length + 1 NUL + offset +
  // datatype + count): a larger count than the bytes allow is a lie.
  if (n_fields > in.remaining() / 13) {
    in.fail("'fields' states " + std::to_string(n_fields) + " fields, more than the " +
            std::to_string(in.remaining()) + " bytes left can hold");
  }
  out.fields.resize(n_fields);
  for (PointField& f : out.fields) {
    in.string(f.name, "fields.name");
    f.offset = in.u32("fields.offset");
    f.datatype = in.u8("fields.datatype");
    f.count = in.u32("fields.count");
  }
  out.is_bigendian = in.boolean("is_bigendian");
  out.point_step = in.u32("point_step");
  out.row_step = in.u32("row_step");
  in.bytes(out.data, "data");
  out.is_dense = in.boolean("is_dense");
  in.finish();
}

/// Deserialises a CDR sensor_msgs/msg/PointCloud2 (see the overload above).
inline PointCloud2Msg parse_cdr_pointcloud2(const std::vector<std::uint8_t>& bytes) {
  PointCloud2Msg out;
  parse_cdr_pointcloud2(bytes.data(), bytes.size(), out);
  return out;
}

/// Deserialises a CDR sensor_msgs/msg/Imu (encapsulation header included)
/// into `out`. Throws FormatError on a bad header, truncated or trailing bytes.
inline void parse_cdr_imu(const std::uint8_t* data, std::size_t size, ImuMsg& out) {
  detail::cdr::Cursor in(data, size, "sensor_msgs/msg/Imu");
  detail::cdr::header(in, out.stamp_s, out.frame_id);
  const double x = in.f64("orientation");
  const double y = in.f64("orientation");
  const double z = in.f64("orientation");
  const double w = in.f64("orientation");
  out.orientation = Eigen::Quaterniond(w, x, y, z);  // Eigen's constructor takes w first
  in.f64_array(out.orientation_covariance, "orientation_covariance");
  out.angular_velocity_radps = detail::cdr::vector3(in, "angular_velocity");
  in.f64_array(out.angular_velocity_covariance, "angular_velocity_covariance");
  out.linear_acceleration_mps2 = detail::cdr::vector3(in, "linear_acceleration");
  in.f64_array(out.linear_acceleration_covariance, "linear_acceleration_covariance");
  in.finish();
}

/// Deserialises a CDR sensor_msgs/msg/Imu (see the overload above).
inline ImuMsg parse_cdr_imu(const std::vector<std::uint8_t>& bytes) {
  ImuMsg out;
  parse_cdr_imu(bytes.data(), bytes.size(), out);
  return out;
}

}  // namespace semlio::io
