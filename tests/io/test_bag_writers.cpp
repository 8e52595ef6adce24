// Bag writers (io/bag/rosbag1_writer.hpp, mcap_writer.hpp,
// ros_writer_msgs.hpp): the bytes they write, read back at the offsets the
// formats document (ROS wiki Bags/Format/2.0, mcap.dev/spec, ROS 1
// serialisation, OMG CDR). The readers' round trip is tested with the
// readers; scripts/check_sim_bags.sh runs the reference readers.
#include <catch2/catch.hpp>

#include <zstd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/bag/mcap_writer.hpp>
#include <semlio/io/bag/ros_writer_msgs.hpp>
#include <semlio/io/bag/rosbag1_writer.hpp>

namespace test_bag_writers {  // one namespace per test file: the area compiles as one TU

namespace io = semlio::io;
using Bytes = std::vector<std::uint8_t>;

namespace {

template <typename T>
T at(const Bytes& b, std::size_t offset) {
  REQUIRE(offset + sizeof(T) <= b.size());
  T v;
  std::memcpy(&v, b.data() + offset, sizeof(T));
  return v;
}

std::string str_at(const Bytes& b, std::size_t offset, std::size_t n) {
  REQUIRE(offset + n <= b.size());
  return {reinterpret_cast<const char*>(b.data() + offset), n};
}

Bytes read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("semlio_test_bag_writers_" + name);
}

/// A 3-point scan with rings and times.
semlio::Scan small_scan() {
  semlio::Scan s;
  s.stamp_s = 12.25;
  s.points = {Eigen::Vector3f(1.0F, 2.0F, 3.0F), Eigen::Vector3f(-4.0F, 0.5F, -1.0F), Eigen::Vector3f(3.0F, 4.0F, 0.0F)};
  s.intensity = {0.25F, 0.5F, 1.0F};
  s.rings = {0, 7, 15};
  s.times_s = {0.0F, 0.05F, 0.0999F};
  return s;
}

io::ImuMsg small_imu() {
  io::ImuMsg m;
  m.stamp_s = 1317643200.01;
  m.frame_id = "imu";
  m.orientation = Eigen::Quaterniond(0.5, 0.5, 0.5, 0.5);
  m.orientation_covariance[0] = -1.0;
  m.angular_velocity_radps = Eigen::Vector3d(0.1, -0.2, 0.3);
  m.linear_acceleration_mps2 = Eigen::Vector3d(0.5, 0.25, 9.81);
  m.linear_acceleration_covariance[8] = 2.25e-4;
  return m;
}

/// ROS bag 2.0 record: header fields (name -> value bytes) and data.
struct BagRecord {
  std::map<std::string, Bytes> fields;
  Bytes data;
  std::size_t end = 0;  ///< offset just past the record
};

BagRecord bag_record(const Bytes& b, std::size_t offset) {
  BagRecord r;
  const auto header_len = at<std::uint32_t>(b, offset);
  std::size_t p = offset + 4;
  const std::size_t header_end = p + header_len;
  while (p < header_end) {
    const auto len = at<std::uint32_t>(b, p);
    const std::string field = str_at(b, p + 4, len);
    const auto eq = field.find('=');
    REQUIRE(eq != std::string::npos);
    r.fields[field.substr(0, eq)] = Bytes(field.begin() + static_cast<std::ptrdiff_t>(eq) + 1, field.end());
    p += 4 + len;
  }
  REQUIRE(p == header_end);
  const auto data_len = at<std::uint32_t>(b, p);
  REQUIRE(p + 4 + data_len <= b.size());
  r.data.assign(b.begin() + static_cast<std::ptrdiff_t>(p + 4), b.begin() + static_cast<std::ptrdiff_t>(p + 4 + data_len));
  r.end = p + 4 + data_len;
  return r;
}

template <typename T>
T field_as(const BagRecord& r, const std::string& name) {
  const auto it = r.fields.find(name);
  REQUIRE(it != r.fields.end());
  REQUIRE(it->second.size() == sizeof(T));
  return at<T>(it->second, 0);
}

std::string field_str(const BagRecord& r, const std::string& name) {
  const auto it = r.fields.find(name);
  REQUIRE(it != r.fields.end());
  return {it->second.begin(), it->second.end()};
}

}  // namespace

TEST_CASE("Velodyne cloud layout: x y z intensity ring time packed in 22 bytes", "[io][bags]") {
  const semlio::Scan s = small_scan();
  const io::PointCloud2Msg m = io::scan_to_pointcloud2(s, {}, "velodyne");
  CHECK(m.stamp_s == 12.25);
  CHECK(m.frame_id == "velodyne");
  REQUIRE(m.fields.size() == 6);
  const char* names[] = {"x", "y", "z", "intensity", "ring", "time"};
  const std::uint32_t offsets[] = {0, 4, 8, 12, 16, 18};
  const std::uint8_t types[] = {7, 7, 7, 7, 4, 7};  // FLOAT32, UINT16 (sensor_msgs/PointField)
  for (std::size_t k = 0; k < 6; ++k) {
    CHECK(m.fields[k].name == names[k]);
    CHECK(m.fields[k].offset == offsets[k]);
    CHECK(m.fields[k].datatype == types[k]);
    CHECK(m.fields[k].count == 1);
  }
  CHECK(m.point_step == 22);
  CHECK(m.height == 1);
  CHECK(m.width == 3);
  CHECK(m.row_step == 66);
  REQUIRE(m.data.size() == 66);
  CHECK(at<float>(m.data, 22 + 0) == -4.0F);
  CHECK(at<float>(m.data, 22 + 4) == 0.5F);
  CHECK(at<float>(m.data, 22 + 12) == 0.5F);
  CHECK(at<std::uint16_t>(m.data, 44 + 16) == 15);
  CHECK(at<float>(m.data, 44 + 18) == 0.0999F);
  // Without ring and time: 16 bytes per point, four fields.
  const io::PointCloud2Msg bare = io::scan_to_pointcloud2(s, {.ring = false, .time = false}, "v");
  CHECK(bare.point_step == 16);
  CHECK(bare.fields.size() == 4);
  // Time only: it moves up to offset 16.
  const io::PointCloud2Msg t_only = io::scan_to_pointcloud2(s, {.ring = false}, "v");
  REQUIRE(t_only.fields.size() == 5);
  CHECK(t_only.fields[4].offset == 16);
  CHECK(at<float>(t_only.data, 20 + 16) == 0.05F);
}

TEST_CASE("Ouster cloud layout: ouster_ros's 48-byte point, t in ns", "[io][bags]") {
  const semlio::Scan s = small_scan();
  const io::PointCloud2Msg m = io::scan_to_pointcloud2(s, {.layout = io::CloudLayout::kOuster}, "os_sensor");
  CHECK(m.point_step == 48);
  std::map<std::string, std::pair<std::uint32_t, std::uint8_t>> f;
  for (const io::PointField& pf : m.fields) f[pf.name] = {pf.offset, pf.datatype};
  CHECK(f.at("intensity") == std::make_pair(16U, std::uint8_t{7}));
  CHECK(f.at("t") == std::make_pair(20U, std::uint8_t{6}));  // UINT32
  CHECK(f.at("ring") == std::make_pair(26U, std::uint8_t{4}));
  CHECK(f.at("range") == std::make_pair(32U, std::uint8_t{6}));
  CHECK(at<float>(m.data, 48 + 16) == 0.5F);
  // 0.05F is 0.0500000007450581 s: 50000000.745 ns, rounded to the nearest ns.
  CHECK(at<std::uint32_t>(m.data, 48 + 20) == 50000001U);
  CHECK(at<std::uint16_t>(m.data, 96 + 26) == 15);
  CHECK(at<std::uint32_t>(m.data, 96 + 32) == 5000U);  // |(3, 4, 0)| = 5 m in mm
  const io::PointCloud2Msg bare =
      io::scan_to_pointcloud2(s, {.layout = io::CloudLayout::kOuster, .ring = false, .time = false}, "o");
  for (const io::PointField& pf : bare.fields) CHECK((pf.name != "t" && pf.name != "ring"));
  CHECK(at<std::uint32_t>(bare.data, 48 + 20) == 0U);  // not written
}

TEST_CASE("cloud packing rejects missing or bad per-point fields", "[io][bags]") {
  semlio::Scan s = small_scan();
  s.times_s.clear();
  CHECK_THROWS_AS(io::scan_to_pointcloud2(s, {}, "v"), semlio::ValueError);
  CHECK_NOTHROW(io::scan_to_pointcloud2(s, {.time = false}, "v"));
  s = small_scan();
  s.rings.pop_back();
  CHECK_THROWS_AS(io::scan_to_pointcloud2(s, {}, "v"), semlio::ValueError);
  s = small_scan();
  s.times_s[1] = -0.01F;
  try {
    (void)io::scan_to_pointcloud2(s, {}, "v");
    FAIL("no exception");
  } catch (const semlio::ValueError& e) {
    CHECK_THAT(e.what(), Catch::Contains("point 1"));
  }
}

TEST_CASE("ROS 1 serialisation: header, then fields back to back", "[io][bags]") {
  const io::ImuMsg imu = small_imu();
  Bytes b;
  io::detail::serialize_ros1(imu, 7, b);
  // seq, stamp.sec, stamp.nsec, frame_id (uint32 length, no NUL), then
  // 4 + 9 + 3 + 9 + 3 + 9 float64.
  REQUIRE(b.size() == 4 + 8 + 4 + 3 + 37 * 8);
  CHECK(at<std::uint32_t>(b, 0) == 7);
  CHECK(at<std::uint32_t>(b, 4) == 1317643200U);
  CHECK(std::abs(static_cast<double>(at<std::uint32_t>(b, 8)) - 1e7) < 300.0);  // 0.01 s, double-rounded
  CHECK(at<std::uint32_t>(b, 12) == 3);
  CHECK(str_at(b, 16, 3) == "imu");
  CHECK(at<double>(b, 19) == 0.5);                 // orientation.x
  CHECK(at<double>(b, 19 + 4 * 8) == -1.0);        // orientation_covariance[0]
  CHECK(at<double>(b, 19 + 13 * 8 + 8) == -0.2);   // angular_velocity.y
  CHECK(at<double>(b, 19 + 25 * 8 + 16) == 9.81);  // linear_acceleration.z
  CHECK(at<double>(b, 19 + 36 * 8) == 2.25e-4);    // linear_acceleration_covariance[8]

  const io::PointCloud2Msg cloud = io::scan_to_pointcloud2(small_scan(), {}, "v");
  io::detail::serialize_ros1(cloud, 0, b);
  // header 4+4+4+(4+1); height, width; 6 fields; is_bigendian; steps; data; is_dense.
  std::size_t p = 17;
  CHECK(at<std::uint32_t>(b, p) == 1);
  CHECK(at<std::uint32_t>(b, p + 4) == 3);
  CHECK(at<std::uint32_t>(b, p + 8) == 6);
  p += 12;
  for (const io::PointField& f : cloud.fields) p += 4 + f.name.size() + 4 + 1 + 4;
  CHECK(b[p] == 0);
  CHECK(at<std::uint32_t>(b, p + 1) == 22);
  CHECK(at<std::uint32_t>(b, p + 5) == 66);
  CHECK(at<std::uint32_t>(b, p + 9) == 66);
  CHECK(std::equal(cloud.data.begin(), cloud.data.end(), b.begin() + static_cast<std::ptrdiff_t>(p + 13)));
  CHECK(b.size() == p + 13 + 66 + 1);
  CHECK(b.back() == 1);  // is_dense
}

TEST_CASE("CDR serialisation: encapsulation header, aligned primitives, NUL-terminated strings", "[io][bags]") {
  Bytes b;
  io::detail::serialize_cdr(small_imu(), b);
  CHECK(b[0] == 0x00);
  CHECK(b[1] == 0x01);  // CDR_LE
  CHECK(at<std::int32_t>(b, 4) == 1317643200);
  CHECK(at<std::uint32_t>(b, 12) == 4);  // "imu" + NUL
  CHECK(str_at(b, 16, 4) == std::string("imu\0", 4));
  // The first float64 aligns to 8 counted from byte 4: byte 20 is 16 from
  // there, aligned already (a 4-character frame_id would need 4 bytes of padding).
  CHECK(at<double>(b, 20) == 0.5);
  CHECK(b.size() == 20 + 37 * 8);
  CHECK(at<double>(b, 20 + 36 * 8) == 2.25e-4);
  io::ImuMsg padded = small_imu();
  padded.frame_id = "imu0";
  io::detail::serialize_cdr(padded, b);
  CHECK(at<double>(b, 28) == 0.5);
  CHECK(b.size() == 28 + 37 * 8);

  const io::PointCloud2Msg cloud = io::scan_to_pointcloud2(small_scan(), {}, "v");
  io::detail::serialize_cdr(cloud, b);
  // stamp 8, frame_id "v\0" (len 2) -> ends at 4+8+4+2 = 18; height aligns to 20.
  CHECK(at<std::uint32_t>(b, 20) == 1);
  CHECK(at<std::uint32_t>(b, 24) == 3);
  CHECK(at<std::uint32_t>(b, 28) == 6);
  CHECK(at<std::uint32_t>(b, 32) == 2);  // "x\0"
  CHECK(str_at(b, 36, 2) == std::string("x\0", 2));
  CHECK(at<std::uint32_t>(b, 40) == 0);  // x.offset, aligned from 38 to 40
  CHECK(b[44] == 7);                     // x.datatype
  CHECK(at<std::uint32_t>(b, 48) == 1);  // x.count, aligned from 45 to 48
  CHECK(b.back() == 1);                  // is_dense
  CHECK(std::equal(cloud.data.begin(), cloud.data.end(), b.end() - 67));
  CHECK(at<std::uint32_t>(b, b.size() - 71) == 66);  // sequence<uint8> length
}

TEST_CASE("ROS stamps split whole seconds before rounding to ns", "[io][bags]") {
  const auto t = io::detail::ros_stamp(1317643200.1);
  CHECK(t.sec == 1317643200U);
  CHECK(std::abs(static_cast<double>(t.nsec) - 1e8) < 300.0);  // the double holds 1317643200.1 to ~120 ns
  const auto z = io::detail::ros_stamp(2.0);
  CHECK(z.sec == 2U);
  CHECK(z.nsec == 0U);
  CHECK_THROWS_AS(io::detail::ros_stamp(-1.0), semlio::ValueError);
  CHECK_THROWS_AS(io::detail::ros_stamp(std::nan("")), semlio::ValueError);
}

TEST_CASE("Rosbag1Writer: magic, 4096-byte header, chunk, index, connections and chunk infos", "[io][bags]") {
  const auto path = temp_path("small.bag");
  io::ImuMsg imu = small_imu();
  const io::PointCloud2Msg cloud = io::scan_to_pointcloud2(small_scan(), {}, "v");
  {
    io::Rosbag1Writer w(path.string());
    const std::size_t points = w.add_topic("/points", io::RosMessageType::kPointCloud2);
    const std::size_t imu_topic = w.add_topic("/imu/data", io::RosMessageType::kImu);
    w.write(imu_topic, 1000000000LL, imu);
    w.write(points, 1500000000LL, cloud);
    imu.stamp_s += 0.01;
    w.write(imu_topic, 2000000001LL, imu);
    CHECK_THROWS_AS(w.write(imu_topic, 0, cloud), semlio::ValueError);  // wrong type
    CHECK_THROWS_AS(w.write(5, 0, imu), semlio::ValueError);            // unknown topic
    CHECK_THROWS_AS(w.write(imu_topic, -1, imu), semlio::ValueError);   // negative time
    CHECK(w.message_count() == 3);
    w.close();
  }
  const Bytes b = read_file(path);
  REQUIRE(str_at(b, 0, 13) == "#ROSBAG V2.0\n");
  const BagRecord header = bag_record(b, 13);
  CHECK(header.end == 13 + 8 + 4096);  // header_len + data_len fields + 4096 bytes
  CHECK(field_as<std::uint8_t>(header, "op") == 0x03);
  CHECK(field_as<std::uint32_t>(header, "conn_count") == 2);
  CHECK(field_as<std::uint32_t>(header, "chunk_count") == 1);
  const auto index_pos = field_as<std::uint64_t>(header, "index_pos");

  // The chunk right after the header; its data holds connection and message records.
  const BagRecord chunk = bag_record(b, header.end);
  CHECK(field_as<std::uint8_t>(chunk, "op") == 0x05);
  CHECK(field_str(chunk, "compression") == "none");
  CHECK(field_as<std::uint32_t>(chunk, "size") == chunk.data.size());
  std::vector<BagRecord> inner;
  for (std::size_t p = 0; p < chunk.data.size();) {
    inner.push_back(bag_record(chunk.data, p));
    p = inner.back().end;
  }
  REQUIRE(inner.size() == 5);  // imu connection, imu msg, points connection, points msg, imu msg
  CHECK(field_as<std::uint8_t>(inner[0], "op") == 0x07);
  CHECK(field_str(inner[0], "topic") == "/imu/data");
  CHECK(field_as<std::uint8_t>(inner[1], "op") == 0x02);
  CHECK(field_as<std::uint32_t>(inner[1], "conn") == 1);
  CHECK(field_as<std::uint64_t>(inner[1], "time") == (std::uint64_t{0} << 32 | 1U));  // sec 1, nsec 0
  Bytes expect;
  io::detail::serialize_ros1(small_imu(), 0, expect);
  CHECK(inner[1].data == expect);
  io::detail::serialize_ros1(cloud, 0, expect);
  CHECK(inner[3].data == expect);
  CHECK(at<std::uint32_t>(inner[4].data, 0) == 1);  // the IMU topic's second message: seq 1
  // Connection data: topic, type, md5sum, message_definition.
  const BagRecord conn_data = bag_record(
      [&] {
        Bytes wrapped;
        io::detail::append_le(wrapped, static_cast<std::uint32_t>(inner[2].data.size()));
        wrapped.insert(wrapped.end(), inner[2].data.begin(), inner[2].data.end());
        io::detail::append_le(wrapped, std::uint32_t{0});
        return wrapped;
      }(),
      0);
  CHECK(field_str(conn_data, "type") == "sensor_msgs/PointCloud2");
  CHECK(field_str(conn_data, "md5sum") == "1158d486dd51d683ce2f1be655c3c181");
  CHECK_THAT(field_str(conn_data, "message_definition"), Catch::StartsWith("Header header\nuint32 height\n") &&
                                                            Catch::Contains("MSG: sensor_msgs/PointField\n"));

  // Index data records after the chunk: one per connection, offsets into the chunk.
  const BagRecord idx_points = bag_record(b, chunk.end);
  CHECK(field_as<std::uint8_t>(idx_points, "op") == 0x04);
  CHECK(field_as<std::uint32_t>(idx_points, "conn") == 0);
  CHECK(field_as<std::uint32_t>(idx_points, "count") == 1);
  CHECK(at<std::uint32_t>(idx_points.data, 0) == 1);          // sec
  CHECK(at<std::uint32_t>(idx_points.data, 4) == 500000000);  // nsec
  CHECK(at<std::uint32_t>(idx_points.data, 8) == inner[2].end);
  const BagRecord idx_imu = bag_record(b, idx_points.end);
  CHECK(field_as<std::uint32_t>(idx_imu, "count") == 2);
  CHECK(at<std::uint32_t>(idx_imu.data, 12) == 2);  // second entry: sec 2
  CHECK(at<std::uint32_t>(idx_imu.data, 16) == 1);  // nsec 1
  CHECK(at<std::uint32_t>(idx_imu.data, 20) == inner[3].end);

  // At index_pos: both connections, then the chunk info.
  REQUIRE(index_pos == idx_imu.end);
  const BagRecord c0 = bag_record(b, index_pos);
  const BagRecord c1 = bag_record(b, c0.end);
  CHECK(field_str(c0, "topic") == "/points");
  CHECK(field_str(c1, "topic") == "/imu/data");
  const BagRecord info = bag_record(b, c1.end);
  CHECK(field_as<std::uint8_t>(info, "op") == 0x06);
  CHECK(field_as<std::uint64_t>(info, "chunk_pos") == header.end);
  CHECK(field_as<std::uint64_t>(info, "start_time") == (std::uint64_t{0} << 32 | 1U));
  CHECK(field_as<std::uint64_t>(info, "end_time") == (std::uint64_t{1} << 32 | 2U));
  CHECK(field_as<std::uint32_t>(info, "count") == 2);
  CHECK(info.end == b.size());
  std::filesystem::remove(path);
}

TEST_CASE("Rosbag1Writer splits chunks at chunk_bytes and reports unwritable paths", "[io][bags]") {
  const auto path = temp_path("chunks.bag");
  {
    io::Rosbag1Writer w(path.string(), {.chunk_bytes = 300});
    const std::size_t t = w.add_topic("/imu", io::RosMessageType::kImu);
    for (int k = 0; k < 5; ++k) w.write(t, k * 10000000LL, small_imu());
  }  // the destructor closes
  const Bytes b = read_file(path);
  const BagRecord header = bag_record(b, 13);
  CHECK(field_as<std::uint32_t>(header, "chunk_count") == 5);  // each ~360-byte IMU record closes a chunk
  CHECK_THROWS_AS(io::Rosbag1Writer("/nonexistent-dir/x.bag"), semlio::IoError);
  CHECK_THROWS_AS(io::Rosbag1Writer(path.string(), {.chunk_bytes = 0}), semlio::ConfigError);
  std::filesystem::remove(path);
}

TEST_CASE("CRC-32 is the ISO-HDLC one MCAP uses", "[io][bags]") {
  const std::string check = "123456789";
  // The standard check value of CRC-32/ISO-HDLC.
  CHECK(io::detail::mcap_crc32(reinterpret_cast<const std::uint8_t*>(check.data()), check.size()) == 0xCBF43926U);
  // Continuation equals one pass.
  const auto* p = reinterpret_cast<const std::uint8_t*>(check.data());
  CHECK(io::detail::mcap_crc32(p + 4, 5, io::detail::mcap_crc32(p, 4)) == 0xCBF43926U);
}

TEST_CASE("McapWriter: magic, header, chunk, message index, summary, footer and CRCs", "[io][bags]") {
  for (const bool zstd : {false, true}) {
    INFO("zstd " << zstd);
    const auto path = temp_path(zstd ? "z.mcap" : "n.mcap");
    const io::PointCloud2Msg cloud = io::scan_to_pointcloud2(small_scan(), {}, "v");
    {
      io::McapWriter w(path.string(), {.compression = zstd ? io::McapCompression::kZstd : io::McapCompression::kNone});
      const std::size_t points = w.add_topic("/points", io::RosMessageType::kPointCloud2);
      const std::size_t imu = w.add_topic("/imu/data", io::RosMessageType::kImu);
      w.add_topic("/unused", io::RosMessageType::kImu);
      w.write(imu, 1000, small_imu());
      w.write(points, 2000, cloud);
      CHECK_THROWS_AS(w.write(points, 3000, small_imu()), semlio::ValueError);
      w.close();
    }
    const Bytes b = read_file(path);
    const std::uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
    REQUIRE(b.size() > 16);
    CHECK(std::memcmp(b.data(), magic, 8) == 0);
    CHECK(std::memcmp(b.data() + b.size() - 8, magic, 8) == 0);
    // Header record: profile "ros2", library.
    CHECK(b[8] == 0x01);
    CHECK(at<std::uint32_t>(b, 17) == 4);
    CHECK(str_at(b, 21, 4) == "ros2");
    const std::size_t chunk_at = 9 + 8 + at<std::uint64_t>(b, 9) + 0;
    // Chunk: start/end times, sizes, CRC of the uncompressed records, compression, records.
    REQUIRE(b[chunk_at] == 0x06);
    const std::size_t c = chunk_at + 9;
    CHECK(at<std::uint64_t>(b, c) == 1000);
    CHECK(at<std::uint64_t>(b, c + 8) == 2000);
    const auto uncompressed_size = at<std::uint64_t>(b, c + 16);
    const auto crc = at<std::uint32_t>(b, c + 24);
    const auto compression_len = at<std::uint32_t>(b, c + 28);
    CHECK(str_at(b, c + 32, compression_len) == (zstd ? "zstd" : ""));
    const std::size_t rec_len_at = c + 32 + compression_len;
    const auto records_len = at<std::uint64_t>(b, rec_len_at);
    Bytes records(b.begin() + static_cast<std::ptrdiff_t>(rec_len_at + 8),
                  b.begin() + static_cast<std::ptrdiff_t>(rec_len_at + 8 + records_len));
    if (zstd) {
      Bytes raw(static_cast<std::size_t>(uncompressed_size));
      REQUIRE(ZSTD_decompress(raw.data(), raw.size(), records.data(), records.size()) == raw.size());
      records = raw;
    }
    REQUIRE(records.size() == uncompressed_size);
    CHECK(io::detail::mcap_crc32(records.data(), records.size()) == crc);
    // Inside: Schema (Imu), Channel (/imu/data), Message, Schema, Channel, Message.
    std::vector<std::pair<std::uint8_t, std::size_t>> ops;  // (opcode, offset)
    for (std::size_t p = 0; p < records.size(); p += 9 + at<std::uint64_t>(records, p + 1)) ops.emplace_back(records[p], p);
    REQUIRE(ops.size() == 6);
    CHECK(ops[0].first == 0x03);
    CHECK(ops[1].first == 0x04);
    CHECK(ops[2].first == 0x05);
    CHECK(ops[5].first == 0x05);
    const std::size_t msg = ops[5].second + 9;
    CHECK(at<std::uint16_t>(records, msg) == 1);     // channel id of /points
    CHECK(at<std::uint32_t>(records, msg + 2) == 0);  // sequence
    CHECK(at<std::uint64_t>(records, msg + 6) == 2000);
    Bytes expect;
    io::detail::serialize_cdr(cloud, expect);
    CHECK(Bytes(records.begin() + static_cast<std::ptrdiff_t>(msg + 22), records.begin() + static_cast<std::ptrdiff_t>(ops[5].second + 9 + at<std::uint64_t>(records, ops[5].second + 1))) == expect);
    // Schema 0x03: id, name, encoding, data.
    const std::size_t sch = ops[0].second + 9;
    CHECK(at<std::uint32_t>(records, sch + 2) == 19);
    CHECK(str_at(records, sch + 6, 19) == "sensor_msgs/msg/Imu");
    CHECK(str_at(records, sch + 29, 7) == "ros2msg");

    // Message indexes follow the chunk: channel 1 (/points) then 2 (/imu/data).
    const std::size_t after_chunk = chunk_at + 9 + at<std::uint64_t>(b, chunk_at + 1);
    REQUIRE(b[after_chunk] == 0x07);
    CHECK(at<std::uint16_t>(b, after_chunk + 9) == 1);
    CHECK(at<std::uint32_t>(b, after_chunk + 11) == 16);
    CHECK(at<std::uint64_t>(b, after_chunk + 15) == 2000);
    CHECK(at<std::uint64_t>(b, after_chunk + 23) == ops[5].second);

    // Footer: summary_start, summary_offset_start, CRC over the summary up to the CRC field.
    const std::size_t footer = b.size() - 8 - 29;
    REQUIRE(b[footer] == 0x02);
    const auto summary_start = at<std::uint64_t>(b, footer + 9);
    const auto summary_offset_start = at<std::uint64_t>(b, footer + 17);
    CHECK(at<std::uint32_t>(b, footer + 25) ==
          io::detail::mcap_crc32(b.data() + summary_start, footer + 25 - static_cast<std::size_t>(summary_start)));
    // DataEnd right before the summary; the summary opens with the schemas.
    CHECK(b[summary_start - 13] == 0x0F);
    CHECK(b[summary_start] == 0x03);
    // Summary offsets: schema, channel, statistics, chunk index groups.
    std::vector<std::uint8_t> groups;
    for (std::size_t p = summary_offset_start; p < footer; p += 9 + at<std::uint64_t>(b, p + 1)) {
      REQUIRE(b[p] == 0x0E);
      groups.push_back(b[p + 9]);
      const auto start = at<std::uint64_t>(b, p + 10);
      CHECK(b[start] == b[p + 9]);
    }
    CHECK(groups == std::vector<std::uint8_t>{0x03, 0x04, 0x0B, 0x08});
    // Statistics: 2 messages, 2 schemas, 2 channels with messages, 1 chunk.
    std::size_t stats = summary_start;
    while (b[stats] != 0x0B) stats += 9 + at<std::uint64_t>(b, stats + 1);
    CHECK(at<std::uint64_t>(b, stats + 9) == 2);
    CHECK(at<std::uint16_t>(b, stats + 17) == 2);
    CHECK(at<std::uint32_t>(b, stats + 19) == 2);
    CHECK(at<std::uint32_t>(b, stats + 31) == 1);
    std::size_t ci = summary_start;
    while (b[ci] != 0x08) ci += 9 + at<std::uint64_t>(b, ci + 1);
    CHECK(at<std::uint64_t>(b, ci + 9 + 16) == chunk_at);  // chunk_start_offset
    std::filesystem::remove(path);
  }
}

TEST_CASE("McapWriter: rosbag2's zstd presets (-5 without chunk CRC, 19), bad settings leave the file alone",
          "[io][bags]") {
  const io::PointCloud2Msg cloud = io::scan_to_pointcloud2(small_scan(), {}, "v");
  Bytes expect;  // the chunk's records: Schema, Channel, Message of the one cloud
  for (const auto& [level, chunk_crc] : {std::pair{-5, false}, std::pair{19, true}}) {
    INFO("level " << level);
    const auto path = temp_path("preset.mcap");
    {
      io::McapWriter w(path.string(), {.zstd_level = level, .chunk_crc = chunk_crc});
      w.write(w.add_topic("/points", io::RosMessageType::kPointCloud2), 2000, cloud);
      w.close();
    }
    const Bytes b = read_file(path);
    const std::size_t chunk_at = 9 + 8 + at<std::uint64_t>(b, 9);
    REQUIRE(b[chunk_at] == 0x06);
    const std::size_t c = chunk_at + 9;
    const auto uncompressed_size = at<std::uint64_t>(b, c + 16);
    const auto crc = at<std::uint32_t>(b, c + 24);
    const std::size_t rec_len_at = c + 32 + at<std::uint32_t>(b, c + 28);
    const auto records_len = at<std::uint64_t>(b, rec_len_at);
    REQUIRE(rec_len_at + 8 + records_len <= b.size());
    Bytes records(static_cast<std::size_t>(uncompressed_size));
    REQUIRE(ZSTD_decompress(records.data(), records.size(), b.data() + rec_len_at + 8, records_len) == records.size());
    // 0 is MCAP's "not computed", what rosbag2's zstd_fast preset stores.
    CHECK(crc == (chunk_crc ? io::detail::mcap_crc32(records.data(), records.size()) : 0U));
    if (expect.empty()) {
      expect = records;
    } else {
      CHECK(records == expect);  // the level changes the bytes on disk, not the records
    }
    std::filesystem::remove(path);
  }
  // Invalid settings are refused before the file is touched: an existing file keeps its bytes.
  const auto path = temp_path("bad_level.mcap");
  std::ofstream(path) << "keep me";
  CHECK_THROWS_AS(io::McapWriter(path.string(), {.zstd_level = 0}), semlio::ConfigError);
  CHECK_THROWS_AS(io::McapWriter(path.string(), {.zstd_level = ZSTD_minCLevel() - 1}), semlio::ConfigError);
  CHECK_THROWS_AS(io::McapWriter(path.string(), {.zstd_level = ZSTD_maxCLevel() + 1}), semlio::ConfigError);
  CHECK_THROWS_AS(io::McapWriter(path.string(), {.chunk_bytes = 0}), semlio::ConfigError);
  CHECK_THROWS_AS(io::Rosbag1Writer(path.string(), {.chunk_bytes = 0}), semlio::ConfigError);
  CHECK(read_file(path) == Bytes{'k', 'e', 'e', 'p', ' ', 'm', 'e'});
  std::filesystem::remove(path);
}

}  // namespace test_bag_writers
