#pragma once
/// \file
/// Writes ROS 1 bags (format 2.0, what `rosbag record` writes) with
/// uncompressed chunks: sensor_msgs/PointCloud2 and sensor_msgs/Imu topics.
///
/// File layout (ROS wiki "Bags/Format/2.0"): the magic "#ROSBAG V2.0\n"; the
/// bag header record padded to 4096 bytes (index_pos, conn_count,
/// chunk_count; rewritten by close()); chunks (compression "none"), each
/// holding a connection record the first time a topic appears and the message
/// data records, and each followed by one index data record per connection
/// it holds (ver 1: time + offset of every message inside the chunk); then,
/// at index_pos, every connection record and one chunk info record per chunk.
/// A record is <uint32 header_len><header><uint32 data_len><data>, its header
/// a run of <uint32 len><name>=<value> fields; all integers little-endian.
/// Connection records carry type, md5sum and the full message definition, so
/// that rosbag can decode the messages without the types installed.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/ros_writer_msgs.hpp>
#include <semlio/io/ros_msgs.hpp>

namespace semlio::io {

/// Settings of Rosbag1Writer.
struct Rosbag1WriterConfig {
  std::size_t chunk_bytes = 768 * 1024;  ///< a chunk is closed once it holds this many bytes (rosbag's default)
};

namespace detail {

/// Op codes of ROS bag 2.0 records.
enum class BagOp : std::uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07,
};

/// Builds a record header (or a connection record's data): name=value fields.
class BagFields {
 public:
  /// Adds a field whose value is raw bytes.
  void bytes(std::string_view name, const void* value, std::size_t n) {
    const std::size_t len = name.size() + 1 + n;
    if (len > std::numeric_limits<std::uint32_t>::max()) throw ValueError("bag writer: header field too long");
    append_le(out_, static_cast<std::uint32_t>(len));
    out_.insert(out_.end(), name.begin(), name.end());
    out_.push_back('=');
    const auto* p = static_cast<const std::uint8_t*>(value);
    out_.insert(out_.end(), p, p + n);
  }
  /// Adds a little-endian integer field.
  template <typename T>
  void number(std::string_view name, T v) {
    bytes(name, &v, sizeof(T));
  }
  /// Adds a string field.
  void text(std::string_view name, std::string_view v) { bytes(name, v.data(), v.size()); }
  /// Adds the op field.
  void op(BagOp o) {
    const auto v = static_cast<std::uint8_t>(o);
    bytes("op", &v, 1);
  }
  /// Adds a ROS time field (uint32 sec, uint32 nsec).
  void time(std::string_view name, std::int64_t ns) {
    std::uint8_t b[8];
    const auto sec = static_cast<std::uint32_t>(ns / 1000000000LL);
    const auto nsec = static_cast<std::uint32_t>(ns % 1000000000LL);
    std::memcpy(b, &sec, 4);
    std::memcpy(b + 4, &nsec, 4);
    bytes(name, b, 8);
  }
  [[nodiscard]] const std::vector<std::uint8_t>& data() const noexcept { return out_; }

 private:
  std::vector<std::uint8_t> out_;
};

/// Appends a whole record <header_len><header><data_len><data>.
inline void append_bag_record(std::vector<std::uint8_t>& out, const BagFields& header, const std::uint8_t* data,
                              std::size_t data_len) {
  if (data_len > std::numeric_limits<std::uint32_t>::max()) {
    throw ValueError("bag writer: record of " + std::to_string(data_len) + " bytes exceeds 4 GiB");
  }
  append_le(out, static_cast<std::uint32_t>(header.data().size()));
  out.insert(out.end(), header.data().begin(), header.data().end());
  append_le(out, static_cast<std::uint32_t>(data_len));
  out.insert(out.end(), data, data + data_len);
}

}  // namespace detail

/// Writes a ROS 1 bag. Usage: add_topic() each topic, write() messages (any
/// order of log times), close(). Not thread-safe. Throws IoError when the
/// file cannot be written and ValueError for a message that cannot be
/// represented (negative stamp, oversized cloud).
class Rosbag1Writer {
 public:
  using Config = Rosbag1WriterConfig;

  /// Creates (truncates) the bag at `path`; throws ConfigError for invalid
  /// settings before the file is touched.
  explicit Rosbag1Writer(const std::string& path, const Rosbag1WriterConfig& config = {})
      : config_(checked(config)), file_(path) {
    static constexpr std::string_view kMagic = "#ROSBAG V2.0\n";
    file_.write(kMagic.data(), kMagic.size());
    file_.write(bag_header_record(0, 0, 0));
  }
  Rosbag1Writer(const Rosbag1Writer&) = delete;
  Rosbag1Writer& operator=(const Rosbag1Writer&) = delete;
  /// Closes the bag if close() was not called; errors are swallowed here, so
  /// call close() to see them.
  ~Rosbag1Writer() {
    try {
      close();
    } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw
    }
  }

  /// Adds a topic (a connection) and returns its id for write().
  std::size_t add_topic(const std::string& topic, RosMessageType type, const std::string& callerid = "/semlio") {
    if (closed_) throw ValueError("Rosbag1Writer::add_topic: the bag is closed");
    connections_.push_back(Connection{topic, type, callerid, false, 0});
    return connections_.size() - 1;
  }

  /// Writes one cloud on `topic` logged at `log_time_ns` (>= 0).
  void write(std::size_t topic, std::int64_t log_time_ns, const PointCloud2Msg& msg) {
    check(topic, RosMessageType::kPointCloud2);
    detail::serialize_ros1(msg, connections_[topic].seq, buffer_);
    write_serialized(topic, log_time_ns, buffer_);
  }
  /// Writes one IMU sample on `topic` logged at `log_time_ns` (>= 0).
  void write(std::size_t topic, std::int64_t log_time_ns, const ImuMsg& msg) {
    check(topic, RosMessageType::kImu);
    detail::serialize_ros1(msg, connections_[topic].seq, buffer_);
    write_serialized(topic, log_time_ns, buffer_);
  }

  /// Messages written so far.
  [[nodiscard]] std::size_t message_count() const noexcept { return messages_; }

  /// Writes the last chunk and the index, patches the bag header and closes
  /// the file. Idempotent.
  void close() {
    if (closed_) return;
    closed_ = true;
    flush_chunk();
    const std::uint64_t index_pos = file_.position();
    std::vector<std::uint8_t> out;
    for (std::size_t c = 0; c < connections_.size(); ++c) append_connection(out, c);
    for (const ChunkInfo& ci : chunks_) {
      detail::BagFields h;
      h.op(detail::BagOp::kChunkInfo);
      h.number("ver", std::uint32_t{1});
      h.number("chunk_pos", ci.pos);
      h.time("start_time", ci.start_ns);
      h.time("end_time", ci.end_ns);
      h.number("count", static_cast<std::uint32_t>(ci.counts.size()));
      std::vector<std::uint8_t> data;
      for (const auto& [conn, count] : ci.counts) {
        detail::append_le(data, conn);
        detail::append_le(data, count);
      }
      detail::append_bag_record(out, h, data.data(), data.size());
    }
    file_.write(out);
    file_.patch(13, bag_header_record(index_pos, static_cast<std::uint32_t>(connections_.size()),
                                      static_cast<std::uint32_t>(chunks_.size())));
    file_.close();
  }

 private:
  struct Connection {
    std::string topic;
    RosMessageType type;
    std::string callerid;
    bool written = false;  ///< its connection record is in a chunk already
    std::uint32_t seq = 0;
  };
  struct IndexEntry {
    std::int64_t time_ns;
    std::uint32_t offset;
  };
  struct ChunkInfo {
    std::uint64_t pos = 0;
    std::int64_t start_ns = 0;
    std::int64_t end_ns = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> counts;  ///< (connection, messages)
  };

  static std::vector<std::uint8_t> bag_header_record(std::uint64_t index_pos, std::uint32_t conns,
                                                     std::uint32_t chunks) {
    detail::BagFields h;
    h.op(detail::BagOp::kBagHeader);
    h.number("index_pos", index_pos);
    h.number("conn_count", conns);
    h.number("chunk_count", chunks);
    // rosbag pads the header record's data with spaces to 4096 bytes, so that
    // the header can be rewritten in place however its fields change.
    const std::vector<std::uint8_t> pad(4096 - h.data().size(), ' ');
    std::vector<std::uint8_t> out;
    detail::append_bag_record(out, h, pad.data(), pad.size());
    return out;
  }

  void check(std::size_t topic, RosMessageType type) const {
    if (closed_) throw ValueError("Rosbag1Writer::write: the bag is closed");
    if (topic >= connections_.size()) {
      throw ValueError("Rosbag1Writer::write: topic id " + std::to_string(topic) + " was never added (" +
                       std::to_string(connections_.size()) + " topics)");
    }
    if (connections_[topic].type != type) {
      throw ValueError("Rosbag1Writer::write: topic '" + connections_[topic].topic + "' has type " +
                       detail::ros_type_info(connections_[topic].type).ros1_name + ", not " +
                       detail::ros_type_info(type).ros1_name);
    }
  }

  void append_connection(std::vector<std::uint8_t>& out, std::size_t c) const {
    const Connection& conn = connections_[c];
    const detail::RosTypeInfo& info = detail::ros_type_info(conn.type);
    detail::BagFields h;
    h.op(detail::BagOp::kConnection);
    h.number("conn", static_cast<std::uint32_t>(c));
    h.text("topic", conn.topic);
    detail::BagFields d;
    d.text("topic", conn.topic);
    d.text("type", info.ros1_name);
    d.text("md5sum", info.md5sum);
    d.text("message_definition", info.ros1_definition);
    d.text("callerid", conn.callerid);
    d.text("latching", "0");
    detail::append_bag_record(out, h, d.data().data(), d.data().size());
  }

  void write_serialized(std::size_t topic, std::int64_t log_time_ns, const std::vector<std::uint8_t>& data) {
    if (log_time_ns < 0 || log_time_ns / 1000000000LL > std::numeric_limits<std::uint32_t>::max()) {
      throw ValueError("Rosbag1Writer::write: log time " + std::to_string(log_time_ns) +
                       " ns is not a ROS time (>= 0, < 2^32 s)");
    }
    Connection& conn = connections_[topic];
    if (!conn.written) {
      append_connection(chunk_, topic);
      conn.written = true;
    }
    if (chunk_.size() > std::numeric_limits<std::uint32_t>::max() - data.size() - 64) {
      throw ValueError("Rosbag1Writer::write: message of " + std::to_string(data.size()) +
                       " bytes does not fit a chunk");
    }
    if (index_.size() < connections_.size()) index_.resize(connections_.size());
    index_[topic].push_back(IndexEntry{log_time_ns, static_cast<std::uint32_t>(chunk_.size())});
    detail::BagFields h;
    h.op(detail::BagOp::kMessageData);
    h.number("conn", static_cast<std::uint32_t>(topic));
    h.time("time", log_time_ns);
    detail::append_bag_record(chunk_, h, data.data(), data.size());
    chunk_start_ns_ = chunk_messages_ == 0 ? log_time_ns : std::min(chunk_start_ns_, log_time_ns);
    chunk_end_ns_ = chunk_messages_ == 0 ? log_time_ns : std::max(chunk_end_ns_, log_time_ns);
    ++chunk_messages_;
    ++messages_;
    ++conn.seq;
    if (chunk_.size() >= config_.chunk_bytes) flush_chunk();
  }

  void flush_chunk() {
    if (chunk_messages_ == 0) return;
    ChunkInfo info;
    info.pos = file_.position();
    info.start_ns = chunk_start_ns_;
    info.end_ns = chunk_end_ns_;
    detail::BagFields h;
    h.op(detail::BagOp::kChunk);
    h.text("compression", "none");
    h.number("size", static_cast<std::uint32_t>(chunk_.size()));
    std::vector<std::uint8_t> out;
    out.reserve(chunk_.size() + 256);
    detail::append_bag_record(out, h, chunk_.data(), chunk_.size());
    for (std::size_t c = 0; c < index_.size(); ++c) {
      if (index_[c].empty()) continue;
      detail::BagFields ih;
      ih.op(detail::BagOp::kIndexData);
      ih.number("ver", std::uint32_t{1});
      ih.number("conn", static_cast<std::uint32_t>(c));
      ih.number("count", static_cast<std::uint32_t>(index_[c].size()));
      std::vector<std::uint8_t> data;
      for (const IndexEntry& e : index_[c]) {
        detail::append_le(data, static_cast<std::uint32_t>(e.time_ns / 1000000000LL));
        detail::append_le(data, static_cast<std::uint32_t>(e.time_ns % 1000000000LL));
        detail::append_le(data, e.offset);
      }
      detail::append_bag_record(out, ih, data.data(), data.size());
      info.counts.emplace_back(static_cast<std::uint32_t>(c), static_cast<std::uint32_t>(index_[c].size()));
      index_[c].clear();
    }
    file_.write(out);
    chunks_.push_back(std::move(info));
    chunk_.clear();
    chunk_messages_ = 0;
  }

  static const Rosbag1WriterConfig& checked(const Rosbag1WriterConfig& c) {
    if (c.chunk_bytes == 0) throw ConfigError("Rosbag1WriterConfig.chunk_bytes must be > 0, got 0");
    return c;
  }

  Rosbag1WriterConfig config_;
  detail::OutFile file_;
  std::vector<Connection> connections_;
  std::vector<std::vector<IndexEntry>> index_;  ///< per connection, the current chunk's messages
  std::vector<ChunkInfo> chunks_;
  std::vector<std::uint8_t> chunk_;             ///< current chunk's records (uncompressed)
  std::vector<std::uint8_t> buffer_;            ///< serialised message (reused)
  std::int64_t chunk_start_ns_ = 0;
  std::int64_t chunk_end_ns_ = 0;
  std::size_t chunk_messages_ = 0;
  std::size_t messages_ = 0;
  bool closed_ = false;
};

}  // namespace semlio::io
