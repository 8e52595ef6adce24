#pragma once
/// \file
/// What the bag writers (rosbag1_writer.hpp, mcap_writer.hpp) put in a bag:
/// a Scan packed as sensor_msgs/PointCloud2 in a driver's point layout, and
/// the ROS 1 and CDR (ROS 2) serialisation of PointCloud2Msg and ImuMsg with
/// their type names, md5sums and message definitions. Written here, apart
/// from the readers (io/ros1_msgs.hpp, io/cdr_msgs.hpp), so that a reader bug
/// and a writer bug cannot cancel out in a round trip.
///
/// Point layouts (`CloudLayout`), little-endian, unorganised (height 1):
/// - Velodyne (velodyne_pointcloud's XYZIRT cloud, packed): x y z intensity
///   float32 at 0/4/8/12, then `ring` uint16 and `time` float32 [s since the
///   header stamp] when enabled; point_step 16 + 2 + 4.
/// - Ouster (ouster_ros's PCL point, 48 bytes): x y z float32 at 0/4/8 (12-15
///   padding), intensity float32 at 16, `t` uint32 [ns since the header
///   stamp] at 20, reflectivity uint16 at 24, `ring` uint16 at 26, ambient
///   uint16 at 28, range uint32 [mm] at 32; the `t` and `ring` fields are
///   listed only when enabled (their bytes stay zero otherwise).
/// The header stamp is the sweep start (Scan::stamp_s).

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/ros_msgs.hpp>

namespace semlio::io {

/// Point layout of written clouds (see the file comment).
enum class CloudLayout : std::uint8_t {
  kVelodyne,  ///< x y z intensity [ring uint16] [time float32 s], packed
  kOuster,    ///< ouster_ros's 48-byte point: [t uint32 ns], [ring uint16], reflectivity, ambient, range
};

/// Which per-point fields a written cloud carries.
struct CloudFieldsConfig {
  CloudLayout layout = CloudLayout::kVelodyne;  ///< driver layout
  bool ring = true;                             ///< write `ring` (needs Scan::rings)
  bool time = true;                             ///< write `time` / `t` (needs Scan::times_s)
};

/// The message types the writers serialise.
enum class RosMessageType : std::uint8_t {
  kPointCloud2,  ///< sensor_msgs/PointCloud2
  kImu,          ///< sensor_msgs/Imu
};

/// Packs `scan` into a PointCloud2 message in the layout of `config`, stamped
/// scan.stamp_s. Throws ValueError when a requested ring/time field has no
/// data in the scan, a per-point time is negative or not finite, or the cloud
/// does not fit the message's 32-bit sizes.
inline PointCloud2Msg scan_to_pointcloud2(const Scan& scan, const CloudFieldsConfig& config,
                                          const std::string& frame_id) {
  const std::size_t n = scan.size();
  if (config.ring && scan.rings.size() != n) {
    throw ValueError("scan_to_pointcloud2: ring field requested but the scan has " +
                     std::to_string(scan.rings.size()) + " rings for " + std::to_string(n) + " points");
  }
  if (config.time && scan.times_s.size() != n) {
    throw ValueError("scan_to_pointcloud2: time field requested but the scan has " +
                     std::to_string(scan.times_s.size()) + " times for " + std::to_string(n) + " points");
  }
  if (scan.intensity.size() != n) {
    throw ValueError("scan_to_pointcloud2: " + std::to_string(scan.intensity.size()) + " intensities for " +
                     std::to_string(n) + " points");
  }
  PointCloud2Msg msg;
  msg.stamp_s = scan.stamp_s;
  msg.frame_id = frame_id;
  const auto field = [&](const char* name, std::uint32_t offset, PointFieldType type) {
    msg.fields.push_back(PointField{name, offset, static_cast<std::uint8_t>(type), 1});
  };
  const bool ouster = config.layout == CloudLayout::kOuster;
  field("x", 0, PointFieldType::kFloat32);
  field("y", 4, PointFieldType::kFloat32);
  field("z", 8, PointFieldType::kFloat32);
  std::uint32_t step = 0;
  std::uint32_t ring_at = 0;
  std::uint32_t time_at = 0;
  if (ouster) {
    field("intensity", 16, PointFieldType::kFloat32);
    if (config.time) field("t", 20, PointFieldType::kUint32);
    field("reflectivity", 24, PointFieldType::kUint16);
    if (config.ring) field("ring", 26, PointFieldType::kUint16);
    field("ambient", 28, PointFieldType::kUint16);
    field("range", 32, PointFieldType::kUint32);
    ring_at = 26;
    time_at = 20;
    step = 48;
  } else {
    field("intensity", 12, PointFieldType::kFloat32);
    step = 16;
    if (config.ring) {
      ring_at = step;
      field("ring", step, PointFieldType::kUint16);
      step += 2;
    }
    if (config.time) {
      time_at = step;
      field("time", step, PointFieldType::kFloat32);
      step += 4;
    }
  }
  if (n > std::numeric_limits<std::uint32_t>::max() / step) {
    throw ValueError("scan_to_pointcloud2: " + std::to_string(n) + " points exceed a PointCloud2's 4 GiB row");
  }
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(n);
  msg.point_step = step;
  msg.row_step = step * msg.width;
  msg.is_bigendian = false;
  msg.is_dense = true;
  msg.data.assign(static_cast<std::size_t>(msg.row_step), 0);
  const auto put = [&](std::size_t at, const auto& v) { std::memcpy(msg.data.data() + at, &v, sizeof(v)); };
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t base = i * step;
    const Eigen::Vector3f& p = scan.points[i];
    put(base + 0, p.x());
    put(base + 4, p.y());
    put(base + 8, p.z());
    put(base + (ouster ? 16U : 12U), scan.intensity[i]);
    if (config.ring) put(base + ring_at, scan.rings[i]);
    if (config.time) {
      const float t = scan.times_s[i];
      if (!std::isfinite(t) || t < 0.0F) {
        throw ValueError("scan_to_pointcloud2: point " + std::to_string(i) + " has time " + std::to_string(t) +
                         " s (must be finite and >= 0, relative to the sweep start)");
      }
      if (ouster) {
        const double ns = std::round(static_cast<double>(t) * 1e9);
        if (ns > static_cast<double>(std::numeric_limits<std::uint32_t>::max())) {
          throw ValueError("scan_to_pointcloud2: point " + std::to_string(i) + " time " + std::to_string(t) +
                           " s overflows Ouster's uint32 ns field");
        }
        put(base + time_at, static_cast<std::uint32_t>(ns));
      } else {
        put(base + time_at, t);
      }
    }
    if (ouster) {
      const float refl = std::clamp(scan.intensity[i], 0.0F, 1.0F) * 255.0F;
      put(base + 24, static_cast<std::uint16_t>(std::lround(refl)));
      const double mm = std::round(static_cast<double>(p.norm()) * 1000.0);
      put(base + 32, static_cast<std::uint32_t>(std::clamp(mm, 0.0, 4.0e9)));
    }
  }
  return msg;
}

namespace detail {

/// Type names, ROS 1 md5sum and full message definitions (dependencies after
/// lines of 80 '='), as rosbag / rosbag2 store them. The definitions leave out
/// the upstream comments; the md5sums are those of sensor_msgs 1.13 (genmsg
/// computes them from the comment-free text), and scripts/check_sim_bags.sh
/// recomputes them from these texts with genpy.
struct RosTypeInfo {
  std::string ros1_name;        ///< e.g. "sensor_msgs/PointCloud2"
  std::string ros2_name;        ///< e.g. "sensor_msgs/msg/PointCloud2"
  std::string md5sum;           ///< ROS 1 md5sum
  std::string ros1_definition;  ///< ros1msg text
  std::string ros2_definition;  ///< ros2msg text
};

inline std::array<RosTypeInfo, 2> make_ros_type_table() {
  const std::string sep = std::string(80, '=') + "\n";
  const std::string header1 = "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
  const std::string header2 = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" + sep +
                              "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";
  const std::string point_field =
      "MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\n"
      "uint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\n"
      "string name\nuint32 offset\nuint8 datatype\nuint32 count\n";
  const std::string cloud_body =
      "uint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\nuint32 point_step\n"
      "uint32 row_step\nuint8[] data\nbool is_dense\n";
  const std::string imu_body =
      "geometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
      "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
      "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n";
  const std::string geometry = "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n" + sep +
                               "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
  return {RosTypeInfo{"sensor_msgs/PointCloud2", "sensor_msgs/msg/PointCloud2", "1158d486dd51d683ce2f1be655c3c181",
                      "Header header\n" + cloud_body + sep + header1 + sep + point_field,
                      "std_msgs/Header header\n" + cloud_body + sep + header2 + sep + point_field},
          RosTypeInfo{"sensor_msgs/Imu", "sensor_msgs/msg/Imu", "6a62c6daae103f4ff57a132d6f95cec2",
                      "Header header\n" + imu_body + sep + header1 + sep + geometry,
                      "std_msgs/Header header\n" + imu_body + sep + header2 + sep + geometry}};
}

/// The RosTypeInfo of a message type (built once, then read-only).
inline const RosTypeInfo& ros_type_info(RosMessageType type) {
  static const std::array<RosTypeInfo, 2> table = make_ros_type_table();
  return table[static_cast<std::size_t>(type)];
}

/// A header stamp as ROS time: whole seconds and nanoseconds, rounded to the
/// nearest ns. Throws ValueError for a stamp that is negative, not finite or
/// past 2106 (ROS 1's uint32 seconds).
struct RosStamp {
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
};

inline RosStamp ros_stamp(double stamp_s) {
  if (!std::isfinite(stamp_s) || stamp_s < 0.0 || stamp_s >= 4294967295.0) {
    throw ValueError("bag writer: header stamp " + std::to_string(stamp_s) +
                     " s is not a ROS time (finite, >= 0 and < 2^32 s)");
  }
  // Whole seconds first: stamp_s * 1e9 would round a 2011 stamp to 256 ns.
  const double whole = std::floor(stamp_s);
  auto sec = static_cast<std::uint32_t>(whole);
  auto nsec = static_cast<std::uint32_t>(std::llround((stamp_s - whole) * 1e9));
  if (nsec >= 1000000000U) {
    nsec -= 1000000000U;
    ++sec;
  }
  return {sec, nsec};
}

/// Appends little-endian ROS 1 primitives (no alignment, uint32 length
/// prefixes for strings and arrays).
class Ros1Out {
 public:
  explicit Ros1Out(std::vector<std::uint8_t>& out) : out_(out) {}
  template <typename T>
  void put(T v) {
    const auto at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &v, sizeof(T));
  }
  void length(std::size_t n, const char* what) {
    if (n > std::numeric_limits<std::uint32_t>::max()) {
      throw ValueError(std::string("bag writer: ") + what + " of " + std::to_string(n) +
                       " elements exceeds the 32-bit length prefix");
    }
    put(static_cast<std::uint32_t>(n));
  }
  void string(const std::string& s) {
    length(s.size(), "string");
    out_.insert(out_.end(), s.begin(), s.end());
  }
  void bytes(const std::vector<std::uint8_t>& b) {
    length(b.size(), "uint8[]");
    out_.insert(out_.end(), b.begin(), b.end());
  }

 private:
  std::vector<std::uint8_t>& out_;
};

/// Appends a ROS 1 std_msgs/Header (seq, stamp, frame_id).
inline void ros1_header(Ros1Out& w, std::uint32_t seq, double stamp_s, const std::string& frame_id) {
  const RosStamp t = ros_stamp(stamp_s);
  w.put(seq);
  w.put(t.sec);
  w.put(t.nsec);
  w.string(frame_id);
}

/// ROS 1 serialisation of a sensor_msgs/PointCloud2 (replaces `out`).
inline void serialize_ros1(const PointCloud2Msg& m, std::uint32_t seq, std::vector<std::uint8_t>& out) {
  out.clear();
  Ros1Out w(out);
  ros1_header(w, seq, m.stamp_s, m.frame_id);
  w.put(m.height);
  w.put(m.width);
  w.length(m.fields.size(), "fields[]");
  for (const PointField& f : m.fields) {
    w.string(f.name);
    w.put(f.offset);
    w.put(f.datatype);
    w.put(f.count);
  }
  w.put(static_cast<std::uint8_t>(m.is_bigendian ? 1 : 0));
  w.put(m.point_step);
  w.put(m.row_step);
  w.bytes(m.data);
  w.put(static_cast<std::uint8_t>(m.is_dense ? 1 : 0));
}

/// ROS 1 serialisation of a sensor_msgs/Imu (replaces `out`).
inline void serialize_ros1(const ImuMsg& m, std::uint32_t seq, std::vector<std::uint8_t>& out) {
  out.clear();
  Ros1Out w(out);
  ros1_header(w, seq, m.stamp_s, m.frame_id);
  w.put(m.orientation.x());
  w.put(m.orientation.y());
  w.put(m.orientation.z());
  w.put(m.orientation.w());
  for (const double c : m.orientation_covariance) w.put(c);
  for (int k = 0; k < 3; ++k) w.put(m.angular_velocity_radps[k]);
  for (const double c : m.angular_velocity_covariance) w.put(c);
  for (int k = 0; k < 3; ++k) w.put(m.linear_acceleration_mps2[k]);
  for (const double c : m.linear_acceleration_covariance) w.put(c);
}

/// Appends little-endian CDR (XCDR1, the ROS 2 default): the 4-byte
/// encapsulation header 00 01 00 00 (CDR_LE), then each primitive aligned to
/// its size counted from the end of that header; strings carry a uint32
/// length that includes their terminating NUL.
class CdrOut {
 public:
  explicit CdrOut(std::vector<std::uint8_t>& out) : out_(out) {
    out_.clear();
    out_.insert(out_.end(), {0x00, 0x01, 0x00, 0x00});
  }
  template <typename T>
  void put(T v) {
    align(sizeof(T));
    const auto at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &v, sizeof(T));
  }
  void length(std::size_t n, const char* what) {
    if (n >= std::numeric_limits<std::uint32_t>::max()) {
      throw ValueError(std::string("bag writer: ") + what + " of " + std::to_string(n) +
                       " elements exceeds the 32-bit CDR length");
    }
    put(static_cast<std::uint32_t>(n));
  }
  void string(const std::string& s) {
    length(s.size() + 1, "string");
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
  }
  void bytes(const std::vector<std::uint8_t>& b) {
    length(b.size(), "sequence<uint8>");
    out_.insert(out_.end(), b.begin(), b.end());
  }

 private:
  void align(std::size_t n) {
    const std::size_t pos = out_.size() - 4;
    out_.resize(out_.size() + (n - pos % n) % n, 0);
  }
  std::vector<std::uint8_t>& out_;
};

/// Appends a ROS 2 std_msgs/Header (builtin_interfaces/Time stamp, frame_id).
inline void cdr_header(CdrOut& w, double stamp_s, const std::string& frame_id) {
  const RosStamp t = ros_stamp(stamp_s);
  if (t.sec > static_cast<std::uint32_t>(std::numeric_limits<std::int32_t>::max())) {
    throw ValueError("bag writer: header stamp " + std::to_string(stamp_s) + " s overflows ROS 2's int32 seconds");
  }
  w.put(static_cast<std::int32_t>(t.sec));
  w.put(t.nsec);
  w.string(frame_id);
}

/// CDR serialisation of a sensor_msgs/msg/PointCloud2 (replaces `out`).
inline void serialize_cdr(const PointCloud2Msg& m, std::vector<std::uint8_t>& out) {
  CdrOut w(out);
  cdr_header(w, m.stamp_s, m.frame_id);
  w.put(m.height);
  w.put(m.width);
  w.length(m.fields.size(), "fields[]");
  for (const PointField& f : m.fields) {
    w.string(f.name);
    w.put(f.offset);
    w.put(f.datatype);
    w.put(f.count);
  }
  w.put(static_cast<std::uint8_t>(m.is_bigendian ? 1 : 0));
  w.put(m.point_step);
  w.put(m.row_step);
  w.bytes(m.data);
  w.put(static_cast<std::uint8_t>(m.is_dense ? 1 : 0));
}

/// CDR serialisation of a sensor_msgs/msg/Imu (replaces `out`).
inline void serialize_cdr(const ImuMsg& m, std::vector<std::uint8_t>& out) {
  CdrOut w(out);
  cdr_header(w, m.stamp_s, m.frame_id);
  w.put(m.orientation.x());
  w.put(m.orientation.y());
  w.put(m.orientation.z());
  w.put(m.orientation.w());
  for (const double c : m.orientation_covariance) w.put(c);
  for (int k = 0; k < 3; ++k) w.put(m.angular_velocity_radps[k]);
  for (const double c : m.angular_velocity_covariance) w.put(c);
  for (int k = 0; k < 3; ++k) w.put(m.linear_acceleration_mps2[k]);
  for (const double c : m.linear_acceleration_covariance) w.put(c);
}

/// A binary output file for the writers: every failure throws IoError naming
/// the path. Not copyable; closed by close() or the destructor.
class OutFile {
 public:
  explicit OutFile(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
    if (file_ == nullptr) throw IoError(semlio::detail::where(path, 0, "cannot open for writing"));
  }
  OutFile(const OutFile&) = delete;
  OutFile& operator=(const OutFile&) = delete;
  ~OutFile() {
    if (file_ != nullptr) std::fclose(file_);
  }
  /// Appends bytes.
  void write(const void* data, std::size_t n) {
    if (n > 0 && std::fwrite(data, 1, n, file_) != n) fail("write failed");
    pos_ += n;
  }
  void write(const std::vector<std::uint8_t>& b) { write(b.data(), b.size()); }
  /// Overwrites bytes at `offset` (earlier in the file), then returns to the end.
  void patch(std::uint64_t offset, const std::vector<std::uint8_t>& b) {
    if (offset > static_cast<std::uint64_t>(std::numeric_limits<long>::max()) ||
        std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0) {
      fail("seek failed");
    }
    if (!b.empty() && std::fwrite(b.data(), 1, b.size(), file_) != b.size()) fail("write failed");
    if (std::fseek(file_, 0, SEEK_END) != 0) fail("seek failed");
  }
  /// Bytes written so far (the offset of the next byte).
  [[nodiscard]] std::uint64_t position() const noexcept { return pos_; }
  /// Flushes and closes; throws IoError when that fails.
  void close() {
    if (file_ == nullptr) return;
    const int rc = std::fclose(file_);
    file_ = nullptr;
    if (rc != 0) throw IoError(semlio::detail::where(path_, 0, "close failed (disk full?)"));
  }
  [[nodiscard]] const std::string& path() const noexcept { return path_; }

 private:
  [[noreturn]] void fail(const char* what) {
    throw IoError(semlio::detail::where(path_, 0, std::string(what) + " at byte " + std::to_string(pos_)));
  }
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t pos_ = 0;
};

/// Appends a little-endian value to a byte buffer.
template <typename T>
void append_le(std::vector<std::uint8_t>& out, T v) {
  const auto at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &v, sizeof(T));
}

}  // namespace detail
}  // namespace semlio::io
