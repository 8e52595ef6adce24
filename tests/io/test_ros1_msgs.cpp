// ROS 1 deserialisation of sensor_msgs/PointCloud2 and sensor_msgs/Imu:
// messages serialised here field by field from the message definitions (the
// reference implementation's bytes are checked in test_rosbag1.cpp), every
// truncation, lying lengths, trailing bytes and the md5sum check.
#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/ros1_msgs.hpp>

namespace test_ros1_msgs {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::FormatError;
using semlio::io::ImuMsg;
using semlio::io::parse_ros1_imu;
using semlio::io::parse_ros1_pointcloud2;
using semlio::io::PointCloud2Msg;

/// ROS 1 serialiser of the test's own: little-endian, packed.
struct Ros1Writer {
  std::vector<std::uint8_t> out;
  template <typename T>
  void put(T v) {
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    out.insert(out.end(), raw, raw + sizeof(T));
  }
  void str(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    out.insert(out.end(), s.begin(), s.end());
  }
  void header(std::uint32_t seq, std::uint32_t sec, std::uint32_t nsec, const std::string& frame) {
    put(seq);
    put(sec);
    put(nsec);
    str(frame);
  }
};

/// A 2-point cloud: x y z float32 + ring uint16 (point_step 16, 2 bytes padding).
std::vector<std::uint8_t> cloud_bytes() {
  Ros1Writer w;
  w.header(42, 1317357625, 100000000, "velo_link");
  w.put(std::uint32_t{1});  // height
  w.put(std::uint32_t{2});  // width
  w.put(std::uint32_t{4});  // fields
  const char* names[] = {"x", "y", "z", "ring"};
  const std::uint32_t offsets[] = {0, 4, 8, 12};
  const std::uint8_t types[] = {7, 7, 7, 4};
  for (int i = 0; i < 4; ++i) {
    w.str(names[i]);
    w.put(offsets[i]);
    w.put(types[i]);
    w.put(std::uint32_t{1});
  }
  w.put(std::uint8_t{0});    // is_bigendian
  w.put(std::uint32_t{16});  // point_step
  w.put(std::uint32_t{32});  // row_step
  w.put(std::uint32_t{32});  // data length
  const float xyz[2][3] = {{1.5F, -2.0F, 0.25F}, {3.0F, 4.0F, -5.0F}};
  for (int p = 0; p < 2; ++p) {
    for (float v : xyz[p]) w.put(v);
    w.put(static_cast<std::uint16_t>(p + 7));
    w.put(std::uint16_t{0xBEEF});  // padding
  }
  w.put(std::uint8_t{1});  // is_dense
  return w.out;
}

std::vector<std::uint8_t> imu_bytes() {
  Ros1Writer w;
  w.header(3, 1317357624, 999999999, "imu_link");
  for (double v : {0.1, 0.2, 0.3, 0.9}) w.put(v);  // orientation x y z w
  for (int i = 0; i < 9; ++i) w.put(0.01 * i);
  for (double v : {-0.5, 0.25, 1.5}) w.put(v);  // angular velocity
  for (int i = 0; i < 9; ++i) w.put(0.02 * i);
  for (double v : {0.125, -9.81, 3.0}) w.put(v);  // linear acceleration
  w.put(-1.0);
  for (int i = 1; i < 9; ++i) w.put(0.0);
  return w.out;
}

}  // namespace

TEST_CASE("ros1 msgs: PointCloud2 fields, layout and data", "[io][ros1_msgs]") {
  const std::vector<std::uint8_t> bytes = cloud_bytes();
  const PointCloud2Msg m = parse_ros1_pointcloud2(bytes);
  CHECK(m.stamp_s == 1317357625.0 + 0.1);
  CHECK(m.frame_id == "velo_link");
  CHECK(m.height == 1);
  CHECK(m.width == 2);
  REQUIRE(m.fields.size() == 4);
  CHECK(m.fields[3].name == "ring");
  CHECK(m.fields[3].offset == 12);
  CHECK(m.fields[3].datatype == 4);
  CHECK(m.fields[3].count == 1);
  CHECK_FALSE(m.is_bigendian);
  CHECK(m.point_step == 16);
  CHECK(m.row_step == 32);
  CHECK(m.data.size() == 32);
  CHECK(m.is_dense);
  // And through the decoder: the values written above.
  const semlio::Scan s = semlio::io::pointcloud2_to_scan(m);
  REQUIRE(s.size() == 2);
  CHECK(s.points[0] == semlio::Point3f(1.5F, -2.0F, 0.25F));
  CHECK(s.points[1] == semlio::Point3f(3.0F, 4.0F, -5.0F));
  CHECK(s.rings == std::vector<std::uint16_t>{7, 8});
}

TEST_CASE("ros1 msgs: decoding straight from the message bytes equals deserialise-then-decode", "[io][ros1_msgs]") {
  const std::vector<std::uint8_t> bytes = cloud_bytes();
  const semlio::Scan two_steps = semlio::io::pointcloud2_to_scan(parse_ros1_pointcloud2(bytes));
  semlio::Scan direct;
  PointCloud2Msg header;
  semlio::io::PointCloud2Layout layout;
  semlio::io::ros1_pointcloud2_to_scan(bytes.data(), bytes.size(), direct, {}, &layout, nullptr, &header);
  CHECK(direct.points == two_steps.points);
  CHECK(direct.rings == two_steps.rings);
  CHECK(direct.stamp_s == two_steps.stamp_s);
  CHECK(header.frame_id == "velo_link");
  CHECK(header.data.empty());
  CHECK(layout.ring_field == "ring");
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    INFO("truncated to " << n << " bytes");
    CHECK_THROWS_AS(semlio::io::ros1_pointcloud2_to_scan(bytes.data(), n, direct), FormatError);
  }
}

TEST_CASE("ros1 msgs: Imu quaternion order, vectors and covariances", "[io][ros1_msgs]") {
  const ImuMsg m = parse_ros1_imu(imu_bytes());
  CHECK(m.stamp_s == 1317357624.0 + 999999999.0 / 1e9);
  CHECK(m.frame_id == "imu_link");
  CHECK(m.orientation.x() == 0.1);
  CHECK(m.orientation.y() == 0.2);
  CHECK(m.orientation.z() == 0.3);
  CHECK(m.orientation.w() == 0.9);
  CHECK(m.angular_velocity_radps == Eigen::Vector3d(-0.5, 0.25, 1.5));
  CHECK(m.linear_acceleration_mps2 == Eigen::Vector3d(0.125, -9.81, 3.0));
  CHECK(m.orientation_covariance[8] == 0.01 * 8);
  CHECK(m.angular_velocity_covariance[4] == 0.02 * 4);
  CHECK(m.linear_acceleration_covariance[0] == -1.0);
}

TEST_CASE("ros1 msgs: every truncation and trailing bytes are FormatErrors", "[io][ros1_msgs]") {
  const std::vector<std::uint8_t> cloud = cloud_bytes();
  PointCloud2Msg pc;
  for (std::size_t n = 0; n < cloud.size(); ++n) {
    INFO("cloud truncated to " << n << " bytes");
    CHECK_THROWS_AS(parse_ros1_pointcloud2(cloud.data(), n, pc), FormatError);
  }
  const std::vector<std::uint8_t> imu = imu_bytes();
  ImuMsg im;
  for (std::size_t n = 0; n < imu.size(); ++n) {
    INFO("imu truncated to " << n << " bytes");
    CHECK_THROWS_AS(parse_ros1_imu(imu.data(), n, im), FormatError);
  }
  std::vector<std::uint8_t> longer = imu;
  longer.push_back(0);
  CHECK_THROWS_WITH(parse_ros1_imu(longer), Catch::Contains("1 bytes left after the last field"));
  // An Imu is not a PointCloud2 and vice versa.
  CHECK_THROWS_AS(parse_ros1_pointcloud2(imu), FormatError);
  CHECK_THROWS_AS(parse_ros1_imu(cloud), FormatError);
}

TEST_CASE("ros1 msgs: lying lengths are rejected before anything is allocated for them", "[io][ros1_msgs]") {
  std::vector<std::uint8_t> bytes = cloud_bytes();
  SECTION("frame_id length") {
    const std::uint32_t huge = 0xFFFFFFF0U;
    std::memcpy(bytes.data() + 12, &huge, 4);
    CHECK_THROWS_WITH(parse_ros1_pointcloud2(bytes), Catch::Contains("header.frame_id"));
  }
  SECTION("field count") {
    const std::size_t at = 12 + 4 + 9 + 8;  // seq, stamp, frame_id, height, width
    const std::uint32_t huge = 0x7FFFFFFFU;
    std::memcpy(bytes.data() + at, &huge, 4);
    CHECK_THROWS_WITH(parse_ros1_pointcloud2(bytes), Catch::Contains("fields cannot fit"));
  }
  SECTION("data length") {
    const std::size_t at = bytes.size() - 1 - 32 - 4;
    const std::uint32_t huge = 1000;
    std::memcpy(bytes.data() + at, &huge, 4);
    CHECK_THROWS_WITH(parse_ros1_pointcloud2(bytes), Catch::Contains("reading 'data'"));
  }
}

TEST_CASE("ros1 msgs: md5sum check of the two types semlio reads", "[io][ros1_msgs]") {
  using semlio::io::check_ros1_md5sum;
  CHECK_NOTHROW(check_ros1_md5sum("sensor_msgs/PointCloud2", "1158d486dd51d683ce2f1be655c3c181", "bag"));
  CHECK_NOTHROW(check_ros1_md5sum("sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2", "bag"));
  CHECK_NOTHROW(check_ros1_md5sum("sensor_msgs/Imu", "*", "bag"));
  CHECK_NOTHROW(check_ros1_md5sum("nav_msgs/Odometry", "0123", "bag"));
  CHECK_THROWS_WITH(check_ros1_md5sum("sensor_msgs/Imu", "1158d486dd51d683ce2f1be655c3c181", "x.bag /imu"),
                    Catch::Contains("x.bag /imu") && Catch::Contains("expected 6a62c6daae103f4ff57a132d6f95cec2"));
}

}  // namespace test_ros1_msgs
