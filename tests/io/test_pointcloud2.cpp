// PointCloud2 -> Scan: every driver layout (Velodyne, Ouster, Hesai,
// Robosense, Livox), padding, organised clouds, byte order, dropped points,
// time conventions, and every inconsistent message the decoder must reject.
// Clouds are written here by an encoder of the test's own (explicit byte
// order per field), not by the decoder's helpers.
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <semlio/io/pointcloud2.hpp>

namespace test_pointcloud2 {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::FormatError;
using semlio::Scan;
using semlio::io::PointCloud2Layout;
using semlio::io::PointCloud2Config;
using semlio::io::PointCloud2Msg;
using semlio::io::PointField;
using semlio::io::PointTimeMode;
using semlio::io::ReadStats;
using semlio::io::pointcloud2_to_scan;

constexpr std::uint8_t kI8 = 1, kU8 = 2, kI16 = 3, kU16 = 4, kI32 = 5, kU32 = 6, kF32 = 7, kF64 = 8;

/// A cloud under construction: fields, steps, padding bytes 0xAB everywhere.
struct CloudWriter {
  PointCloud2Msg msg;

  CloudWriter(std::uint32_t height, std::uint32_t width, std::uint32_t point_step, std::uint32_t row_pad,
              std::vector<PointField> fields, bool big_endian = false, double stamp_s = 1700000000.5) {
    msg.stamp_s = stamp_s;
    msg.frame_id = "test";
    msg.height = height;
    msg.width = width;
    msg.fields = std::move(fields);
    msg.is_bigendian = big_endian;
    msg.point_step = point_step;
    msg.row_step = width * point_step + row_pad;
    msg.data.assign(std::size_t{height} * msg.row_step, 0xAB);
  }

  /// Writes v into field `name` of point (r, c) in the cloud's byte order.
  template <typename T>
  void put(std::uint32_t r, std::uint32_t c, const std::string& name, T v) {
    const auto it = std::find_if(msg.fields.begin(), msg.fields.end(), [&](const PointField& f) { return f.name == name; });
    REQUIRE(it != msg.fields.end());
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));  // the test host is little-endian
    if (msg.is_bigendian) std::reverse(raw, raw + sizeof(T));
    std::memcpy(msg.data.data() + std::size_t{r} * msg.row_step + std::size_t{c} * msg.point_step + it->offset, raw,
                sizeof(T));
  }
};

PointField field(const std::string& name, std::uint32_t offset, std::uint8_t type) {
  return PointField{name, offset, type, 1};
}

/// Point j's coordinates: exact in float, distinct x per j (x recovers j).
float px(std::size_t j) { return 1.0F + 0.25F * static_cast<float>(j); }
float py(std::size_t j) { return -0.5F * static_cast<float>(j); }
float pz(std::size_t j) { return 0.125F * static_cast<float>(j % 64) - 2.0F; }
std::size_t index_of(float x) { return static_cast<std::size_t>(std::lround((x - 1.0F) / 0.25F)); }

/// velodyne_pointcloud PointXYZIRT: x y z (+pad) intensity f32, ring u16, time f32, step 32.
CloudWriter velodyne_cloud(std::uint32_t n, bool big = false) {
  CloudWriter w(1, n, 32, 0,
                {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("intensity", 16, kF32),
                 field("ring", 20, kU16), field("time", 24, kF32)},
                big);
  for (std::uint32_t j = 0; j < n; ++j) {
    w.put(0, j, "x", px(j));
    w.put(0, j, "y", py(j));
    w.put(0, j, "z", pz(j));
    w.put(0, j, "intensity", static_cast<float>(j % 256));
    w.put(0, j, "ring", static_cast<std::uint16_t>(j % 32));
    w.put(0, j, "time", static_cast<float>((static_cast<double>(j) - n) * 1e-5));  // negative: stamp = sweep end
  }
  return w;
}

template <typename E, typename F>
void require_throws_with(F&& f, const std::string& fragment) {
  bool thrown = false;
  try {
    f();
  } catch (const E& e) {
    thrown = true;
    INFO("message: " << e.what());
    CHECK(std::string(e.what()).find(fragment) != std::string::npos);
  }
  CHECK(thrown);
}

}  // namespace

TEST_CASE("pointcloud2: Velodyne layout with padding bytes and negative relative float32 times", "[io][pointcloud2]") {
  const std::uint32_t n = 200;
  const CloudWriter w = velodyne_cloud(n);
  PointCloud2Layout layout;
  ReadStats stats;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout, &stats);
  REQUIRE(s.size() == n);
  REQUIRE(s.has_intensity());
  REQUIRE(s.has_rings());
  REQUIRE(s.has_times());
  s.validate();
  for (std::uint32_t j = 0; j < n; ++j) {
    CHECK(s.points[j].x() == px(j));
    CHECK(s.points[j].y() == py(j));
    CHECK(s.points[j].z() == pz(j));
    CHECK(s.intensity[j] == static_cast<float>(j % 256));
    CHECK(s.rings[j] == j % 32);
    // Time since the earliest point (j = 0): j * 10 us.
    CHECK(s.times_s[j] == Approx(j * 1e-5).margin(1e-8));
  }
  // Sweep start = header stamp + the first point's (negative) relative time.
  const double t0 = static_cast<double>(static_cast<float>(-static_cast<double>(n) * 1e-5));
  CHECK(s.stamp_s == w.msg.stamp_s + t0);
  CHECK(s.times_s[0] == 0.0F);
  CHECK(layout.coordinate_type == kF32);
  CHECK(layout.intensity_field == "intensity");
  CHECK(layout.ring_field == "ring");
  CHECK(layout.ring_type == kU16);
  CHECK(layout.time_field == "time");
  CHECK(layout.time_type == kF32);
  CHECK(layout.time_mode == PointTimeMode::kRelativeSeconds);
  CHECK(layout.header_minus_earliest_s == Approx(n * 1e-5).margin(1e-7));
  CHECK(layout.points_in == n);
  CHECK(layout.points_out == n);
  CHECK(stats.dropped() == 0);
}

TEST_CASE("pointcloud2: Ouster organised cloud with row padding, uint8 ring, uint32 ns t, NaN and zero points",
          "[io][pointcloud2]") {
  // ouster_ros Point (ring u8 in older drivers): 8 rows of 40, 16 pad bytes per row.
  const std::uint32_t rows = 8, cols = 40;
  CloudWriter w(rows, cols, 48, 16,
                {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("intensity", 16, kF32),
                 field("t", 20, kU32), field("reflectivity", 24, kU16), field("ring", 26, kU8),
                 field("ambient", 28, kU16), field("range", 32, kU32)});
  w.msg.is_dense = false;
  std::size_t nan_points = 0, zero_points = 0;
  for (std::uint32_t r = 0; r < rows; ++r) {
    for (std::uint32_t c = 0; c < cols; ++c) {
      const std::size_t j = r * cols + c;
      float x = px(j), y = py(j), z = pz(j);
      if (j % 17 == 5) {
        (j % 3 == 0 ? x : j % 3 == 1 ? y : z) = std::numeric_limits<float>::quiet_NaN();
        ++nan_points;
      } else if (j % 23 == 7) {
        x = y = z = 0.0F;
        ++zero_points;
      }
      w.put(r, c, "x", x);
      w.put(r, c, "y", y);
      w.put(r, c, "z", z);
      w.put(r, c, "intensity", static_cast<float>(j % 256));
      w.put(r, c, "t", static_cast<std::uint32_t>(c * 25000 + 1000));  // column time, ns since the stamp
      w.put(r, c, "reflectivity", std::uint16_t{7});
      w.put(r, c, "ring", static_cast<std::uint8_t>(r));
    }
  }
  PointCloud2Layout layout;
  ReadStats stats;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout, &stats);
  s.validate();
  CHECK(stats.dropped_nonfinite == nan_points);
  CHECK(stats.dropped_zero == zero_points);
  REQUIRE(s.size() == rows * cols - nan_points - zero_points);
  REQUIRE(s.rings.size() == s.size());
  // Every kept point carries its own ring, intensity and time (no shift after a drop).
  std::size_t previous = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::size_t j = index_of(s.points[i].x());
    INFO("kept point " << i << " is point " << j);
    CHECK((i == 0 || j > previous));
    previous = j;
    CHECK(j % 17 != 5);
    CHECK(j % 23 != 7);
    CHECK(s.points[i].y() == py(j));
    CHECK(s.rings[i] == j / cols);
    CHECK(s.intensity[i] == static_cast<float>(j % 256));
    CHECK(s.times_s[i] == Approx((j % cols) * 25e-6).margin(1e-9));
  }
  // Earliest point: t = 1000 ns after the header stamp.
  CHECK(s.stamp_s == Approx(w.msg.stamp_s + 1e-6).epsilon(0).margin(1e-9));
  CHECK(layout.time_mode == PointTimeMode::kRelativeNanoseconds);
  CHECK(layout.ring_type == kU8);
  CHECK(layout.points_in == rows * cols);
  CHECK(layout.points_out == s.size());
}

TEST_CASE("pointcloud2: Hesai float64 absolute seconds, header stamped at the sweep's end", "[io][pointcloud2]") {
  const std::uint32_t n = 120;
  const double first = 1700000123.25;  // exact in double
  CloudWriter w(1, n, 48, 0,
                {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("intensity", 16, kF32),
                 field("timestamp", 24, kF64), field("ring", 32, kU16)},
                false, first + 0.1);
  for (std::uint32_t j = 0; j < n; ++j) {
    w.put(0, j, "x", px(j));
    w.put(0, j, "y", py(j));
    w.put(0, j, "z", pz(j));
    w.put(0, j, "intensity", 3.5F);
    w.put(0, j, "timestamp", first + j * 1e-4);
    w.put(0, j, "ring", static_cast<std::uint16_t>(j % 32));
  }
  PointCloud2Layout layout;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout);
  REQUIRE(s.size() == n);
  CHECK(s.stamp_s == first);
  CHECK(layout.time_mode == PointTimeMode::kAbsoluteSeconds);
  CHECK(layout.header_minus_earliest_s == Approx(0.1).margin(1e-9));
  // float64 epoch seconds are rounded to 2.4e-7 s (their ulp at 1.7e9 s).
  for (std::uint32_t j = 0; j < n; ++j) CHECK(s.times_s[j] == Approx(j * 1e-4).margin(3e-7));
}

TEST_CASE("pointcloud2: the earliest point need not be the first one", "[io][pointcloud2]") {
  CloudWriter w = velodyne_cloud(50);
  w.put(0, 30, "time", -0.5F);  // point 30 is the earliest
  const Scan s = pointcloud2_to_scan(w.msg);
  CHECK(s.stamp_s == w.msg.stamp_s - 0.5);
  CHECK(s.times_s[30] == 0.0F);
  CHECK(s.times_s[0] == Approx(0.5 - 50e-5).margin(1e-7));
  CHECK(*std::min_element(s.times_s.begin(), s.times_s.end()) == 0.0F);
}

TEST_CASE("pointcloud2: a point time far from the reference is a FormatError, not an infinite time",
          "[io][pointcloud2]") {
  // Found by fuzzing (tests/fuzz/crashes/ros1_pointcloud2): an absolute
  // float64 timestamp of 4.3e96 s gave a time offset beyond float's range,
  // an infinite Scan::times_s.
  CloudWriter w = velodyne_cloud(50);
  w.put(0, 7, "time", 3e38F);  // float32 relative seconds, finite
  CHECK_THROWS_AS(pointcloud2_to_scan(w.msg), FormatError);
  CHECK_THROWS_WITH(pointcloud2_to_scan(w.msg), Catch::Contains("at point 7") && Catch::Contains("limit"));
  w.put(0, 7, "time", static_cast<float>(semlio::io::kMaxPointTimeOffset_s / 2));  // within the limit
  const Scan s = pointcloud2_to_scan(w.msg);
  CHECK(s.size() == 50);
  for (const float t : s.times_s) CHECK(std::isfinite(t));
}

TEST_CASE("pointcloud2: Robosense uint8 intensity, uint16 ring, float64 absolute timestamp", "[io][pointcloud2]") {
  const std::uint32_t n = 64;
  CloudWriter w(1, n, 32, 0,
                {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("intensity", 16, kU8),
                 field("ring", 18, kU16), field("timestamp", 24, kF64)});
  for (std::uint32_t j = 0; j < n; ++j) {
    w.put(0, j, "x", px(j));
    w.put(0, j, "y", py(j));
    w.put(0, j, "z", pz(j));
    w.put(0, j, "intensity", static_cast<std::uint8_t>(200 + j % 50));
    w.put(0, j, "ring", static_cast<std::uint16_t>(j % 16));
    w.put(0, j, "timestamp", 1700000000.0 + (n - j) * 1e-5);  // reversed: the last point is the earliest
  }
  PointCloud2Layout layout;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout);
  REQUIRE(s.size() == n);
  CHECK(layout.intensity_type == kU8);
  CHECK(s.intensity[3] == 203.0F);
  CHECK(s.rings[17] == 1);
  CHECK(s.stamp_s == Approx(1700000000.0 + 1e-5).epsilon(0).margin(1e-7));
  CHECK(s.times_s[n - 1] == 0.0F);
  CHECK(s.times_s[0] == Approx((n - 1) * 1e-5).margin(3e-7));
}

TEST_CASE("pointcloud2: Livox packed 22-byte points with uint32 offset_time and no ring", "[io][pointcloud2]") {
  const std::uint32_t n = 77;
  CloudWriter w(1, n, 22, 0,
                {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("intensity", 12, kF32),
                 field("tag", 16, kU8), field("line", 17, kU8), field("offset_time", 18, kU32)});
  for (std::uint32_t j = 0; j < n; ++j) {
    w.put(0, j, "x", px(j));
    w.put(0, j, "y", py(j));
    w.put(0, j, "z", pz(j));
    w.put(0, j, "intensity", 10.0F);
    w.put(0, j, "offset_time", static_cast<std::uint32_t>(j * 100000));
  }
  PointCloud2Layout layout;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout);
  REQUIRE(s.size() == n);
  CHECK_FALSE(s.has_rings());
  CHECK(layout.ring_field.empty());
  CHECK(layout.time_field == "offset_time");
  CHECK(s.stamp_s == w.msg.stamp_s);
  CHECK(s.times_s[76] == Approx(76 * 1e-4).margin(1e-8));
  CHECK(s.points[76].x() == px(76));
  // The Livox line id as ring when the user says so.
  PointCloud2Config cfg;
  cfg.ring_fields = {"ring", "line"};
  for (std::uint32_t j = 0; j < n; ++j) w.put(0, j, "line", static_cast<std::uint8_t>(j % 6));
  const Scan with_line = pointcloud2_to_scan(w.msg, cfg);
  REQUIRE(with_line.has_rings());
  CHECK(with_line.rings[13] == 1);
}

TEST_CASE("pointcloud2: livox_ros_driver2 float64 absolute nanoseconds", "[io][pointcloud2]") {
  const std::uint32_t n = 10;
  CloudWriter w(1, n, 24, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("timestamp", 16, kF64)});
  const double first_ns = 1700000000.0 * 1e9;  // 1.7e18, exact in double
  for (std::uint32_t j = 0; j < n; ++j) {
    w.put(0, j, "x", px(j));
    w.put(0, j, "y", py(j));
    w.put(0, j, "z", pz(j));
    w.put(0, j, "timestamp", first_ns + j * 1024.0 * 1024.0);  // steps exact at this magnitude (ulp 256 ns)
  }
  PointCloud2Layout layout;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout);
  CHECK(layout.time_mode == PointTimeMode::kAbsoluteNanoseconds);
  CHECK(s.stamp_s == 1700000000.0);
  CHECK(s.times_s[9] == Approx(9 * 1048576e-9).margin(1e-9));
}

TEST_CASE("pointcloud2: a big-endian cloud decodes to the same scan as its little-endian twin", "[io][pointcloud2]") {
  const CloudWriter le = velodyne_cloud(90, false);
  const CloudWriter be = velodyne_cloud(90, true);
  REQUIRE(le.msg.data != be.msg.data);  // the bytes really differ
  const Scan a = pointcloud2_to_scan(le.msg);
  const Scan b = pointcloud2_to_scan(be.msg);
  REQUIRE(a.size() == b.size());
  CHECK(a.points == b.points);
  CHECK(a.intensity == b.intensity);
  CHECK(a.rings == b.rings);
  CHECK(a.times_s == b.times_s);
  CHECK(a.stamp_s == b.stamp_s);
}

TEST_CASE("pointcloud2: float64 coordinates, big-endian, with int16 ring", "[io][pointcloud2]") {
  CloudWriter w(2, 3, 32, 8, {field("x", 0, kF64), field("y", 8, kF64), field("z", 16, kF64), field("ring", 24, kI16)}, true);
  for (std::uint32_t r = 0; r < 2; ++r) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      w.put(r, c, "x", 1.5 + c);
      w.put(r, c, "y", -2.0 * r);
      w.put(r, c, "z", 1e-3);
      w.put(r, c, "ring", static_cast<std::int16_t>(r + 10));
    }
  }
  PointCloud2Layout layout;
  const Scan s = pointcloud2_to_scan(w.msg, {}, &layout);
  REQUIRE(s.size() == 6);
  CHECK(layout.coordinate_type == kF64);
  CHECK(s.points[4] == semlio::Point3f(2.5F, -2.0F, 1e-3F));
  CHECK(s.rings[4] == 11);
  CHECK_FALSE(s.has_intensity());
  CHECK_FALSE(s.has_times());
  CHECK(s.stamp_s == w.msg.stamp_s);  // no time field: the header stamp
  CHECK(layout.header_minus_earliest_s == 0.0);
}

TEST_CASE("pointcloud2: intensity falls back to reflectivity, configured lists and time modes", "[io][pointcloud2]") {
  CloudWriter w(1, 4, 16, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("reflectivity", 12, kU16)});
  for (std::uint32_t j = 0; j < 4; ++j) {
    w.put(0, j, "x", px(j));
    w.put(0, j, "y", py(j));
    w.put(0, j, "z", pz(j));
    w.put(0, j, "reflectivity", static_cast<std::uint16_t>(1000 + j));
  }
  PointCloud2Layout layout;
  Scan s = pointcloud2_to_scan(w.msg, {}, &layout);
  CHECK(layout.intensity_field == "reflectivity");
  CHECK(s.intensity == std::vector<float>{1000.0F, 1001.0F, 1002.0F, 1003.0F});
  // With intensity disabled, and reflectivity read as a time in explicit relative ns.
  PointCloud2Config cfg;
  cfg.intensity_fields = {};
  cfg.time_fields = {"reflectivity"};
  cfg.time_mode = PointTimeMode::kRelativeNanoseconds;
  s = pointcloud2_to_scan(w.msg, cfg, &layout);
  CHECK_FALSE(s.has_intensity());
  CHECK(layout.time_mode == PointTimeMode::kRelativeNanoseconds);
  CHECK(s.stamp_s == Approx(w.msg.stamp_s + 1e-6).epsilon(0).margin(1e-9));
  CHECK(s.times_s[3] == Approx(3e-9).margin(1e-12));
}

TEST_CASE("pointcloud2: zero points can be kept, an empty cloud is an empty scan", "[io][pointcloud2]") {
  CloudWriter w(1, 2, 12, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32)});
  w.put(0, 0, "x", 0.0F);
  w.put(0, 0, "y", 0.0F);
  w.put(0, 0, "z", 0.0F);
  w.put(0, 1, "x", 1.0F);
  w.put(0, 1, "y", 2.0F);
  w.put(0, 1, "z", 3.0F);
  CHECK(pointcloud2_to_scan(w.msg).size() == 1);
  PointCloud2Config keep;
  keep.drop_zero_points = false;
  CHECK(pointcloud2_to_scan(w.msg, keep).size() == 2);
  CloudWriter empty(0, 0, 12, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32)});
  const Scan e = pointcloud2_to_scan(empty.msg);
  CHECK(e.empty());
  CHECK(e.stamp_s == empty.msg.stamp_s);
  // Found by fuzzing: width 0 with height 2^32 - 1 (no points, no data) made
  // the decoder walk four billion empty rows. It is an empty scan at once.
  CloudWriter tall(0, 0, 16, 0,
                   {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("time", 8, kF64)});
  tall.msg.height = 0xFFFFFFFFU;
  const auto start = std::chrono::steady_clock::now();
  CHECK(pointcloud2_to_scan(tall.msg).empty());
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::milliseconds(100));
}

TEST_CASE("pointcloud2: inconsistent messages are FormatErrors naming the problem", "[io][pointcloud2]") {
  const auto decode = [](const PointCloud2Msg& m) { return [m] { (void)pointcloud2_to_scan(m); }; };
  SECTION("data shorter than height * row_step") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.data.pop_back();
    require_throws_with<FormatError>(decode(w.msg), "shorter than height");
  }
  SECTION("a field beyond point_step") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields.push_back(field("extra", 30, kU32));
    require_throws_with<FormatError>(decode(w.msg), "beyond point_step");
  }
  SECTION("a field count reaching beyond point_step") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields[3].count = 5;
    require_throws_with<FormatError>(decode(w.msg), "beyond point_step");
  }
  SECTION("point_step * width > row_step") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.row_step -= 1;
    require_throws_with<FormatError>(decode(w.msg), "exceeds row_step");
  }
  SECTION("an unknown datatype") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields[5].datatype = 9;
    require_throws_with<FormatError>(decode(w.msg), "unknown datatype 9");
  }
  SECTION("no z field") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields[2].name = "zz";
    require_throws_with<FormatError>(decode(w.msg), "no 'z' field");
  }
  SECTION("an integer coordinate") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields[0].datatype = kI32;
    require_throws_with<FormatError>(decode(w.msg), "expected float32 or float64");
  }
  SECTION("a duplicate field name") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields[4].name = "intensity";
    require_throws_with<FormatError>(decode(w.msg), "appears twice");
  }
  SECTION("a float ring") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.fields[4].datatype = kF32;
    require_throws_with<FormatError>(decode(w.msg), "ring field 'ring' has datatype float32");
  }
  SECTION("a ring value outside 0..65535") {
    CloudWriter w(1, 1, 16, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("ring", 12, kI32)});
    w.put(0, 0, "x", 1.0F);
    w.put(0, 0, "ring", std::int32_t{-1});
    require_throws_with<FormatError>(decode(w.msg), "outside 0..65535");
  }
  SECTION("an 8-bit time field in auto mode") {
    CloudWriter w(1, 1, 13, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("t", 12, kI8)});
    require_throws_with<FormatError>(decode(w.msg), "too narrow for a time");
  }
  SECTION("absolute nanoseconds beyond int64") {
    CloudWriter w(1, 1, 20, 0, {field("x", 0, kF32), field("y", 4, kF32), field("z", 8, kF32), field("timestamp", 12, kF64)});
    w.put(0, 0, "x", 1.0F);
    w.put(0, 0, "timestamp", 1e30);
    require_throws_with<FormatError>(decode(w.msg), "not an epoch time");
  }
  SECTION("huge height and width with little data: no overflow, no over-read") {
    CloudWriter w = velodyne_cloud(10);
    w.msg.height = 0xFFFFFFFFU;
    w.msg.width = 0xFFFFFFFFU;
    w.msg.row_step = 0xFFFFFFFFU;
    w.msg.point_step = 32;
    require_throws_with<FormatError>(decode(w.msg), "height * width overflows");
    w.msg.width = 1;
    require_throws_with<FormatError>(decode(w.msg), "shorter than height");
  }
}

TEST_CASE("pointcloud2: random layouts and bytes give a scan or a FormatError, never an over-read",
          "[io][pointcloud2]") {
  std::mt19937 rng(12345);
  std::size_t decoded = 0, rejected = 0;
  const char* names[] = {"x", "y", "z", "intensity", "ring", "time", "t", "timestamp", "offset_time"};
  const auto u = [&rng](std::uint32_t n) { return static_cast<std::uint32_t>(rng() % n); };
  for (int trial = 0; trial < 3000; ++trial) {
    PointCloud2Msg m;
    m.height = u(4);
    m.width = u(9);
    m.point_step = 20 + u(20);
    // Usually consistent steps and sizes (so decoding runs), sometimes one byte short.
    m.row_step = m.width * m.point_step + u(3);
    if (u(8) == 0 && m.row_step > 0) --m.row_step;
    m.is_bigendian = u(2) == 0;
    // Usually x, y, z of a floating type (so decoding gets past them), then random fields.
    if (u(8) != 0) {
      const auto t = static_cast<std::uint8_t>(7 + u(2));
      for (const char* c : {"x", "y", "z"}) m.fields.push_back(PointField{c, u(28), t, 1});
    }
    const std::uint32_t nf = u(5);
    for (std::uint32_t f = 0; f < nf; ++f) {
      m.fields.push_back(PointField{names[3 + u(6)], u(40), static_cast<std::uint8_t>(u(10)), u(3)});
    }
    std::size_t bytes = std::size_t{m.height} * m.row_step + u(3);
    if (u(8) == 0 && bytes > 0) --bytes;
    m.data.resize(bytes);
    for (auto& b : m.data) b = static_cast<std::uint8_t>(rng());
    try {
      const Scan s = pointcloud2_to_scan(m);
      s.validate();
      ++decoded;
    } catch (const FormatError&) {
      ++rejected;
    }
  }
  // Both outcomes occur, so the loop exercised the decoder and the checks.
  CHECK(decoded > 10);
  CHECK(rejected > 10);
}

}  // namespace test_pointcloud2
