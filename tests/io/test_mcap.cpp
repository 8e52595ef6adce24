// MCAP reader on files written by the reference implementation (@mcap/core,
// @foxglove/cdr; scripts/fixtures/make_mcap_fixtures.mjs): the real KITTI
// scans bit-exact against their PCD files, real OXTS IMU values against
// their text lines, the small files' clouds and IMU messages against the
// script's formulas (exact binary fractions), zstd / lz4 / uncompressed
// chunks, no chunks, a streamed file without summary, big-endian CDR, chunks
// overlapping in time, and damaged copies that must fail with typed errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/mcap.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/ros1_msgs.hpp>
#include <semlio_test/bag_compare.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_cloud_files.hpp>

namespace test_mcap {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::io::BagMessage;
using semlio::io::BagTopic;
using semlio::io::ImuMsg;
using semlio::io::McapReader;
using semlio::io::MessageEncoding;
using semlio::io::PointCloud2Msg;
using semlio::io::parse_cdr_imu;
using semlio::io::parse_cdr_pointcloud2;
using semlio_test::data_path;

std::string bag(const std::string& name) { return data_path("bags/" + name); }

/// Index of the topic named `name` (fails the test when absent).
std::size_t topic_index(const std::vector<BagTopic>& topics, const std::string& name) {
  for (std::size_t i = 0; i < topics.size(); ++i) {
    if (topics[i].name == name) return i;
  }
  FAIL("no topic " << name);
  return 0;
}

/// Every selected message of a reader.
std::vector<BagMessage> read_all(McapReader& reader) {
  std::vector<BagMessage> out;
  BagMessage m;
  while (reader.next(m)) out.push_back(m);
  return out;
}

/// Header stamp as the decoders compute it: double(sec) + double(nanosec) / 1e9.
double stamp(std::int64_t sec, std::int64_t nanosec) {
  return static_cast<double>(sec) + static_cast<double>(nanosec) / 1e9;
}

float f32_at(const std::vector<std::uint8_t>& data, std::size_t offset) {
  float v = 0;
  std::memcpy(&v, data.data() + offset, 4);
  return v;
}

// ---- the small files' formulas (make_mcap_fixtures.mjs: smallCloud, paddedCloud, smallImu)
constexpr std::int64_t kBaseSec = 1700000000;

void check_small_cloud(const PointCloud2Msg& c, int k) {
  CAPTURE(k);
  CHECK(c.stamp_s == stamp(kBaseSec, k * 100000000LL));
  CHECK(c.frame_id == "lidar");
  CHECK(c.height == 1);
  CHECK(c.width == 300);
  REQUIRE(c.fields.size() == 4);
  const char* names[] = {"x", "y", "z", "intensity"};
  for (std::size_t i = 0; i < 4; ++i) {
    CHECK(c.fields[i].name == names[i]);
    CHECK(c.fields[i].offset == 4 * i);
    CHECK(c.fields[i].datatype == 7);
    CHECK(c.fields[i].count == 1);
  }
  CHECK_FALSE(c.is_bigendian);
  CHECK(c.point_step == 16);
  CHECK(c.row_step == 16 * 300);
  CHECK(c.is_dense);
  REQUIRE(c.data.size() == 16 * 300);
  int bad = 0;
  for (int j = 0; j < 300; ++j) {
    const auto o = static_cast<std::size_t>(16 * j);
    bad += f32_at(c.data, o) != static_cast<float>(k) + static_cast<float>(j) / 8.0F;
    bad += f32_at(c.data, o + 4) != -static_cast<float>(j) / 4.0F;
    bad += f32_at(c.data, o + 8) != static_cast<float>(j % 7) / 2.0F;
    bad += f32_at(c.data, o + 12) != static_cast<float>(j % 100);
  }
  CHECK(bad == 0);
}

void check_padded_cloud(const PointCloud2Msg& c, int k) {
  CAPTURE(k);
  CHECK(c.stamp_s == stamp(kBaseSec, k * 100000000LL + 50000000LL));
  CHECK(c.frame_id == "os_sensor");
  CHECK(c.height == 2);
  CHECK(c.width == 20);
  REQUIRE(c.fields.size() == 5);
  CHECK(c.fields[3].name == "intensity");
  CHECK(c.fields[3].offset == 16);
  CHECK(c.fields[4].name == "ring");
  CHECK(c.fields[4].offset == 20);
  CHECK(c.fields[4].datatype == 4);
  CHECK(c.point_step == 32);
  CHECK(c.row_step == 32 * 20 + 8);
  CHECK_FALSE(c.is_dense);
  REQUIRE(c.data.size() == 2 * (32 * 20 + 8));
  int bad = 0;
  for (std::size_t r = 0; r < 2; ++r) {
    const std::size_t row = r * (32 * 20 + 8);
    for (std::size_t i = 0; i < 8; ++i) bad += c.data[row + 32 * 20 + i] != 0xCD;  // row padding
    for (std::size_t col = 0; col < 20; ++col) {
      const std::size_t o = row + 32 * col;
      bad += f32_at(c.data, o) != static_cast<float>(r) + static_cast<float>(col) / 4.0F;
      bad += f32_at(c.data, o + 4) != static_cast<float>(col) / 2.0F;
      bad += f32_at(c.data, o + 8) != -static_cast<float>(r);
      bad += f32_at(c.data, o + 16) != static_cast<float>(col);
      std::uint16_t ring = 0;
      std::memcpy(&ring, c.data.data() + o + 20, 2);
      bad += ring != r;
      for (std::size_t p : {12U, 13U, 14U, 15U}) bad += c.data[o + p] != 0xAB;  // point padding
      for (std::size_t p = 22; p < 32; ++p) bad += c.data[o + p] != 0xAB;
    }
  }
  CHECK(bad == 0);
}

void check_small_imu(const ImuMsg& m, int i) {
  CAPTURE(i);
  const double d = i;
  CHECK(m.stamp_s == stamp(kBaseSec, i * 25000000LL));
  CHECK(m.frame_id == "imu");
  CHECK(m.orientation.x() == 0.0);
  CHECK(m.orientation.y() == 0.0);
  CHECK(m.orientation.z() == d / 16);
  CHECK(m.orientation.w() == 1 - d / 16);
  CHECK(m.angular_velocity_radps == Eigen::Vector3d(d / 8, -d / 4, 0.5));
  CHECK(m.linear_acceleration_mps2 == Eigen::Vector3d(d / 2, 0.25, 9.75));
  for (std::size_t r = 0; r < 9; ++r) {
    const double dr = static_cast<double>(r);
    CHECK(m.orientation_covariance[r] == d + dr / 4);
    CHECK(m.angular_velocity_covariance[r] == dr / 2);
    CHECK(m.linear_acceleration_covariance[r] == -dr);
  }
}

/// Reads a whole small file and checks every message against the formulas;
/// returns the messages.
std::vector<BagMessage> check_small_file(const std::string& name, bool padded) {
  CAPTURE(name);
  McapReader reader(bag(name));
  const std::vector<BagTopic>& topics = reader.topics();
  REQUIRE(topics.size() == (padded ? 3U : 2U));
  const std::size_t points = topic_index(topics, "/points");
  const std::size_t imu = topic_index(topics, "/imu");
  CHECK(topics[points].type == "sensor_msgs/msg/PointCloud2");
  CHECK(topics[imu].type == "sensor_msgs/msg/Imu");
  CHECK(topics[points].encoding == MessageEncoding::kCdr);
  CHECK(topics[imu].encoding == MessageEncoding::kCdr);
  CHECK(topics[points].message_count == 3);
  CHECK(topics[imu].message_count == 10);
  const std::size_t padded_topic = padded ? topic_index(topics, "/padded/points") : topics.size();
  if (padded) CHECK(topics[padded_topic].message_count == 3);

  const std::vector<BagMessage> all = read_all(reader);
  REQUIRE(all.size() == (padded ? 16U : 13U));
  int clouds = 0;
  int imus = 0;
  int paddeds = 0;
  std::int64_t last = 0;
  for (const BagMessage& m : all) {
    CHECK(m.log_time_ns >= last);
    last = m.log_time_ns;
    if (m.topic == points) {
      const PointCloud2Msg c = parse_cdr_pointcloud2(m.data);
      check_small_cloud(c, clouds++);
      CHECK(m.log_time_ns == kBaseSec * 1000000000LL + (clouds - 1) * 100000000LL);  // log time = header stamp
    } else if (m.topic == imu) {
      check_small_imu(parse_cdr_imu(m.data), imus++);
    } else {
      REQUIRE(m.topic == padded_topic);
      check_padded_cloud(parse_cdr_pointcloud2(m.data), paddeds++);
    }
  }
  CHECK(clouds == 3);
  CHECK(imus == 10);
  CHECK(paddeds == (padded ? 3 : 0));
  return all;
}

// ---- KITTI: the PCD payload and the OXTS text lines

/// The binary payload of a PCD file written with x y z intensity float32 (16 bytes a point).
std::vector<std::uint8_t> pcd_payload(const std::string& path, std::size_t& points) {
  const std::string bytes = semlio_test::read_bytes(path);
  const std::size_t width_at = bytes.find("\nWIDTH ");
  const std::size_t data_at = bytes.find("DATA binary\n");
  REQUIRE(width_at != std::string::npos);
  REQUIRE(data_at != std::string::npos);
  points = std::stoul(bytes.substr(width_at + 7, 12));
  const std::size_t begin = data_at + 12;
  REQUIRE(bytes.size() >= begin + 16 * points);
  return {bytes.begin() + static_cast<std::ptrdiff_t>(begin),
          bytes.begin() + static_cast<std::ptrdiff_t>(begin + 16 * points)};
}

std::vector<std::vector<double>> oxts_lines() {
  std::ifstream in(bag("kitti3_oxts.txt"));  // OXTS lines 0-29, verbatim (README.md)
  std::vector<std::vector<double>> lines;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::vector<double> v;
    std::string tok;
    while (ss >> tok) v.push_back(std::strtod(tok.c_str(), nullptr));
    lines.push_back(v);
  }
  return lines;
}

/// Copy of a fixture with `edit` applied, in a temporary directory.
struct DamagedCopy {
  semlio_test::CloudTempDir dir{"mcap"};
  std::string path;
  std::string bytes;
  explicit DamagedCopy(const std::string& name) : bytes(semlio_test::read_bytes(bag(name))) { REQUIRE(!bytes.empty()); }
  std::string write() { return path = dir.write("damaged.mcap", bytes); }
};

/// Opens and reads a whole file; true when it went through, false on a
/// semlio::Error (any other exception escapes and fails the test).
bool reads_or_typed_error(const std::string& path, std::size_t* messages = nullptr) {
  try {
    McapReader reader(path);
    const std::size_t n = read_all(reader).size();
    if (messages != nullptr) *messages = n;
    for (const BagMessage& m : read_all(reader)) (void)m;
    return true;
  } catch (const semlio::Error&) {
    return false;
  }
}

}  // namespace

TEST_CASE("MCAP KITTI: topics and counts from the summary", "[io][bags][mcap]") {
  McapReader reader(bag("kitti3_zstd.mcap"));
  const std::vector<BagTopic>& topics = reader.topics();
  REQUIRE(topics.size() == 2);
  const BagTopic& velo = topics[topic_index(topics, "/kitti/velo/pointcloud")];
  const BagTopic& imu = topics[topic_index(topics, "/kitti/oxts/imu")];
  CHECK(velo.type == "sensor_msgs/msg/PointCloud2");
  CHECK(imu.type == "sensor_msgs/msg/Imu");
  CHECK(semlio::io::is_pointcloud2_type(velo.type));
  CHECK(semlio::io::is_imu_type(imu.type));
  CHECK(velo.encoding == MessageEncoding::kCdr);
  CHECK(velo.message_count == 3);
  CHECK(imu.message_count == 30);
}

TEST_CASE("MCAP KITTI: the three real scans decode to the PCD files' exact bytes", "[io][bags][mcap]") {
  McapReader reader(bag("kitti3_zstd.mcap"));
  const std::size_t velo = topic_index(reader.topics(), "/kitti/velo/pointcloud");
  reader.select({"/kitti/velo/pointcloud"});
  BagMessage m;
  PointCloud2Msg cloud;
  for (int i = 0; i < 3; ++i) {
    CAPTURE(i);
    REQUIRE(reader.next(m));
    CHECK(m.topic == velo);
    CHECK(m.log_time_ns == 1317357625LL * 1000000000LL + i * 100000000LL);
    parse_cdr_pointcloud2(m.data.data(), m.data.size(), cloud);
    const std::string pcd = data_path("kitti_raw/snippet_22/000000000" + std::to_string(i) + ".pcd");
    std::size_t n = 0;
    const std::vector<std::uint8_t> payload = pcd_payload(pcd, n);
    CHECK(n > 100000);
    CHECK(cloud.stamp_s == stamp(1317357625, i * 100000000LL));
    CHECK(cloud.frame_id == "velo_link");
    CHECK(cloud.height == 1);
    CHECK(cloud.width == n);
    CHECK(cloud.point_step == 16);
    CHECK(cloud.row_step == 16 * n);
    REQUIRE(cloud.fields.size() == 4);
    CHECK(cloud.fields[3].name == "intensity");
    CHECK(cloud.fields[3].offset == 12);
    CHECK(cloud.fields[3].datatype == 7);
    CHECK(cloud.data == payload);  // bit-exact, in file order

    // ...and the same floats semlio's own PCD reader returns (it drops (0,0,0) points).
    const semlio::Scan scan = semlio::io::read_pcd(pcd);
    REQUIRE(scan.has_intensity());
    std::size_t k = 0;
    int mismatches = 0;
    for (std::size_t j = 0; j < n; ++j) {
      float p[4];
      std::memcpy(p, cloud.data.data() + 16 * j, 16);
      if (p[0] == 0.0F && p[1] == 0.0F && p[2] == 0.0F) continue;
      if (k >= scan.size()) break;  // counted below: k must end at scan.size() with every point seen
      mismatches += std::memcmp(p, scan.points[k].data(), 12) != 0;
      mismatches += std::memcmp(&p[3], &scan.intensity[k], 4) != 0;
      ++k;
    }
    CHECK(k == scan.size());
    CHECK(k + 1 == n);  // each KITTI raw scan holds exactly one (0,0,0) point (tests/data/kitti_raw/README.md)
    CHECK(mismatches == 0);

    // The whole path a ROS 2 user takes (MCAP -> CDR -> Scan) gives the PCD reader's scan bit for bit.
    const semlio::Scan from_bag = semlio::io::pointcloud2_to_scan(cloud);
    REQUIRE(from_bag.size() == scan.size());
    REQUIRE(from_bag.has_intensity());
    CHECK(std::memcmp(from_bag.points.data(), scan.points.data(), scan.size() * sizeof(semlio::Point3f)) == 0);
    CHECK(std::memcmp(from_bag.intensity.data(), scan.intensity.data(), scan.size() * sizeof(float)) == 0);
    CHECK(from_bag.stamp_s == cloud.stamp_s);
  }
  CHECK_FALSE(reader.next(m));
}

TEST_CASE("MCAP KITTI: real OXTS IMU values, and log-time order with the IMU first at a tie", "[io][bags][mcap]") {
  const std::vector<std::vector<double>> oxts = oxts_lines();
  REQUIRE(oxts.size() == 30);
  McapReader reader(bag("kitti3_zstd.mcap"));
  const std::size_t imu_topic = topic_index(reader.topics(), "/kitti/oxts/imu");
  const std::size_t velo = topic_index(reader.topics(), "/kitti/velo/pointcloud");
  std::vector<std::size_t> order;
  std::int64_t last = 0;
  BagMessage m;
  int k = 0;
  while (reader.next(m)) {
    CHECK(m.log_time_ns >= last);
    last = m.log_time_ns;
    order.push_back(m.topic);
    if (m.topic != imu_topic) continue;
    CAPTURE(k);
    const ImuMsg imu = parse_cdr_imu(m.data);
    const std::vector<double>& v = oxts[static_cast<std::size_t>(k)];
    REQUIRE(v.size() == 30);
    CHECK(imu.stamp_s == stamp(1317357624 + k / 10, (k % 10) * 100000000LL));
    CHECK(imu.frame_id == "imu_link");
    CHECK(imu.linear_acceleration_mps2 == Eigen::Vector3d(v[14], v[15], v[16]));  // af al au
    CHECK(imu.angular_velocity_radps == Eigen::Vector3d(v[20], v[21], v[22]));    // wf wl wu
    // Orientation: R = Rz(yaw) Ry(pitch) Rx(roll), up to rounding of sin/cos.
    const Eigen::Quaterniond q = Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX());
    CHECK(std::abs(imu.orientation.dot(q)) == Approx(1.0).margin(1e-12));
    CHECK(imu.orientation_covariance[0] == 0.0);
    ++k;
  }
  CHECK(k == 30);
  REQUIRE(order.size() == 33);
  // IMU k = 10 and cloud 0 share 1317357625.000; the file has the IMU first (ties in file order).
  CHECK(order[10] == imu_topic);
  CHECK(order[11] == velo);
}

TEST_CASE("MCAP small files: every chunk kind gives the same messages", "[io][bags][mcap]") {
  const std::vector<BagMessage> lz4 = check_small_file("small_lz4.mcap", false);
  const std::vector<BagMessage> unchunked = check_small_file("small_unchunked.mcap", false);
  const std::vector<BagMessage> streamed = check_small_file("small_streamed.mcap", false);
  const std::vector<BagMessage> bigendian = check_small_file("small_bigendian.mcap", false);
  const std::vector<BagMessage> none = check_small_file("small_none.mcap", true);
  // Same messages in the same order, same bytes (big-endian CDR excepted).
  REQUIRE(lz4.size() == unchunked.size());
  REQUIRE(lz4.size() == streamed.size());
  for (std::size_t i = 0; i < lz4.size(); ++i) {
    CAPTURE(i);
    CHECK(lz4[i].log_time_ns == unchunked[i].log_time_ns);
    CHECK(lz4[i].data == unchunked[i].data);
    CHECK(lz4[i].data == streamed[i].data);
    CHECK(lz4[i].log_time_ns == bigendian[i].log_time_ns);
    CHECK(lz4[i].data.size() == bigendian[i].data.size());
    CHECK(bigendian[i].data[1] == 0x00);  // encapsulation: big-endian CDR
    CHECK(lz4[i].data[1] == 0x01);
  }
}

TEST_CASE("MCAP small files: the fixtures exercise the paths they are meant to", "[io][bags][mcap]") {
  // Footer.summary_start (29 + 8 bytes from the end) is 0 only in the streamed file.
  const auto summary_start = [](const std::string& name) {
    const std::string b = semlio_test::read_bytes(bag(name));
    REQUIRE(b.size() > 37);
    std::uint64_t v = 0;
    std::memcpy(&v, b.data() + b.size() - 37 + 9, 8);
    return v;
  };
  CHECK(summary_start("small_streamed.mcap") == 0);
  CHECK(summary_start("small_lz4.mcap") != 0);
  CHECK(summary_start("kitti3_zstd.mcap") != 0);
  // small_lz4 was written clouds first, then IMU: the file order is not the time order.
  const std::string b = semlio_test::read_bytes(bag("small_lz4.mcap"));
  CHECK(b.find("lz4") != std::string::npos);
  McapReader reader(bag("small_lz4.mcap"));
  const std::size_t imu = topic_index(reader.topics(), "/imu");
  std::vector<std::size_t> order;
  BagMessage m;
  while (reader.next(m)) order.push_back(m.topic);
  REQUIRE(order.size() == 13);
  // t = 0: cloud 0 (written first) then IMU 0; then IMU 1..3 (25-75 ms) before cloud 1 (100 ms).
  CHECK(order[0] != imu);
  CHECK(order[1] == imu);
  CHECK(order[2] == imu);
  CHECK(order[4] == imu);
  CHECK(order[5] != imu);
}

TEST_CASE("MCAP profile ros1: ROS 1 serialised messages are topics of encoding kRos1", "[io][bags][mcap]") {
  McapReader reader(bag("small_ros1.mcap"));
  const std::vector<BagTopic>& topics = reader.topics();
  REQUIRE(topics.size() == 2);
  const std::size_t points = topic_index(topics, "/points");
  const std::size_t imu = topic_index(topics, "/imu");
  CHECK(topics[points].type == "sensor_msgs/PointCloud2");
  CHECK(topics[imu].type == "sensor_msgs/Imu");
  CHECK(topics[points].encoding == MessageEncoding::kRos1);
  CHECK(topics[imu].encoding == MessageEncoding::kRos1);
  CHECK(topics[imu].message_count == 10);
  int clouds = 0;
  int imus = 0;
  BagMessage m;
  while (reader.next(m)) {
    if (m.topic == points) {
      check_small_cloud(semlio::io::parse_ros1_pointcloud2(m.data), clouds++);
    } else {
      check_small_imu(semlio::io::parse_ros1_imu(m.data), imus++);
    }
  }
  CHECK(clouds == 3);
  CHECK(imus == 10);
}

TEST_CASE("MCAP select: a subset, all again, and unknown names", "[io][bags][mcap]") {
  McapReader reader(bag("small_none.mcap"));
  const std::size_t imu = topic_index(reader.topics(), "/imu");
  reader.select({"/imu"});
  std::vector<BagMessage> only = read_all(reader);
  REQUIRE(only.size() == 10);
  for (const BagMessage& m : only) CHECK(m.topic == imu);
  reader.select({"/imu", "/padded/points"});
  CHECK(read_all(reader).size() == 13);
  reader.select({});
  CHECK(read_all(reader).size() == 16);
  CHECK_THROWS_AS(reader.select({"/nope"}), semlio::ValueError);
  // The streamed file (channels known only from a scan) selects the same way.
  McapReader streamed(bag("small_streamed.mcap"));
  streamed.select({"/points"});
  CHECK(read_all(streamed).size() == 3);
}

TEST_CASE("MCAP: CRC-32 of a known string", "[io][bags][mcap]") {
  const std::string s = "123456789";
  CHECK(semlio::io::detail::mcap::crc32(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()) == 0xCBF43926U);
  const std::string longer = "The quick brown fox jumps over the lazy dog";
  CHECK(semlio::io::detail::mcap::crc32(reinterpret_cast<const std::uint8_t*>(longer.data()), longer.size()) ==
        0x414FA339U);
  // The sliced tables against the bit-at-a-time definition, for every length
  // 0-100 (every tail after the 16-byte blocks) and a few long buffers.
  const auto bitwise = [](const std::vector<std::uint8_t>& b) {
    std::uint32_t c = 0xFFFFFFFFU;
    for (const std::uint8_t byte : b) {
      c ^= byte;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320U & (0U - (c & 1U)));
    }
    return ~c;
  };
  std::mt19937 rng(3);
  int mismatches = 0;
  for (std::size_t n : {std::size_t{1000}, std::size_t{4096 + 7}, std::size_t{65536 + 13}}) {
    std::vector<std::uint8_t> b(n);
    for (std::uint8_t& v : b) v = static_cast<std::uint8_t>(rng());
    mismatches += semlio::io::detail::mcap::crc32(b.data(), b.size()) != bitwise(b);
  }
  for (std::size_t n = 0; n <= 100; ++n) {
    std::vector<std::uint8_t> b(n);
    for (std::uint8_t& v : b) v = static_cast<std::uint8_t>(rng());
    mismatches += semlio::io::detail::mcap::crc32(b.data(), b.size()) != bitwise(b);
  }
  CHECK(mismatches == 0);
}

TEST_CASE("MCAP: the CRC-32 of every committed fixture's chunks equals the CRC its writer stored", "[io][bags][mcap]") {
  // Walks each file's data section by hand, decompresses each Chunk and
  // compares crc32() (the PCLMUL path where the CPU has it) and the sliced
  // tables with the stored uncompressed_crc.
  namespace d = semlio::io::detail;
  int chunks = 0;
  int kitti_chunks = 0;
  for (const char* name : {"kitti3_zstd.mcap", "small_lz4.mcap", "small_none.mcap", "small_bigendian.mcap",
                           "small_ros1.mcap", "small_streamed.mcap"}) {
    CAPTURE(name);
    const std::string b = semlio_test::read_bytes(bag(name));
    const auto at = [&](std::size_t off, auto v) {
      REQUIRE(off + sizeof(v) <= b.size());
      std::memcpy(&v, b.data() + off, sizeof(v));
      return v;
    };
    for (std::size_t off = 8; off + 9 <= b.size();) {
      const auto op = static_cast<std::uint8_t>(b[off]);
      const std::uint64_t len = at(off + 1, std::uint64_t{});
      if (op == 0x0F || op == 0x02) break;  // DataEnd, Footer
      if (op == 0x06) {
        std::size_t c = off + 9 + 16;
        const std::uint64_t uncompressed_size = at(c, std::uint64_t{});
        const std::uint32_t stored = at(c + 8, std::uint32_t{});
        const std::uint32_t comp_len = at(c + 12, std::uint32_t{});
        const std::string compression = b.substr(c + 16, comp_len);
        c += 16 + comp_len;
        const std::uint64_t n = at(c, std::uint64_t{});
        REQUIRE(c + 8 + n <= b.size());
        const auto* in = reinterpret_cast<const std::uint8_t*>(b.data() + c + 8);
        std::vector<std::uint8_t> records;
        if (compression == "zstd") {
          d::decompress_zstd(in, n, uncompressed_size, records, name);
        } else if (compression == "lz4") {
          d::decompress_lz4_frame(in, n, uncompressed_size, records, name);
        } else {
          records.assign(in, in + n);
        }
        CHECK(stored != 0U);
        CHECK(d::mcap::crc32(records.data(), records.size()) == stored);
        CHECK((d::mcap::crc32_update_sliced(0xFFFFFFFFU, records.data(), records.size()) ^ 0xFFFFFFFFU) == stored);
        ++chunks;
        kitti_chunks += std::string(name) == "kitti3_zstd.mcap";
      }
      off += 9 + len;
    }
  }
  CHECK(kitti_chunks == 4);
  CHECK(chunks > kitti_chunks);
}

TEST_CASE("MCAP: a damaged chunk fails its CRC unless the check is off", "[io][bags][mcap]") {
  DamagedCopy copy("small_none.mcap");
  // The uncompressed chunks hold the padded clouds' 0xCD row padding verbatim: damage one byte of it.
  const std::size_t at = copy.bytes.find(std::string(8, '\xCD'));
  REQUIRE(at != std::string::npos);
  copy.bytes[at] = '\x00';
  const std::string path = copy.write();
  McapReader reader(path);
  CHECK_THROWS_AS(read_all(reader), semlio::FormatError);
  McapReader unchecked(path, {.verify_chunk_crc = false});
  CHECK(read_all(unchecked).size() == 16);
}

TEST_CASE("MCAP: a chunk index that states a later start time than its chunk holds is a FormatError", "[io][bags][mcap]") {
  DamagedCopy copy("small_lz4.mcap");
  const std::string& b = copy.bytes;
  // Walk the summary section (Footer.summary_start .. Footer.summary_offset_start).
  std::uint64_t begin = 0;
  std::uint64_t end = 0;
  std::memcpy(&begin, b.data() + b.size() - 37 + 9, 8);
  std::memcpy(&end, b.data() + b.size() - 37 + 17, 8);
  REQUIRE(begin > 0);
  REQUIRE(end > begin);
  REQUIRE(end <= b.size());
  std::vector<std::size_t> chunk_indexes;  // offsets of ChunkIndex contents
  for (std::uint64_t off = begin; off < end;) {
    std::uint64_t len = 0;
    std::memcpy(&len, b.data() + off + 1, 8);
    if (static_cast<unsigned char>(b[off]) == 0x08) chunk_indexes.push_back(static_cast<std::size_t>(off + 9));
    off += 9 + len;
  }
  REQUIRE(chunk_indexes.size() >= 3);
  // The first chunk (cloud 0 at t = 0) claims to start after every message of the file.
  const std::uint64_t late = (kBaseSec + 10) * 1000000000ULL;
  std::memcpy(copy.bytes.data() + chunk_indexes.front(), &late, 8);
  McapReader reader(copy.write());
  CHECK_THROWS_AS(read_all(reader), semlio::FormatError);
}

TEST_CASE("MCAP: a rosbag2 folder with one .mcap file opens, one with two does not", "[io][bags][mcap]") {
  semlio_test::CloudTempDir dir("mcap_folder");
  const std::filesystem::path folder = dir.file("bag");
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "metadata.yaml") << "rosbag2_bagfile_information:\n  storage_identifier: mcap\n";
  CHECK_THROWS_AS(McapReader(folder.string()), semlio::IoError);
  std::filesystem::copy_file(bag("small_lz4.mcap"), folder / "bag_0.mcap");
  McapReader reader(folder.string());
  CHECK(read_all(reader).size() == 13);
  std::filesystem::copy_file(bag("small_lz4.mcap"), folder / "bag_1.mcap");
  CHECK_THROWS_AS(McapReader(folder.string()), semlio::FormatError);
}

TEST_CASE("MCAP: not an MCAP file, a missing file, truncated and damaged files give typed errors", "[io][bags][mcap]") {
  CHECK_THROWS_AS(McapReader(bag("does_not_exist.mcap")), semlio::IoError);
  CHECK_THROWS_AS(McapReader(data_path("kitti_raw/snippet_22/0000000000.pcd")), semlio::FormatError);

  SECTION("every truncation of the streamed and the indexed file") {
    for (const std::string name : {"small_streamed.mcap", "small_lz4.mcap"}) {
      const std::string full = semlio_test::read_bytes(bag(name));
      semlio_test::CloudTempDir dir("mcap_cut");
      int errors = 0;
      int complete = 0;
      for (std::size_t n = 0; n < full.size(); n += 13) {
        const std::string path = dir.write("cut.mcap", full.substr(0, n));
        std::size_t messages = 0;
        if (!reads_or_typed_error(path, &messages)) {
          ++errors;
        } else if (messages == 13) {
          ++complete;
        }
      }
      CAPTURE(name);
      CHECK(errors > 0);
      // A cut inside the summary leaves the data section whole: the scan still finds every message.
      CHECK(complete > 0);
    }
  }
  SECTION("random byte damage") {
    std::mt19937 rng(11);
    for (const std::string name : {"small_streamed.mcap", "small_lz4.mcap", "small_none.mcap"}) {
      const std::string full = semlio_test::read_bytes(bag(name));
      semlio_test::CloudTempDir dir("mcap_fuzz");
      int errors = 0;
      for (int trial = 0; trial < 150; ++trial) {
        std::string b = full;
        for (int f = 0; f < 1 + trial % 3; ++f) {
          b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng)] =
              static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
        }
        errors += reads_or_typed_error(dir.write("fuzz.mcap", b)) ? 0 : 1;
      }
      CAPTURE(name);
      CHECK(errors > 0);
    }
  }
  SECTION("a record length pointing past the end") {
    DamagedCopy copy("small_streamed.mcap");
    // The Header record starts right after the 8-byte magic; its length is bytes 9..16.
    const std::uint64_t huge = ~std::uint64_t{0} - 4;
    std::memcpy(copy.bytes.data() + 9, &huge, 8);
    try {
      McapReader reader(copy.write());
      FAIL("no exception");
    } catch (const semlio::FormatError& e) {
      CHECK(std::string(e.what()).find("damaged.mcap") != std::string::npos);
    }
  }
}

TEST_CASE("MCAP: from_bytes reads a file held in memory like its path, errors name the given name",
          "[io][bags][mcap]") {
  for (const char* rel : {"bags/kitti3_zstd.mcap", "bags/small_lz4.mcap", "bags/small_unchunked.mcap"}) {
    INFO(rel);
    const std::string path = data_path(rel);
    McapReader by_path(path);
    McapReader in_memory = McapReader::from_bytes(semlio_test::read_bytes(path), "mem");
    CHECK(semlio_test::check_same_bag(by_path, in_memory) >= 5);
  }
  CHECK_THROWS_WITH(McapReader::from_bytes("not a bag at all, just text", "mem_name"), Catch::Contains("mem_name"));
  CHECK_THROWS_AS(McapReader::from_bytes("", "mem_name"), semlio::FormatError);
}

}  // namespace test_mcap
