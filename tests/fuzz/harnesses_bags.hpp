#pragma once
// Fuzz harness bodies of the bag container readers (include/semlio/io/bag/):
// ROS 1 bag, MCAP and rosbag2 sqlite3, each opened from the input bytes in
// memory (from_bytes: the same reader code as the path constructor, reads
// served from a copy), every message read, and PointCloud2 / Imu messages
// decoded with the deserialiser their encoding needs. Invariants: topic
// indices in range, log times non-decreasing (every reader's contract,
// io/bag/message.hpp), decoded clouds as in harnesses.hpp.
//
// Needs the optional bag libraries (semlio::io_bags: bz2, lz4, zstd,
// sqlite3), so it is compiled only where they were found
// (SEMLIO_HAVE_BAGS); harnesses.hpp holds the rest.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/mcap.hpp>
#include <semlio/io/bag/message.hpp>
#include <semlio/io/bag/rosbag1.hpp>
#include <semlio/io/bag/sqlite_bag.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio/io/ros1_msgs.hpp>

#include "fuzz_support.hpp"
#include "harnesses.hpp"

namespace semlio_fuzz {

/// Most messages a bag harness reads and decodes per input: bounds the time
/// of one execution (a 64 KiB input can index many tiny messages).
inline constexpr std::size_t kMaxBagMessages = 256;

/// Decodes one bag message by its topic's type and encoding (typed errors
/// expected: the fuzzer corrupts message bytes too).
inline void decode_bag_message(const semlio::io::BagTopic& topic, const semlio::io::BagMessage& m) {
  const bool ros1 = topic.encoding == semlio::io::MessageEncoding::kRos1;
  try {
    if (semlio::io::is_pointcloud2_type(topic.type)) {
      semlio::io::PointCloud2Msg msg;
      if (ros1) {
        semlio::io::parse_ros1_pointcloud2(m.data.data(), m.data.size(), msg);
      } else {
        semlio::io::parse_cdr_pointcloud2(m.data.data(), m.data.size(), msg);
      }
      fuzz_decode_cloud(msg);
    } else if (semlio::io::is_imu_type(topic.type)) {
      semlio::io::ImuMsg msg;
      if (ros1) {
        semlio::io::parse_ros1_imu(m.data.data(), m.data.size(), msg);
      } else {
        semlio::io::parse_cdr_imu(m.data.data(), m.data.size(), msg);
      }
      check(std::isfinite(msg.stamp_s));
    }
  } catch (const semlio::Error&) {
  }
}

/// Reads every message of an opened reader (at most kMaxBagMessages): topic
/// in range, log times non-decreasing, messages decoded. A typed error part
/// way (a corrupt chunk) is an expected outcome.
template <typename Reader>
void read_bag(Reader& reader) {
  const auto& topics = reader.topics();
  semlio::io::BagMessage m;
  std::int64_t last = std::numeric_limits<std::int64_t>::min();
  try {
    for (std::size_t i = 0; i < kMaxBagMessages && reader.next(m); ++i) {
      check(m.topic < topics.size());
      check(m.log_time_ns >= last);
      last = m.log_time_ns;
      decode_bag_message(topics[m.topic], m);
    }
  } catch (const semlio::Error&) {
  }
}

/// ROS 1 bag (format 2.0): RosBag1Reader::from_bytes, every message read.
inline int fuzz_rosbag1(const std::uint8_t* data, std::size_t size) {
  try {
    semlio::io::RosBag1Reader reader = semlio::io::RosBag1Reader::from_bytes(as_text(data, size), "in.bag");
    read_bag(reader);
  } catch (const semlio::Error&) {
  }
  return 0;
}

/// MCAP: McapReader::from_bytes, every message read.
inline int fuzz_mcap(const std::uint8_t* data, std::size_t size) {
  try {
    semlio::io::McapReader reader = semlio::io::McapReader::from_bytes(as_text(data, size), "in.mcap");
    read_bag(reader);
  } catch (const semlio::Error&) {
  }
  return 0;
}

/// rosbag2 sqlite3 (.db3): SqliteBagReader::from_bytes, every message read.
inline int fuzz_sqlite_bag(const std::uint8_t* data, std::size_t size) {
  try {
    semlio::io::SqliteBagReader reader = semlio::io::SqliteBagReader::from_bytes(as_text(data, size), "in.db3");
    read_bag(reader);
  } catch (const semlio::Error&) {
  }
  return 0;
}

/// Every harness of this header.
inline constexpr Harness kBagHarnesses[] = {
    {"rosbag1", fuzz_rosbag1}, {"mcap", fuzz_mcap}, {"sqlite_bag", fuzz_sqlite_bag},
};

}  // namespace semlio_fuzz
