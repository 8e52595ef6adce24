// CDR (ROS 2) deserialisation of PointCloud2 and Imu on messages written
// byte by byte from the XCDR1 rules (OMG DDS-XTypes 1.3, 7.4.3; ROS 2's
// 4-byte encapsulation header), with every padding byte placed by hand --
// not by the decoder's own alignment code. The messages the reference
// writer (@foxglove/cdr) produced are decoded in test_mcap.cpp and
// test_sqlite_bag.cpp.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/cdr_msgs.hpp>

namespace test_cdr_msgs {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::io::ImuMsg;
using semlio::io::PointCloud2Msg;
using semlio::io::parse_cdr_imu;
using semlio::io::parse_cdr_pointcloud2;

/// Appends raw values in a chosen byte order; padding is explicit (pad()).
struct Bytes {
  bool big = false;
  std::vector<std::uint8_t> b;

  void u8(std::uint8_t v) { b.push_back(v); }
  void pad(int n) {
    for (int i = 0; i < n; ++i) b.push_back(0);
  }
  template <typename T>
  void put(T v) {
    std::array<std::uint8_t, sizeof(T)> raw{};
    std::memcpy(raw.data(), &v, sizeof(T));
    if (big) std::reverse(raw.begin(), raw.end());
    b.insert(b.end(), raw.begin(), raw.end());
  }
  void u32(std::uint32_t v) { put(v); }
  void i32(std::int32_t v) { put(v); }
  void f64(double v) { put(v); }
  /// CDR string: uint32 length including the NUL, bytes, NUL (no padding).
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    b.insert(b.end(), s.begin(), s.end());
    b.push_back(0);
  }
  /// Encapsulation header: 0x00 0x01 (little-endian) or 0x00 0x00 (big-endian), options 0.
  void encapsulation() {
    b = {0x00, static_cast<std::uint8_t>(big ? 0x00 : 0x01), 0x00, 0x00};
  }
};

/// sensor_msgs/msg/Imu with frame_id "ab": the header ends at payload offset
/// 15 (4 sec + 4 nanosec + 4 length + "ab\0"), so ONE pad byte brings the
/// first float64 to payload offset 16. (Aligning to the buffer start instead
/// would need five.)
std::vector<std::uint8_t> imu_bytes(bool big) {
  Bytes m;
  m.big = big;
  m.encapsulation();
  m.i32(1317357624);
  m.u32(500000000);
  m.str("ab");
  m.pad(1);
  for (double v : {0.1, -0.2, 0.3, 0.9}) m.f64(v);  // orientation x y z w
  for (int i = 0; i < 9; ++i) m.f64(i * 0.5);
  for (double v : {0.01, 0.02, -0.03}) m.f64(v);
  for (int i = 0; i < 9; ++i) m.f64(-i * 1.0);
  for (double v : {0.25, -9.81, 1.5}) m.f64(v);
  for (int i = 0; i < 9; ++i) m.f64(i + 100.0);
  return m.b;
}

/// sensor_msgs/msg/PointCloud2 with frame_id "velo" and two fields, two
/// points. Payload offsets (after the 4-byte header) in the comments.
std::vector<std::uint8_t> cloud_bytes(bool big) {
  Bytes m;
  m.big = big;
  m.encapsulation();
  m.i32(-5);          // 0 sec (negative: before the epoch)
  m.u32(999999999);   // 4 nanosec
  m.str("velo");      // 8 length 5, 12..16 "velo\0" -> 17
  m.pad(3);           // 17 -> 20
  m.u32(1);           // 20 height
  m.u32(2);           // 24 width
  m.u32(2);           // 28 fields: 2
  m.str("x");         // 32 length 2, "x\0" -> 38
  m.pad(2);           // 38 -> 40
  m.u32(0);           // 40 offset
  m.u8(7);            // 44 datatype FLOAT32
  m.pad(3);           // 45 -> 48
  m.u32(1);           // 48 count
  m.str("ring");      // 52 length 5, "ring\0" -> 61
  m.pad(3);           // 61 -> 64
  m.u32(4);           // 64 offset
  m.u8(4);            // 68 datatype UINT16
  m.pad(3);           // 69 -> 72
  m.u32(1);           // 72 count
  m.u8(1);            // 76 is_bigendian
  m.pad(3);           // 77 -> 80
  m.u32(8);           // 80 point_step
  m.u32(16);          // 84 row_step
  m.u32(16);          // 88 data length
  for (std::uint8_t i = 0; i < 16; ++i) m.u8(static_cast<std::uint8_t>(0xA0 + i));  // 92..108
  m.u8(0);            // 108 is_dense
  return m.b;
}

void check_imu(const ImuMsg& msg) {
  CHECK(msg.stamp_s == 1317357624.0 + 500000000.0 / 1e9);
  CHECK(msg.frame_id == "ab");
  CHECK(msg.orientation.x() == 0.1);
  CHECK(msg.orientation.y() == -0.2);
  CHECK(msg.orientation.z() == 0.3);
  CHECK(msg.orientation.w() == 0.9);
  CHECK(msg.angular_velocity_radps == Eigen::Vector3d(0.01, 0.02, -0.03));
  CHECK(msg.linear_acceleration_mps2 == Eigen::Vector3d(0.25, -9.81, 1.5));
  for (std::size_t i = 0; i < 9; ++i) {
    CHECK(msg.orientation_covariance[i] == static_cast<double>(i) * 0.5);
    CHECK(msg.angular_velocity_covariance[i] == -static_cast<double>(i));
    CHECK(msg.linear_acceleration_covariance[i] == static_cast<double>(i) + 100.0);
  }
}

void check_cloud(const PointCloud2Msg& msg) {
  CHECK(msg.stamp_s == -5.0 + 999999999.0 / 1e9);
  CHECK(msg.frame_id == "velo");
  CHECK(msg.height == 1);
  CHECK(msg.width == 2);
  REQUIRE(msg.fields.size() == 2);
  CHECK(msg.fields[0].name == "x");
  CHECK(msg.fields[0].offset == 0);
  CHECK(msg.fields[0].datatype == 7);
  CHECK(msg.fields[0].count == 1);
  CHECK(msg.fields[1].name == "ring");
  CHECK(msg.fields[1].offset == 4);
  CHECK(msg.fields[1].datatype == 4);
  CHECK(msg.fields[1].count == 1);
  CHECK(msg.is_bigendian);
  CHECK(msg.point_step == 8);
  CHECK(msg.row_step == 16);
  REQUIRE(msg.data.size() == 16);
  for (std::size_t i = 0; i < 16; ++i) CHECK(msg.data[i] == 0xA0 + i);
  CHECK_FALSE(msg.is_dense);
}

}  // namespace

TEST_CASE("CDR Imu: alignment counted from the end of the encapsulation header, both byte orders", "[io][ros][cdr]") {
  for (const bool big : {false, true}) {
    CAPTURE(big);
    const std::vector<std::uint8_t> bytes = imu_bytes(big);
    REQUIRE(bytes.size() == 4 + 16 + 37 * 8);  // header, 16 payload bytes to the first float64, 37 float64
    check_imu(parse_cdr_imu(bytes));
  }
}

TEST_CASE("CDR PointCloud2: header, fields, data and flags in both byte orders", "[io][ros][cdr]") {
  for (const bool big : {false, true}) {
    CAPTURE(big);
    const std::vector<std::uint8_t> bytes = cloud_bytes(big);
    REQUIRE(bytes.size() == 4 + 109);
    check_cloud(parse_cdr_pointcloud2(bytes));
  }
}

TEST_CASE("CDR PointCloud2: decoding into a used message replaces every field", "[io][ros][cdr]") {
  PointCloud2Msg msg;
  msg.fields.resize(5);
  msg.data.assign(1000, 0xFF);
  msg.frame_id = "something long";
  const std::vector<std::uint8_t> bytes = cloud_bytes(false);
  parse_cdr_pointcloud2(bytes.data(), bytes.size(), msg);
  check_cloud(msg);
}

TEST_CASE("CDR: up to 3 padding bytes after the last field are accepted, more are an error", "[io][ros][cdr]") {
  std::vector<std::uint8_t> bytes = cloud_bytes(false);
  for (int extra = 1; extra <= 3; ++extra) {
    bytes.push_back(0);
    CHECK_NOTHROW(parse_cdr_pointcloud2(bytes));
  }
  bytes.push_back(0);
  CHECK_THROWS_AS(parse_cdr_pointcloud2(bytes), semlio::FormatError);
  // An Imu is not a PointCloud2 (and the other way round).
  CHECK_THROWS_AS(parse_cdr_pointcloud2(imu_bytes(false)), semlio::FormatError);
  CHECK_THROWS_AS(parse_cdr_imu(cloud_bytes(false)), semlio::FormatError);
}

TEST_CASE("CDR: every truncation is a FormatError", "[io][ros][cdr]") {
  const std::vector<std::uint8_t> cloud = cloud_bytes(false);
  const std::vector<std::uint8_t> imu = imu_bytes(true);
  for (std::size_t n = 0; n < cloud.size(); ++n) {
    CAPTURE(n);
    const std::vector<std::uint8_t> cut(cloud.begin(), cloud.begin() + static_cast<std::ptrdiff_t>(n));
    CHECK_THROWS_AS(parse_cdr_pointcloud2(cut), semlio::FormatError);
  }
  for (std::size_t n = 0; n < imu.size(); ++n) {
    CAPTURE(n);
    const std::vector<std::uint8_t> cut(imu.begin(), imu.begin() + static_cast<std::ptrdiff_t>(n));
    CHECK_THROWS_AS(parse_cdr_imu(cut), semlio::FormatError);
  }
}

TEST_CASE("CDR: lying lengths, bad encapsulations, strings and bools are FormatErrors", "[io][ros][cdr]") {
  const std::vector<std::uint8_t> good = cloud_bytes(false);
  const auto with = [&](std::size_t payload_offset, std::uint32_t v) {
    std::vector<std::uint8_t> b = good;
    std::memcpy(b.data() + 4 + payload_offset, &v, 4);
    return b;
  };
  SECTION("data length beyond the buffer") {
    CHECK_THROWS_AS(parse_cdr_pointcloud2(with(88, 0xFFFFFFFFU)), semlio::FormatError);
    CHECK_THROWS_AS(parse_cdr_pointcloud2(with(88, 17)), semlio::FormatError);
  }
  SECTION("field count beyond what the bytes can hold") {
    CHECK_THROWS_AS(parse_cdr_pointcloud2(with(28, 0xFFFFFFFFU)), semlio::FormatError);
    CHECK_THROWS_AS(parse_cdr_pointcloud2(with(28, 3)), semlio::FormatError);
  }
  SECTION("string lengths: beyond the buffer, or without the terminating NUL") {
    CHECK_THROWS_AS(parse_cdr_pointcloud2(with(8, 0x7FFFFFFFU)), semlio::FormatError);
    CHECK_THROWS_AS(parse_cdr_pointcloud2(with(8, 4)), semlio::FormatError);  // "velo" without its NUL
  }
  SECTION("encapsulation kinds other than plain CDR") {
    for (const int kind : {0x02, 0x03, 0x06, 0x07, 0x10, 0x11}) {
      std::vector<std::uint8_t> b = good;
      b[1] = static_cast<std::uint8_t>(kind);
      CAPTURE(kind);
      CHECK_THROWS_AS(parse_cdr_pointcloud2(b), semlio::FormatError);
    }
    std::vector<std::uint8_t> b = good;
    b[0] = 0x01;
    CHECK_THROWS_AS(parse_cdr_pointcloud2(b), semlio::FormatError);
  }
  SECTION("a bool that is neither 0 nor 1") {
    std::vector<std::uint8_t> b = good;
    b[4 + 76] = 2;  // is_bigendian
    CHECK_THROWS_AS(parse_cdr_pointcloud2(b), semlio::FormatError);
  }
  SECTION("the message names the type and field") {
    try {
      parse_cdr_pointcloud2(with(88, 1000));
      FAIL("no exception");
    } catch (const semlio::FormatError& e) {
      const std::string what = e.what();
      CHECK(what.find("PointCloud2") != std::string::npos);
      CHECK(what.find("'data'") != std::string::npos);
    }
  }
}

TEST_CASE("CDR: random byte damage gives a typed error or a message, never a crash", "[io][ros][cdr]") {
  std::mt19937 rng(7);
  const std::vector<std::vector<std::uint8_t>> sources = {cloud_bytes(false), cloud_bytes(true), imu_bytes(false)};
  int errors = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<std::uint8_t> b = sources[static_cast<std::size_t>(trial) % sources.size()];
    const int flips = 1 + trial % 4;
    for (int f = 0; f < flips; ++f) {
      b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng)] =
          static_cast<std::uint8_t>(std::uniform_int_distribution<int>(0, 255)(rng));
    }
    try {
      PointCloud2Msg cloud;
      ImuMsg imu;
      parse_cdr_pointcloud2(b.data(), b.size(), cloud);
      parse_cdr_imu(b.data(), b.size(), imu);
    } catch (const semlio::FormatError&) {
      ++errors;
    }
  }
  // No buffer is both a PointCloud2 and an Imu (their sizes differ by far
  // more than the 3 bytes of padding allowed), so every trial must throw.
  CHECK(errors == 3000);
}

}  // namespace test_cdr_msgs
