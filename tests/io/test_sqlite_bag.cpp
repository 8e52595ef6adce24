// rosbag2 sqlite3 reader on a bag folder in rosbag2's schema (two split
// .db3 files whose topic ids differ, metadata.yaml) holding the CDR messages
// @foxglove/cdr wrote (scripts/fixtures/make_mcap_fixtures.mjs,
// write_sqlite_bag.py): the same messages, byte for byte and in the same
// order, as the MCAP file small_none.mcap written from the same values;
// values against the script's formulas; single-file and folder-without-
// metadata opening; typed errors for what is not a rosbag2 sqlite3 bag.
#include <catch2/catch.hpp>

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/mcap.hpp>
#include <semlio/io/bag/sqlite_bag.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio_test/bag_compare.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_cloud_files.hpp>

namespace test_sqlite_bag {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::io::BagMessage;
using semlio::io::BagTopic;
using semlio::io::McapReader;
using semlio::io::MessageEncoding;
using semlio::io::SqliteBagReader;
using semlio_test::data_path;

const std::string kBag = data_path("bags/ros2_sqlite");

std::size_t topic_index(const std::vector<BagTopic>& topics, const std::string& name) {
  for (std::size_t i = 0; i < topics.size(); ++i) {
    if (topics[i].name == name) return i;
  }
  FAIL("no topic " << name);
  return 0;
}

template <typename Reader>
std::vector<BagMessage> read_all(Reader& reader) {
  std::vector<BagMessage> out;
  BagMessage m;
  while (reader.next(m)) out.push_back(m);
  return out;
}

/// Runs `sql` on a new database file.
void make_db(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(path.c_str(), &db) == SQLITE_OK);
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  sqlite3_free(err);
  sqlite3_close(db);
  REQUIRE(rc == SQLITE_OK);
}

}  // namespace

TEST_CASE("rosbag2 sqlite3: topics, types and counts over the split files", "[io][bags][sqlite]") {
  SqliteBagReader reader(kBag);
  const std::vector<BagTopic>& topics = reader.topics();
  REQUIRE(topics.size() == 3);
  const BagTopic& points = topics[topic_index(topics, "/points")];
  const BagTopic& padded = topics[topic_index(topics, "/padded/points")];
  const BagTopic& imu = topics[topic_index(topics, "/imu")];
  CHECK(points.type == "sensor_msgs/msg/PointCloud2");
  CHECK(imu.type == "sensor_msgs/msg/Imu");
  CHECK(points.encoding == MessageEncoding::kCdr);
  CHECK(imu.encoding == MessageEncoding::kCdr);
  CHECK(points.message_count == 3);
  CHECK(padded.message_count == 3);
  CHECK(imu.message_count == 10);
}

TEST_CASE("rosbag2 sqlite3: the same messages, bytes and order as the MCAP file of the same values", "[io][bags][sqlite]") {
  SqliteBagReader reader(kBag);
  McapReader mcap(data_path("bags/small_none.mcap"));
  const std::vector<BagMessage> got = read_all(reader);
  const std::vector<BagMessage> want = read_all(mcap);
  REQUIRE(got.size() == 16);
  REQUIRE(want.size() == 16);
  for (std::size_t i = 0; i < got.size(); ++i) {
    CAPTURE(i);
    CHECK(got[i].log_time_ns == want[i].log_time_ns);
    CHECK(reader.topics()[got[i].topic].name == mcap.topics()[want[i].topic].name);
    CHECK(got[i].data == want[i].data);
  }
  // ...and they decode to the generator's values (spot checks; test_mcap.cpp checks all of them).
  const std::size_t imu = topic_index(reader.topics(), "/imu");
  int imus = 0;
  for (const BagMessage& m : got) {
    if (m.topic != imu) continue;
    const semlio::io::ImuMsg msg = semlio::io::parse_cdr_imu(m.data);
    const double d = imus++;
    CHECK(msg.angular_velocity_radps == Eigen::Vector3d(d / 8, -d / 4, 0.5));
    CHECK(msg.stamp_s == 1700000000.0 + static_cast<double>(25000000 * (imus - 1)) / 1e9);
    CHECK(m.log_time_ns == 1700000000LL * 1000000000LL + 25000000LL * (imus - 1));
  }
  CHECK(imus == 10);
  const std::size_t points = topic_index(reader.topics(), "/points");
  const semlio::io::PointCloud2Msg first = semlio::io::parse_cdr_pointcloud2(got.front().data);
  CHECK(got.front().topic == points);
  CHECK(first.width == 300);
  CHECK(first.frame_id == "lidar");
}

TEST_CASE("rosbag2 sqlite3: select, a single .db3, a folder without metadata.yaml", "[io][bags][sqlite]") {
  SqliteBagReader reader(kBag);
  reader.select({"/padded/points"});
  const std::vector<BagMessage> padded = read_all(reader);
  REQUIRE(padded.size() == 3);
  for (const BagMessage& m : padded) CHECK(reader.topics()[m.topic].name == "/padded/points");
  reader.select({});
  CHECK(read_all(reader).size() == 16);
  CHECK_THROWS_AS(reader.select({"/nope"}), semlio::ValueError);

  // The second split alone: messages after 150 ms (clouds at 200 ms, 250 ms; IMU at 175-225 ms).
  SqliteBagReader second(kBag + "/ros2_sqlite_1.db3");
  const std::vector<BagMessage> rest = read_all(second);
  REQUIRE(rest.size() == 5);
  for (const BagMessage& m : rest) CHECK(m.log_time_ns > 1700000000LL * 1000000000LL + 150000000LL);

  // A folder of .db3 files without metadata.yaml: every *.db3, sorted by name.
  semlio_test::CloudTempDir dir("sqlite_bag");
  const std::filesystem::path folder = dir.file("bag");
  std::filesystem::create_directories(folder);
  for (const char* f : {"ros2_sqlite_0.db3", "ros2_sqlite_1.db3"}) {
    std::filesystem::copy_file(kBag + "/" + f, folder / f);
  }
  SqliteBagReader bare(folder.string());
  CHECK(read_all(bare).size() == 16);
}

TEST_CASE("rosbag2 sqlite3: what is not a rosbag2 sqlite3 bag gives typed errors naming the file", "[io][bags][sqlite]") {
  semlio_test::CloudTempDir dir("sqlite_bad");
  CHECK_THROWS_AS(SqliteBagReader(dir.file("missing")), semlio::IoError);
  CHECK_THROWS_AS(SqliteBagReader(dir.file("")), semlio::IoError);  // a folder without .db3 files

  const std::string text = dir.write("text.db3", "this is not a database, just some bytes of text\n");
  try {
    SqliteBagReader r(text);
    FAIL("no exception");
  } catch (const semlio::FormatError& e) {
    CHECK(std::string(e.what()).find("text.db3") != std::string::npos);
  }

  const std::string no_messages = dir.file("no_messages.db3");
  make_db(no_messages, "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT);");
  CHECK_THROWS_AS(SqliteBagReader(no_messages), semlio::FormatError);

  std::filesystem::create_directories(dir.file("mcap_bag"));
  std::ofstream(dir.file("mcap_bag/metadata.yaml"))
      << "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths:\n    - mcap_bag_0.mcap\n";
  CHECK_THROWS_AS(SqliteBagReader(dir.file("mcap_bag")), semlio::FormatError);

  std::filesystem::create_directories(dir.file("no_list"));
  std::ofstream(dir.file("no_list/metadata.yaml")) << "rosbag2_bagfile_information:\n  version: 5\n";
  CHECK_THROWS_AS(SqliteBagReader(dir.file("no_list")), semlio::FormatError);

  // A truncated database file.
  const std::string full = semlio_test::read_bytes(kBag + "/ros2_sqlite_0.db3");
  REQUIRE(full.size() > 4096);
  const std::string cut = dir.write("cut.db3", full.substr(0, full.size() / 2));
  CHECK_THROWS_AS(
      [&] {
        SqliteBagReader r(cut);
        read_all(r);
      }(),
      semlio::FormatError);
}

TEST_CASE("rosbag2 sqlite3: random byte damage gives messages or a semlio::Error, nothing else", "[io][bags][sqlite]") {
  const std::string full = semlio_test::read_bytes(kBag + "/ros2_sqlite_0.db3");
  REQUIRE(full.size() > 4096);
  semlio_test::CloudTempDir dir("sqlite_fuzz");
  std::mt19937 rng(5);
  int errors = 0;
  for (int trial = 0; trial < 120; ++trial) {
    std::string b = full;
    // Damage the first page (schema, header) in a third of the trials: it is where a lie hurts most.
    const std::size_t span = trial % 3 == 0 ? 4096 : b.size();
    for (int f = 0; f < 1 + trial % 4; ++f) {
      b[std::uniform_int_distribution<std::size_t>(0, span - 1)(rng)] =
          static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
    }
    try {
      SqliteBagReader reader(dir.write("fuzz_" + std::to_string(trial) + ".db3", b));
      read_all(reader);
    } catch (const semlio::Error&) {
      ++errors;
    }
  }
  CHECK(errors > 0);
}

TEST_CASE("rosbag2 sqlite3: topics of another serialization format are not listed", "[io][bags][sqlite]") {
  semlio_test::CloudTempDir dir("sqlite_fmt");
  const std::string db = dir.file("mixed.db3");
  make_db(db,
          "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
          " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
          "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,"
          " data BLOB NOT NULL);"
          "INSERT INTO topics VALUES (1, '/json', 'std_msgs/msg/String', 'json', '');"
          "INSERT INTO topics VALUES (2, '/cdr', 'std_msgs/msg/String', 'cdr', '');"
          "INSERT INTO messages VALUES (1, 1, 5, x'7b7d');"
          "INSERT INTO messages VALUES (2, 2, 7, x'00010000');"
          "INSERT INTO messages VALUES (3, 2, 6, x'00010000');");
  SqliteBagReader reader(db);
  REQUIRE(reader.topics().size() == 1);
  CHECK(reader.topics()[0].name == "/cdr");
  CHECK(reader.topics()[0].message_count == 2);
  const std::vector<BagMessage> all = read_all(reader);
  REQUIRE(all.size() == 2);
  CHECK(all[0].log_time_ns == 6);  // ORDER BY timestamp, not insertion order
  CHECK(all[1].log_time_ns == 7);
  CHECK(all[0].data == std::vector<std::uint8_t>{0x00, 0x01, 0x00, 0x00});
}

TEST_CASE("rosbag2 sqlite3: rows out of timestamp order are a FormatError, not a time going back",
          "[io][bags][sqlite]") {
  // Found by fuzzing (tests/fuzz/crashes/sqlite_bag): a corrupt timestamp
  // index returned a row out of order. The same happens without corruption
  // when a timestamp is not an integer: SQLite sorts text after every number.
  semlio_test::CloudTempDir dir("sqlite_order");
  const std::string db = dir.file("text_stamp.db3");
  make_db(db,
          "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
          " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
          "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,"
          " data BLOB NOT NULL);"
          "INSERT INTO topics VALUES (1, '/cdr', 'std_msgs/msg/String', 'cdr', '');"
          "INSERT INTO messages VALUES (1, 1, 7, x'00010000');"
          "INSERT INTO messages VALUES (2, 1, '3 ns', x'00010000');");
  SqliteBagReader reader(db);
  BagMessage m;
  REQUIRE(reader.next(m));
  CHECK(m.log_time_ns == 7);
  CHECK_THROWS_WITH(reader.next(m), Catch::Contains("text_stamp.db3") && Catch::Contains("timestamp order"));
}

TEST_CASE("rosbag2 sqlite3: from_bytes reads a .db3 held in memory like its path", "[io][bags][sqlite]") {
  const std::string path = kBag + "/ros2_sqlite_0.db3";
  SqliteBagReader by_path(path);
  SqliteBagReader in_memory = SqliteBagReader::from_bytes(semlio_test::read_bytes(path), "mem.db3");
  // 2 + 7 + 2 messages on its three topics (counted with the sqlite3 shell)
  CHECK(semlio_test::check_same_bag(by_path, in_memory) == 11);
  CHECK_THROWS_WITH(SqliteBagReader::from_bytes("not a database", "mem.db3"), Catch::Contains("mem.db3"));
  CHECK_THROWS_AS(SqliteBagReader::from_bytes("", "empty.db3"), semlio::FormatError);
}

}  // namespace test_sqlite_bag
