// Replays the committed fuzz corpus and crash inputs of the bag container
// harnesses (tests/fuzz/harnesses_bags.hpp) in the regular test build; built
// only with the bag libraries (tests/fuzz/replay.cmake). Also checks that
// every bag seed is a valid bag -- the in-memory reader (from_bytes) returns
// the same messages as the path reader on it -- so the fuzzer starts deep.
#include <catch2/catch.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "harnesses_bags.hpp"
#include "replay.hpp"

namespace test_replay_bags {

namespace {

std::string bytes_of(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Every message of a reader: (topic name, log time, bytes).
template <typename Reader>
std::vector<std::string> messages(Reader& r) {
  std::vector<std::string> out;
  semlio::io::BagMessage m;
  while (r.next(m)) {
    out.push_back(r.topics()[m.topic].name + " " + std::to_string(m.log_time_ns) + " " +
                  std::string(m.data.begin(), m.data.end()));
  }
  return out;
}

template <typename Reader, typename Open>
void check_seeds(const std::string& harness, Open from_bytes) {
  const auto seeds = semlio_fuzz::inputs("corpus", harness);
  REQUIRE(!seeds.empty());
  for (const auto& p : seeds) {
    INFO(p.string());
    Reader by_path(p.string());
    Reader in_memory = from_bytes(bytes_of(p), p.string());
    const std::vector<std::string> a = messages(by_path);
    CHECK(a.size() >= 3);
    CHECK(messages(in_memory) == a);
  }
}

}  // namespace

TEST_CASE("fuzz replay: every corpus and crash input of the bag harnesses", "[fuzz]") {
  for (const semlio_fuzz::Harness& h : semlio_fuzz::kBagHarnesses) {
    SECTION(h.name) { semlio_fuzz::replay(h.name, h.body); }
  }
}

TEST_CASE("fuzz bag seeds are valid bags, read alike from memory and from their path", "[fuzz]") {
  check_seeds<semlio::io::RosBag1Reader>("rosbag1", [](const std::string& b, const std::string& n) {
    return semlio::io::RosBag1Reader::from_bytes(b, n);
  });
  check_seeds<semlio::io::McapReader>("mcap", [](const std::string& b, const std::string& n) {
    return semlio::io::McapReader::from_bytes(b, n);
  });
  check_seeds<semlio::io::SqliteBagReader>("sqlite_bag", [](const std::string& b, const std::string& n) {
    return semlio::io::SqliteBagReader::from_bytes(b, n);
  });
}

TEST_CASE("fuzz message seeds deserialise and decode", "[fuzz]") {
  for (const auto& p : semlio_fuzz::inputs("corpus", "ros1_pointcloud2")) {
    INFO(p.string());
    const std::string b = bytes_of(p);
    semlio::Scan s;
    semlio::io::ros1_pointcloud2_to_scan(reinterpret_cast<const std::uint8_t*>(b.data()), b.size(), s);
    CHECK(s.size() >= 5);
  }
  for (const auto& p : semlio_fuzz::inputs("corpus", "cdr_pointcloud2")) {
    INFO(p.string());
    const std::string b = bytes_of(p);
    semlio::io::PointCloud2Msg msg;
    semlio::io::parse_cdr_pointcloud2(reinterpret_cast<const std::uint8_t*>(b.data()), b.size(), msg);
    CHECK(semlio::io::pointcloud2_to_scan(msg).size() >= 5);
  }
  for (const char* h : {"ros1_imu", "cdr_imu"}) {
    for (const auto& p : semlio_fuzz::inputs("corpus", h)) {
      INFO(p.string());
      const std::string b = bytes_of(p);
      const auto* d = reinterpret_cast<const std::uint8_t*>(b.data());
      semlio::io::ImuMsg msg;
      if (std::string(h) == "ros1_imu") {
        semlio::io::parse_ros1_imu(d, b.size(), msg);
      } else {
        semlio::io::parse_cdr_imu(d, b.size(), msg);
      }
      CHECK(msg.stamp_s > 1e9);  // the fixtures' stamps are 2011 and 2023 epochs
      CHECK(std::abs(msg.linear_acceleration_mps2.norm() - 9.81) < 1.0);
    }
  }
}

}  // namespace test_replay_bags
