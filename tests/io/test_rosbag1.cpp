// ROS 1 bag reader on bags written by the reference implementation (Debian's
// python3-rosbag, scripts/make_bag_fixtures.py): the real KITTI scans
// bit-exact against their PCD files, real OXTS IMU values against their text
// lines, synthetic driver layouts against the script's formulas, log-time
// order of messages written out of order, bz2/lz4/uncompressed chunks, a bag
// whose index was cut off, bags of semlio's own writer, and damaged copies that
// must fail with typed errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <lz4frame.h>

#include <semlio/io/bag/ros_writer_msgs.hpp>
#include <semlio/io/bag/rosbag1.hpp>
#include <semlio/io/bag/rosbag1_writer.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/ros1_msgs.hpp>
#include <semlio_test/bag_compare.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_cloud_files.hpp>

namespace test_rosbag1 {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::Scan;
using semlio::io::BagMessage;
using semlio::io::BagTopic;
using semlio::io::ImuMsg;
using semlio::io::PointCloud2Layout;
using semlio::io::PointCloud2Msg;
using semlio::io::ReadStats;
using semlio::io::RosBag1Reader;
using semlio::io::parse_ros1_imu;
using semlio::io::parse_ros1_pointcloud2;
using semlio::io::pointcloud2_to_scan;
using semlio_test::data_path;

std::string bag(const std::string& name) { return data_path("bags/" + name); }

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  REQUIRE(in);
  std::string bytes(static_cast<std::size_t>(in.tellg()), '\0');
  in.seekg(0);
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return bytes;
}

/// Index of a topic by name (fails the test when absent).
std::size_t topic_index(const RosBag1Reader& r, const std::string& name) {
  for (std::size_t i = 0; i < r.topics().size(); ++i) {
    if (r.topics()[i].name == name) return i;
  }
  FAIL("no topic " << name);
  return 0;
}

/// (log time, topic) of every message, in the order next() returns them.
std::vector<std::pair<std::int64_t, std::string>> read_order(RosBag1Reader& r) {
  std::vector<std::pair<std::int64_t, std::string>> out;
  BagMessage m;
  while (r.next(m)) out.emplace_back(m.log_time_ns, r.topics().at(m.topic).name);
  return out;
}

/// quirks_expected.txt: "log_time_ns topic" lines written by the fixture script.
std::vector<std::pair<std::int64_t, std::string>> expected_order() {
  std::ifstream in(bag("quirks_expected.txt"));
  std::vector<std::pair<std::int64_t, std::string>> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::int64_t t = 0;
    std::string topic;
    ls >> t >> topic;
    out.emplace_back(t, topic);
  }
  return out;
}

// The fixture script's formulas (scripts/make_bag_fixtures.py, tests/data/bags/README.md).
constexpr std::uint32_t kBaseSec = 1700000000;
double header_stamp_s(int k) { return static_cast<double>(kBaseSec) + static_cast<double>(k * 100000000) / 1e9; }
float fx(std::size_t j) { return 1.0F + 0.25F * static_cast<float>(j); }
std::size_t index_of(float x) { return static_cast<std::size_t>(std::lround((x - 1.0F) / 0.25F)); }

/// Checks one decoded quirk cloud of `topic` against the formulas; returns its k.
int check_quirk_cloud(const std::string& topic, const PointCloud2Msg& msg, const Scan& s, const PointCloud2Layout& layout,
                      const ReadStats& stats) {
  INFO("topic " << topic << ", header stamp " << msg.stamp_s);
  REQUIRE(!s.empty());
  s.validate();
  // k from point 0's y = -0.5 j + k with j = 0 (point 0 is never dropped).
  REQUIRE(index_of(s.points[0].x()) == 0);
  const int k = static_cast<int>(std::lround(s.points[0].y()));
  const bool ouster = topic == "/ouster/points";
  const bool livox = topic == "/livox/lidar";
  std::size_t expect_nan = 0, expect_zero = 0;
  const std::size_t width = msg.width * msg.height;
  if (ouster || livox) {
    for (std::size_t j = 0; j < width; ++j) {
      if (j % 17 == 5) {
        ++expect_nan;
      } else if (j % 23 == 7) {
        ++expect_zero;
      }
    }
  }
  CHECK(stats.dropped_nonfinite == expect_nan);
  CHECK(stats.dropped_zero == expect_zero);
  CHECK(s.size() == width - expect_nan - expect_zero);
  REQUIRE(s.has_intensity());
  REQUIRE(s.has_times());
  CHECK(s.has_rings() == !livox);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::size_t j = index_of(s.points[i].x());
    INFO("kept point " << i << " = point " << j);
    const auto jf = static_cast<float>(j);
    CHECK(s.points[i].x() == fx(j));
    CHECK(s.points[i].y() == -0.5F * jf + static_cast<float>(k));
    CHECK(s.points[i].z() == 0.125F * static_cast<float>(j % 64) - 2.0F);
    CHECK(s.intensity[i] == static_cast<float>(j % 256));
    if (s.has_rings()) CHECK(s.rings[i] == (ouster ? j / 40 : j % 16));
    // float64 absolute seconds carry ~2.4e-7 s of rounding at epoch magnitude.
    CHECK(s.times_s[i] == Approx(static_cast<double>(j) * 1e-5).margin(5e-7));
  }
  // Sweep start = the earliest point (j = 0) in every layout.
  if (topic == "/velodyne_points") {
    CHECK(s.stamp_s == header_stamp_s(k) + static_cast<double>(static_cast<float>(-160 * 1e-5)));
  } else if (topic == "/hesai/pandar") {
    CHECK(s.stamp_s == header_stamp_s(k));  // absolute float64: the first point's value, exactly
    CHECK(layout.header_minus_earliest_s == Approx(0.1).margin(1e-6));
  } else {
    CHECK(s.stamp_s == Approx(header_stamp_s(k)).epsilon(0).margin(1e-6));
  }
  return k;
}

}  // namespace

TEST_CASE("rosbag1: the KITTI lz4 bag holds the three PCD scans bit-exactly and the real OXTS IMU",
          "[io][rosbag1]") {
  RosBag1Reader reader(bag("kitti3_lz4.bag"));
  CHECK_FALSE(reader.reindexed());
  REQUIRE(reader.topics().size() == 2);
  const std::size_t velo = topic_index(reader, "/kitti/velo/pointcloud");
  const std::size_t imu = topic_index(reader, "/kitti/oxts/imu");
  CHECK(reader.topics()[velo].type == "sensor_msgs/PointCloud2");
  CHECK(reader.topics()[velo].message_count == 3);
  CHECK(reader.topics()[imu].type == "sensor_msgs/Imu");
  CHECK(reader.topics()[imu].message_count == 30);
  CHECK(reader.topics()[imu].encoding == semlio::io::MessageEncoding::kRos1);

  reader.select({"/kitti/velo/pointcloud"});
  BagMessage m;
  PointCloud2Msg cloud;
  for (int i = 0; i < 3; ++i) {
    REQUIRE(reader.next(m));
    CHECK(m.topic == velo);
    CHECK(m.log_time_ns == 1317357625LL * 1000000000 + i * 100000000LL);
    parse_ros1_pointcloud2(m.data.data(), m.data.size(), cloud);
    CHECK(cloud.frame_id == "velo_link");
    CHECK(cloud.stamp_s == 1317357625.0 + static_cast<double>(i * 100000000) / 1e9);
    CHECK(cloud.point_step == 16);
    ReadStats stats;
    const Scan s = pointcloud2_to_scan(cloud, {}, nullptr, &stats);
    ReadStats pcd_stats;
    const Scan ref = semlio::io::read_pcd(data_path("kitti_raw/snippet_22/" + std::string("000000000") +
                                                    std::to_string(i) + ".pcd"),
                                          &pcd_stats);
    REQUIRE(s.size() == ref.size());
    REQUIRE(s.size() > 100000);
    CHECK(std::memcmp(s.points.data(), ref.points.data(), s.size() * sizeof(semlio::Point3f)) == 0);
    CHECK(std::memcmp(s.intensity.data(), ref.intensity.data(), s.size() * sizeof(float)) == 0);
    CHECK(stats.dropped_zero == 1);  // each KITTI raw scan holds one (0,0,0) point (kitti_raw/README.md)
    CHECK(stats.dropped() == pcd_stats.dropped());
    CHECK(s.stamp_s == cloud.stamp_s);  // no per-point time in KITTI: the header stamp
    Scan direct;  // decoded from the message bytes without the PointCloud2Msg copy
    semlio::io::ros1_pointcloud2_to_scan(m.data.data(), m.data.size(), direct);
    CHECK(direct.points == s.points);
    CHECK(direct.intensity == s.intensity);
  }
  CHECK_FALSE(reader.next(m));

  // IMU: the OXTS af al au / wf wl wu columns (14-16, 20-22) of each line.
  reader.select({"/kitti/oxts/imu"});
  std::ifstream oxts(bag("kitti3_oxts.txt"));
  double up_sum = 0.0;
  for (int k = 0; k < 30; ++k) {
    std::string line;
    REQUIRE(std::getline(oxts, line));
    std::istringstream ls(line);
    std::vector<double> v;
    double x = 0.0;
    while (ls >> x) v.push_back(x);
    REQUIRE(v.size() == 30);
    REQUIRE(reader.next(m));
    const ImuMsg msg = parse_ros1_imu(m.data);
    CHECK(msg.frame_id == "imu_link");
    CHECK(msg.stamp_s == Approx(1317357624.0 + 0.1 * k).epsilon(0).margin(1e-6));
    CHECK(msg.linear_acceleration_mps2 == Eigen::Vector3d(v[14], v[15], v[16]));
    CHECK(msg.angular_velocity_radps == Eigen::Vector3d(v[20], v[21], v[22]));
    CHECK(msg.orientation.norm() == Approx(1.0).epsilon(1e-12));
    up_sum += msg.linear_acceleration_mps2.z();
  }
  CHECK_FALSE(reader.next(m));
  // The upward axis carries gravity: its mean over 3 s of driving is near g.
  CHECK(up_sum / 30.0 == Approx(9.81).margin(0.2));
}

TEST_CASE("rosbag1: messages written out of time order come back in log-time order, ties in file order",
          "[io][rosbag1]") {
  const auto expected = expected_order();
  REQUIRE(expected.size() == 6 * 3 + 8 + 1);
  for (const char* name : {"quirks_none.bag", "quirks_bz2.bag", "quirks_lz4_unindexed.bag"}) {
    INFO(name);
    RosBag1Reader reader(bag(name));
    CHECK(reader.reindexed() == (std::string(name) == "quirks_lz4_unindexed.bag"));
    CHECK(reader.chunk_count() > 5);  // 8 KiB chunks: time order crosses chunks
    CHECK(reader.topics().size() == 7);
    const auto got = read_order(reader);
    CHECK(got == expected);
    // And again after select({}) restarts.
    reader.select({});
    CHECK(read_order(reader) == expected);
  }
}

TEST_CASE("rosbag1: every driver layout in the quirk bags decodes to the script's values", "[io][rosbag1]") {
  for (const char* name : {"quirks_none.bag", "quirks_bz2.bag", "quirks_lz4_unindexed.bag"}) {
    INFO(name);
    RosBag1Reader reader(bag(name));
    std::map<std::string, std::vector<int>> clouds;
    BagMessage m;
    PointCloud2Msg msg;
    while (reader.next(m)) {
      const BagTopic& t = reader.topics().at(m.topic);
      if (t.type != "sensor_msgs/PointCloud2") continue;
      parse_ros1_pointcloud2(m.data.data(), m.data.size(), msg);
      PointCloud2Layout layout;
      ReadStats stats;
      const Scan s = pointcloud2_to_scan(msg, {}, &layout, &stats);
      clouds[t.name].push_back(check_quirk_cloud(t.name, msg, s, layout, stats));
    }
    REQUIRE(clouds.size() == 6);
    for (const auto& [topic, ks] : clouds) {
      INFO(topic);
      if (topic == "/velodyne_points") {
        CHECK(ks == std::vector<int>{0, 3, 1, 2});  // the tie cloud (k = 3) is logged at IMU 2's time
      } else {
        CHECK(ks == std::vector<int>{0, 1, 2});
      }
    }
  }
}

TEST_CASE("rosbag1: select() filters topics and restarts, IMU values match the script", "[io][rosbag1]") {
  RosBag1Reader reader(bag("quirks_bz2.bag"));
  reader.select({"/imu/data"});
  BagMessage m;
  int i = 0;
  while (reader.next(m)) {
    const ImuMsg imu = parse_ros1_imu(m.data);
    CHECK(m.log_time_ns == 1700000000LL * 1000000000 + i * 50000000LL);
    CHECK(imu.stamp_s == static_cast<double>(kBaseSec) + static_cast<double>(i * 50000000) / 1e9);
    CHECK(imu.angular_velocity_radps == Eigen::Vector3d(0.01 * i, -0.02 * i, 0.03));
    CHECK(imu.linear_acceleration_mps2 == Eigen::Vector3d(0.1, 0.2 * i, 9.81));
    CHECK(imu.orientation.z() == std::sin(0.1 * i));
    CHECK(imu.orientation.w() == std::cos(0.1 * i));
    CHECK(imu.orientation_covariance[4] == 0.001 * 4);
    CHECK(imu.linear_acceleration_covariance[0] == -1.0);
    ++i;
  }
  CHECK(i == 8);
  CHECK(reader.topics()[m.topic].message_count == 8);
  reader.select({"/imu/data", "/livox/lidar"});
  CHECK(read_order(reader).size() == 8 + 3);
  CHECK_THROWS_AS(reader.select({"/no/such/topic"}), semlio::ValueError);
}

TEST_CASE("rosbag1: reads back what semlio's Rosbag1Writer writes, both driver layouts, out of log order",
          "[io][rosbag1]") {
  // The writer (io/bag/rosbag1_writer.hpp) is a second, independent ROS 1
  // implementation (its own serialisers); python3-rosbag checks it in
  // scripts/check_sim_bags.sh. Reader and writer must agree on every value.
  namespace io = semlio::io;
  const semlio_test::CloudTempDir dir("rosbag1_writer");
  const auto make_scan = [](int k) {
    Scan s;
    for (int j = 0; j < 300; ++j) {
      s.points.emplace_back(0.5F + 0.25F * static_cast<float>(j), static_cast<float>(k), -1.0F);
      s.intensity.push_back(static_cast<float>(j % 100));
      s.rings.push_back(static_cast<std::uint16_t>(j % 64));
      s.times_s.push_back(static_cast<float>(j) * 2e-4F);
    }
    s.stamp_s = 1600000000.0 + 0.1 * k;
    return s;
  };
  const std::string path = dir.file("written.bag");
  {
    io::Rosbag1Writer writer(path, {.chunk_bytes = 16 * 1024});
    const std::size_t velo = writer.add_topic("/velodyne_points", io::RosMessageType::kPointCloud2);
    const std::size_t ouster = writer.add_topic("/os_cloud_node/points", io::RosMessageType::kPointCloud2);
    const std::size_t imu = writer.add_topic("/imu", io::RosMessageType::kImu);
    for (int k : {3, 0, 4, 1, 2}) {  // log times go backwards in the file
      const Scan s = make_scan(k);
      const auto t = static_cast<std::int64_t>(1600000000) * 1000000000 + k * 100000000LL;
      writer.write(velo, t, io::scan_to_pointcloud2(s, {.layout = io::CloudLayout::kVelodyne}, "velodyne"));
      writer.write(ouster, t + 1, io::scan_to_pointcloud2(s, {.layout = io::CloudLayout::kOuster}, "os_sensor"));
    }
    for (int i = 0; i < 20; ++i) {
      ImuMsg m;
      m.stamp_s = 1600000000.0 + 0.025 * i;
      m.frame_id = "imu";
      m.angular_velocity_radps = Eigen::Vector3d(0.5 * i, 0.0, -1.0);
      writer.write(imu, static_cast<std::int64_t>(1600000000) * 1000000000 + i * 25000000LL, m);
    }
    writer.close();
  }
  RosBag1Reader reader(path);
  CHECK_FALSE(reader.reindexed());
  REQUIRE(reader.topics().size() == 3);
  CHECK(reader.topics()[topic_index(reader, "/imu")].message_count == 20);
  BagMessage m;
  std::int64_t last = 0;
  std::map<std::string, std::vector<int>> ks;
  int imus = 0;
  while (reader.next(m)) {
    CHECK(m.log_time_ns >= last);
    last = m.log_time_ns;
    const BagTopic& t = reader.topics().at(m.topic);
    if (t.type == "sensor_msgs/Imu") {
      const ImuMsg imu = parse_ros1_imu(m.data);
      CHECK(imu.angular_velocity_radps.x() == 0.5 * imus);
      ++imus;
      continue;
    }
    PointCloud2Layout layout;
    const Scan got = pointcloud2_to_scan(parse_ros1_pointcloud2(m.data), {}, &layout);
    const int k = static_cast<int>(got.points.at(0).y());
    ks[t.name].push_back(k);
    const Scan want = make_scan(k);
    INFO(t.name << " k " << k);
    CHECK(layout.time_field == (t.name == "/velodyne_points" ? "time" : "t"));
    CHECK(got.points == want.points);
    CHECK(got.intensity == want.intensity);
    CHECK(got.rings == want.rings);
    REQUIRE(got.times_s.size() == want.times_s.size());
    for (std::size_t j = 0; j < got.size(); ++j) CHECK(got.times_s[j] == Approx(want.times_s[j]).margin(1e-6));
    CHECK(got.stamp_s == Approx(want.stamp_s).epsilon(0).margin(1e-6));
  }
  CHECK(imus == 20);
  CHECK(ks["/velodyne_points"] == std::vector<int>{0, 1, 2, 3, 4});
  CHECK(ks["/os_cloud_node/points"] == std::vector<int>{0, 1, 2, 3, 4});
}

TEST_CASE("rosbag1: missing, foreign and hand-damaged files give typed errors", "[io][rosbag1]") {
  const semlio_test::CloudTempDir dir("rosbag1");
  CHECK_THROWS_AS(RosBag1Reader(dir.file("missing.bag")), semlio::IoError);
  CHECK_THROWS_WITH(RosBag1Reader(dir.write("text.bag", "hello, not a bag at all\n")), Catch::Contains("not a ROS bag"));
  CHECK_THROWS_WITH(RosBag1Reader(dir.write("old.bag", "#ROSBAG V1.2\nxxxxxxxxxxxxxx")), Catch::Contains("unsupported"));
  CHECK_THROWS_AS(RosBag1Reader(dir.write("empty.bag", "")), semlio::FormatError);

  const std::string good = read_file(bag("quirks_none.bag"));
  const std::size_t header_len_at = 13;  // after "#ROSBAG V2.0\n"
  SECTION("a bag header length beyond the file") {
    std::string b = good;
    const std::uint32_t huge = 0x00FFFFFF;
    std::memcpy(b.data() + header_len_at, &huge, 4);
    CHECK_THROWS_WITH(RosBag1Reader(dir.write("b.bag", b)), Catch::Contains("beyond the end"));
  }
  SECTION("an implausible bag header length") {
    std::string b = good;
    const std::uint32_t huge = 0xFFFFFFF0U;
    std::memcpy(b.data() + header_len_at, &huge, 4);
    CHECK_THROWS_WITH(RosBag1Reader(dir.write("b.bag", b)), Catch::Contains("not plausible"));
  }
  SECTION("a chunk whose stated size is a lie") {
    // The first chunk record follows the 4096-byte bag header record; its
    // header holds "size=" + uint32: state 2^31 + 1 bytes.
    std::string b = good;
    const std::size_t at = b.find("size=", 13 + 4096);
    REQUIRE(at != std::string::npos);
    const std::uint32_t lie = 0x80000001U;
    std::memcpy(b.data() + at + 5, &lie, 4);
    CHECK_THROWS_AS(RosBag1Reader(dir.write("b.bag", b)), semlio::FormatError);
  }
}

TEST_CASE("rosbag1: XXH32 of known strings and of liblz4's frames, and a wrong LZ4 content checksum is a FormatError",
          "[io][rosbag1]") {
  using semlio::io::detail::xxh32;
  const auto h = [](const std::string& s) { return xxh32(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()); };
  CHECK(h("") == 0x02CC5D05U);
  CHECK(h("a") == 0x550D7456U);
  CHECK(h("abc") == 0x32D153FFU);
  CHECK(h("Nobody inspects the spammish repetition") == 0xE2293B2FU);
  // liblz4 writes XXH32 of the content as the frame's last 4 bytes: every
  // tail length after the 16-byte stripes, and a multi-block frame.
  std::mt19937 rng(5);
  LZ4F_preferences_t prefs{};
  prefs.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;
  prefs.frameInfo.blockSizeID = LZ4F_max64KB;
  int mismatches = 0;
  std::vector<std::uint8_t> out;
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{15}, std::size_t{16}, std::size_t{17},
                              std::size_t{31}, std::size_t{100}, std::size_t{65536 * 3 + 5}}) {
    std::vector<std::uint8_t> data(n);
    for (std::uint8_t& v : data) v = static_cast<std::uint8_t>(rng() % 7);  // compressible
    std::vector<std::uint8_t> frame(LZ4F_compressFrameBound(n, &prefs));
    const std::size_t size = LZ4F_compressFrame(frame.data(), frame.size(), data.data(), n, &prefs);
    REQUIRE(LZ4F_isError(size) == 0U);
    frame.resize(size);
    std::uint32_t stated = 0;
    std::memcpy(&stated, frame.data() + size - 4, 4);
    mismatches += xxh32(data.data(), n) != stated;
    semlio::io::detail::decompress_lz4_frame(frame.data(), frame.size(), n, out, "test");
    mismatches += out != data;
    if (n > 0) {
      std::vector<std::uint8_t> bad = frame;
      bad[size - 1] ^= 0x01U;  // the stored checksum
      CHECK_THROWS_WITH(semlio::io::detail::decompress_lz4_frame(bad.data(), bad.size(), n, out, "test"),
                        Catch::Contains("checksum"));
    }
  }
  CHECK(mismatches == 0);
}

TEST_CASE("rosbag1: truncated and randomly damaged copies fail with semlio errors only", "[io][rosbag1]") {
  const semlio_test::CloudTempDir dir("rosbag1_fuzz");
  std::mt19937 rng(2024);
  std::size_t ok = 0, failed = 0;
  // Opens, reads every message and decodes every cloud and IMU message.
  const auto read_all = [&](const std::string& path) {
    try {
      RosBag1Reader reader(path);
      BagMessage m;
      PointCloud2Msg cloud;
      while (reader.next(m)) {
        const std::string& type = reader.topics().at(m.topic).type;
        if (type == "sensor_msgs/PointCloud2") {
          parse_ros1_pointcloud2(m.data.data(), m.data.size(), cloud);
          (void)pointcloud2_to_scan(cloud);
        } else if (type == "sensor_msgs/Imu") {
          (void)parse_ros1_imu(m.data);
        }
      }
      ++ok;
    } catch (const semlio::Error&) {
      ++failed;
    }
  };
  for (const char* name : {"quirks_none.bag", "quirks_bz2.bag", "quirks_lz4_unindexed.bag"}) {
    const std::string good = read_file(bag(name));
    // Truncations, from inside the bag header to just before the end.
    for (int trial = 0; trial < 40; ++trial) {
      const std::size_t n = rng() % good.size();
      read_all(dir.write("t.bag", good.substr(0, n)));
    }
    // 1-8 random bytes overwritten anywhere.
    for (int trial = 0; trial < 60; ++trial) {
      std::string b = good;
      const unsigned flips = 1 + static_cast<unsigned>(rng() % 8);
      for (unsigned f = 0; f < flips; ++f) b[rng() % b.size()] = static_cast<char>(rng());
      read_all(dir.write("f.bag", b));
    }
  }
  // Both outcomes occur (a flip inside float data is harmless; one in a length is not).
  CHECK(ok > 10);
  CHECK(failed > 10);
}

TEST_CASE("rosbag1: from_bytes reads a file held in memory like its path, errors name the given name",
          "[io][rosbag1]") {
  for (const char* rel : {"bags/kitti3_lz4.bag", "bags/quirks_bz2.bag", "bags/quirks_lz4_unindexed.bag"}) {
    INFO(rel);
    const std::string path = data_path(rel);
    RosBag1Reader by_path(path);
    RosBag1Reader in_memory = RosBag1Reader::from_bytes(semlio_test::read_bytes(path), "mem");
    CHECK(semlio_test::check_same_bag(by_path, in_memory) >= 5);
  }
  CHECK_THROWS_WITH(RosBag1Reader::from_bytes("not a bag at all, just text", "mem_name"), Catch::Contains("mem_name"));
  CHECK_THROWS_AS(RosBag1Reader::from_bytes("", "mem_name"), semlio::FormatError);
}

TEST_CASE("rosbag1: a chunk stating more bytes than its LZ4 / zstd data can expand to is a FormatError",
          "[io][rosbag1]") {
  // 64 compressed bytes expand to at most 64 * 255 (+ 128 KiB) with LZ4 and
  // 64 * 32768 (+ 128 KiB) with zstd: a larger stated size is refused before
  // the output buffer is allocated.
  const std::vector<std::uint8_t> in(64, 0);
  std::vector<std::uint8_t> out;
  CHECK_THROWS_WITH(semlio::io::detail::decompress_lz4_frame(in.data(), in.size(), 64 * 255 + (1 << 17) + 1, out,
                                                             "chunk"),
                    Catch::Contains("more than 64 bytes of LZ4 can hold"));
  CHECK(out.empty());
  CHECK_THROWS_WITH(
      semlio::io::detail::decompress_zstd(in.data(), in.size(), 64 * 32768 + (1 << 17) + 1, out, "chunk"),
      Catch::Contains("more than 64 bytes of zstd can hold"));
  CHECK(out.empty());
  // Within the bound the data itself decides (64 zero bytes are no LZ4 frame).
  CHECK_THROWS_WITH(semlio::io::detail::decompress_lz4_frame(in.data(), in.size(), 1000, out, "chunk"),
                    Catch::Contains("LZ4 data is corrupt"));
}

}  // namespace test_rosbag1
