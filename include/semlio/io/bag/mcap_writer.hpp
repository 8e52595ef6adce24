#pragma once
/// \file
/// Writes MCAP files (mcap.dev/spec, version 0) holding sensor_msgs/PointCloud2
/// and sensor_msgs/Imu: profile "ros2" with CDR messages and "ros2msg"
/// schemas by default (what rosbag2 records), or profile "ros1" with ROS 1
/// messages and "ros1msg" schemas. Chunks are uncompressed or zstd.
///
/// Layout: magic, Header; data section of Chunks (a chunk holds the Schema
/// and Channel records the first time they are needed, then Messages; its
/// uncompressed CRC-32 is filled in), each followed by one MessageIndex per
/// channel in it; DataEnd (data_section_crc 0 = "not computed", which the
/// spec allows); summary section: every Schema, Channel, one Statistics and
/// one ChunkIndex per chunk, then a SummaryOffset per group; Footer with the
/// summary CRC-32; magic. Records are <uint8 opcode><uint64 length><content>,
/// integers little-endian, strings <uint32 length><bytes>.

#include <zstd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/message.hpp>
#include <semlio/io/bag/ros_writer_msgs.hpp>
#include <semlio/io/ros_msgs.hpp>

namespace semlio::io {

/// Chunk compression of McapWriter.
enum class McapCompression : std::uint8_t {
  kNone,  ///< chunks stored as they are
  kZstd,  ///< Zstandard ("zstd")
};

/// Settings of McapWriter.
struct McapWriterConfig {
  MessageEncoding encoding = MessageEncoding::kCdr;  ///< kCdr: profile ros2; kRos1: profile ros1
  McapCompression compression = McapCompression::kZstd;  ///< chunk compression
  /// Zstandard level, ZSTD_minCLevel() to ZSTD_maxCLevel() except 0. rosbag2's
  /// MCAP presets write 1 (its default), -5 (`zstd_fast`) and 19 (`zstd_small`).
  int zstd_level = 3;
  std::size_t chunk_bytes = 4 * 1024 * 1024;  ///< a chunk is closed once it holds this many bytes
  bool chunk_crc = true;  ///< store each chunk's CRC-32 (false: 0, "not computed", as rosbag2's `zstd_fast`)
};

namespace detail {

/// CRC-32 (ISO-HDLC: reflected polynomial 0xEDB88320, as zlib and MCAP use),
/// continued from `crc` (0 to start).
inline std::uint32_t mcap_crc32(const std::uint8_t* data, std::size_t n, std::uint32_t crc = 0) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1U) : c >> 1U;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFFU] ^ (crc >> 8U);
  return ~crc;
}

/// MCAP record opcodes.
enum class McapOp : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// Builds one record's content, then appends <op><length><content>.
class McapRecord {
 public:
  template <typename T>
  McapRecord& put(T v) {
    append_le(content_, v);
    return *this;
  }
  McapRecord& string(std::string_view s) {
    if (s.size() > std::numeric_limits<std::uint32_t>::max()) throw ValueError("mcap writer: string too long");
    append_le(content_, static_cast<std::uint32_t>(s.size()));
    content_.insert(content_.end(), s.begin(), s.end());
    return *this;
  }
  McapRecord& raw(const std::uint8_t* data, std::size_t n) {
    content_.insert(content_.end(), data, data + n);
    return *this;
  }
  /// Appends the record to `out` and returns its length in bytes.
  std::size_t append_to(std::vector<std::uint8_t>& out, McapOp op) const {
    out.push_back(static_cast<std::uint8_t>(op));
    append_le(out, static_cast<std::uint64_t>(content_.size()));
    out.insert(out.end(), content_.begin(), content_.end());
    return 9 + content_.size();
  }
  [[nodiscard]] std::vector<std::uint8_t>& content() noexcept { return content_; }

 private:
  std::vector<std::uint8_t> content_;
};

inline constexpr std::array<std::uint8_t, 8> kMcapMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

}  // namespace detail

/// Writes an MCAP file. Usage: add_topic() each topic, write() messages (any
/// order of log times), close(). Not thread-safe. Throws IoError when the
/// file cannot be written, ValueError for a message that cannot be
/// represented and FormatError when zstd fails.
class McapWriter {
 public:
  using Config = McapWriterConfig;

  /// Creates (truncates) the file at `path` and writes magic and Header;
  /// throws ConfigError for invalid settings before the file is touched.
  explicit McapWriter(const std::string& path, const McapWriterConfig& config = {})
      : config_(checked(config)), file_(path) {
    std::vector<std::uint8_t> out(detail::kMcapMagic.begin(), detail::kMcapMagic.end());
    detail::McapRecord h;
    h.string(cdr() ? "ros2" : "ros1").string("semlio");
    h.append_to(out, detail::McapOp::kHeader);
    file_.write(out);
  }
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;
  /// Closes the file if close() was not called; errors are swallowed here,
  /// so call close() to see them.
  ~McapWriter() {
    try {
      close();
    } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw
    }
  }

  /// Adds a topic (a channel; its schema is shared per type) and returns its
  /// id for write().
  std::size_t add_topic(const std::string& topic, RosMessageType type) {
    if (closed_) throw ValueError("McapWriter::add_topic: the file is closed");
    if (channels_.size() >= 65535) throw ValueError("McapWriter::add_topic: at most 65535 topics");
    channels_.push_back(Channel{topic, type, false, 0, 0});
    return channels_.size() - 1;
  }

  /// Writes one cloud on `topic` logged (and published) at `log_time_ns`.
  void write(std::size_t topic, std::int64_t log_time_ns, const PointCloud2Msg& msg) {
    check(topic, RosMessageType::kPointCloud2);
    if (cdr()) {
      detail::serialize_cdr(msg, buffer_);
    } else {
      detail::serialize_ros1(msg, channels_[topic].sequence, buffer_);
    }
    write_serialized(topic, log_time_ns);
  }
  /// Writes one IMU sample on `topic` logged (and published) at `log_time_ns`.
  void write(std::size_t topic, std::int64_t log_time_ns, const ImuMsg& msg) {
    check(topic, RosMessageType::kImu);
    if (cdr()) {
      detail::serialize_cdr(msg, buffer_);
    } else {
      detail::serialize_ros1(msg, channels_[topic].sequence, buffer_);
    }
    write_serialized(topic, log_time_ns);
  }

  /// Messages written so far.
  [[nodiscard]] std::size_t message_count() const noexcept { return messages_; }

  /// Writes the last chunk, DataEnd, the summary and the footer, and closes
  /// the file. Idempotent.
  void close() {
    if (closed_) return;
    closed_ = true;
    flush_chunk();
    std::vector<std::uint8_t> out;
    detail::McapRecord data_end;
    data_end.put(std::uint32_t{0});
    data_end.append_to(out, detail::McapOp::kDataEnd);
    file_.write(out);
    out.clear();

    const std::uint64_t summary_start = file_.position();
    struct Group {
      detail::McapOp op;
      std::uint64_t start;
      std::uint64_t length;
    };
    std::vector<Group> groups;
    const auto group = [&](detail::McapOp op, const auto& emit) {
      const std::uint64_t start = summary_start + out.size();
      emit();
      const std::uint64_t length = summary_start + out.size() - start;
      if (length > 0) groups.push_back(Group{op, start, length});
    };
    group(detail::McapOp::kSchema, [&] {
      for (std::size_t t = 0; t < schema_written_.size(); ++t) {
        if (schema_written_[t]) schema_record(static_cast<RosMessageType>(t)).append_to(out, detail::McapOp::kSchema);
      }
    });
    group(detail::McapOp::kChannel, [&] {
      for (std::size_t c = 0; c < channels_.size(); ++c) {
        if (channels_[c].written) channel_record(c).append_to(out, detail::McapOp::kChannel);
      }
    });
    group(detail::McapOp::kStatistics, [&] {
      detail::McapRecord s;
      std::uint32_t written = 0;
      for (const Channel& ch : channels_) written += ch.written ? 1U : 0U;
      s.put(static_cast<std::uint64_t>(messages_))
          .put(schemas_)
          .put(written)
          .put(std::uint32_t{0})
          .put(std::uint32_t{0})
          .put(static_cast<std::uint32_t>(chunk_indexes_.size()))
          .put(static_cast<std::uint64_t>(messages_ > 0 ? start_ns_ : 0))
          .put(static_cast<std::uint64_t>(messages_ > 0 ? end_ns_ : 0));
      detail::McapRecord counts;
      for (std::size_t c = 0; c < channels_.size(); ++c) {
        if (channels_[c].written) counts.put(static_cast<std::uint16_t>(c + 1)).put(channels_[c].count);
      }
      s.put(static_cast<std::uint32_t>(counts.content().size()));
      s.raw(counts.content().data(), counts.content().size());
      s.append_to(out, detail::McapOp::kStatistics);
    });
    group(detail::McapOp::kChunkIndex, [&] {
      for (const std::vector<std::uint8_t>& ci : chunk_indexes_) out.insert(out.end(), ci.begin(), ci.end());
    });
    const std::uint64_t summary_offset_start = summary_start + out.size();
    for (const Group& g : groups) {
      detail::McapRecord so;
      so.put(static_cast<std::uint8_t>(g.op)).put(g.start).put(g.length);
      so.append_to(out, detail::McapOp::kSummaryOffset);
    }
    // Footer: its CRC covers the summary section up to and including the
    // footer's summary_offset_start field.
    out.push_back(static_cast<std::uint8_t>(detail::McapOp::kFooter));
    detail::append_le(out, std::uint64_t{20});
    detail::append_le(out, summary_start);
    detail::append_le(out, summary_offset_start);
    detail::append_le(out, detail::mcap_crc32(out.data(), out.size()));
    out.insert(out.end(), detail::kMcapMagic.begin(), detail::kMcapMagic.end());
    file_.write(out);
    file_.close();
  }

 private:
  struct Channel {
    std::string topic;
    RosMessageType type;
    bool written = false;        ///< its Channel record is in the data section
    std::uint32_t sequence = 0;  ///< next Message sequence number
    std::uint64_t count = 0;     ///< messages written
  };

  [[nodiscard]] bool cdr() const noexcept { return config_.encoding == MessageEncoding::kCdr; }

  void check(std::size_t topic, RosMessageType type) const {
    if (closed_) throw ValueError("McapWriter::write: the file is closed");
    if (topic >= channels_.size()) {
      throw ValueError("McapWriter::write: topic id " + std::to_string(topic) + " was never added (" +
                       std::to_string(channels_.size()) + " topics)");
    }
    if (channels_[topic].type != type) {
      throw ValueError("McapWriter::write: topic '" + channels_[topic].topic + "' has type " +
                       detail::ros_type_info(channels_[topic].type).ros1_name + ", not " +
                       detail::ros_type_info(type).ros1_name);
    }
  }

  detail::McapRecord schema_record(RosMessageType type) const {
    const detail::RosTypeInfo& info = detail::ros_type_info(type);
    const std::string& text = cdr() ? info.ros2_definition : info.ros1_definition;
    detail::McapRecord r;
    r.put(schema_ids_[static_cast<std::size_t>(type)])
        .string(cdr() ? info.ros2_name : info.ros1_name)
        .string(cdr() ? "ros2msg" : "ros1msg");
    r.put(static_cast<std::uint32_t>(text.size()));
    r.raw(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
    return r;
  }

  detail::McapRecord channel_record(std::size_t c) const {
    detail::McapRecord r;
    r.put(static_cast<std::uint16_t>(c + 1))
        .put(schema_ids_[static_cast<std::size_t>(channels_[c].type)])
        .string(channels_[c].topic)
        .string(cdr() ? "cdr" : "ros1");
    if (!cdr()) {
      // rosbag-style connection metadata (what mcap's ros1 writers add).
      detail::McapRecord meta;
      meta.string("md5sum").string(detail::ros_type_info(channels_[c].type).md5sum);
      r.put(static_cast<std::uint32_t>(meta.content().size()));
      r.raw(meta.content().data(), meta.content().size());
    } else {
      r.put(std::uint32_t{0});
    }
    return r;
  }

  void write_serialized(std::size_t topic, std::int64_t log_time_ns) {
    if (log_time_ns < 0) {
      throw ValueError("McapWriter::write: log time " + std::to_string(log_time_ns) + " ns is negative");
    }
    Channel& ch = channels_[topic];
    const auto type = static_cast<std::size_t>(ch.type);
    if (schema_ids_[type] == 0) {
      schema_ids_[type] = ++schemas_;
    }
    if (!schema_written_[type]) {
      schema_record(ch.type).append_to(chunk_, detail::McapOp::kSchema);
      schema_written_[type] = true;
    }
    if (!ch.written) {
      channel_record(topic).append_to(chunk_, detail::McapOp::kChannel);
      ch.written = true;
    }
    if (index_.size() < channels_.size()) index_.resize(channels_.size());
    index_[topic].emplace_back(static_cast<std::uint64_t>(log_time_ns), static_cast<std::uint64_t>(chunk_.size()));
    // Message: channel_id, sequence, log_time, publish_time, data (the rest).
    chunk_.push_back(static_cast<std::uint8_t>(detail::McapOp::kMessage));
    detail::append_le(chunk_, static_cast<std::uint64_t>(2 + 4 + 8 + 8 + buffer_.size()));
    detail::append_le(chunk_, static_cast<std::uint16_t>(topic + 1));
    detail::append_le(chunk_, ch.sequence);
    detail::append_le(chunk_, static_cast<std::uint64_t>(log_time_ns));
    detail::append_le(chunk_, static_cast<std::uint64_t>(log_time_ns));
    chunk_.insert(chunk_.end(), buffer_.begin(), buffer_.end());
    const auto t = static_cast<std::uint64_t>(log_time_ns);
    chunk_start_ns_ = chunk_messages_ == 0 ? t : std::min(chunk_start_ns_, t);
    chunk_end_ns_ = chunk_messages_ == 0 ? t : std::max(chunk_end_ns_, t);
    start_ns_ = messages_ == 0 ? t : std::min(start_ns_, t);
    end_ns_ = messages_ == 0 ? t : std::max(end_ns_, t);
    ++chunk_messages_;
    ++messages_;
    ++ch.sequence;
    ++ch.count;
    if (chunk_.size() >= config_.chunk_bytes) flush_chunk();
  }

  void flush_chunk() {
    if (chunk_messages_ == 0) return;
    const std::uint32_t crc = config_.chunk_crc ? detail::mcap_crc32(chunk_.data(), chunk_.size()) : 0;
    std::vector<std::uint8_t> packed;
    const std::vector<std::uint8_t>* records = &chunk_;
    if (config_.compression == McapCompression::kZstd) {
      packed.resize(ZSTD_compressBound(chunk_.size()));
      const std::size_t n = ZSTD_compress(packed.data(), packed.size(), chunk_.data(), chunk_.size(), config_.zstd_level);
      if (ZSTD_isError(n) != 0U) {
        throw FormatError(semlio::detail::where(file_.path(), 0, std::string("zstd compression failed: ") +
                                                                     ZSTD_getErrorName(n)));
      }
      packed.resize(n);
      records = &packed;
    }
    const char* compression = config_.compression == McapCompression::kZstd ? "zstd" : "";
    detail::McapRecord chunk;
    chunk.put(chunk_start_ns_)
        .put(chunk_end_ns_)
        .put(static_cast<std::uint64_t>(chunk_.size()))
        .put(crc)
        .string(compression)
        .put(static_cast<std::uint64_t>(records->size()));
    chunk.raw(records->data(), records->size());
    std::vector<std::uint8_t> out;
    const std::uint64_t chunk_start = file_.position();
    const std::size_t chunk_length = chunk.append_to(out, detail::McapOp::kChunk);
    // MessageIndex per channel of the chunk, in channel order.
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;
    for (std::size_t c = 0; c < index_.size(); ++c) {
      if (index_[c].empty()) continue;
      index_offsets.emplace_back(static_cast<std::uint16_t>(c + 1), chunk_start + out.size());
      detail::McapRecord mi;
      mi.put(static_cast<std::uint16_t>(c + 1)).put(static_cast<std::uint32_t>(index_[c].size() * 16));
      for (const auto& [time, offset] : index_[c]) mi.put(time).put(offset);
      mi.append_to(out, detail::McapOp::kMessageIndex);
      index_[c].clear();
    }
    file_.write(out);
    detail::McapRecord ci;
    ci.put(chunk_start_ns_)
        .put(chunk_end_ns_)
        .put(chunk_start)
        .put(static_cast<std::uint64_t>(chunk_length))
        .put(static_cast<std::uint32_t>(index_offsets.size() * 10));
    for (const auto& [id, offset] : index_offsets) ci.put(id).put(offset);
    ci.put(static_cast<std::uint64_t>(out.size() - chunk_length))
        .string(compression)
        .put(static_cast<std::uint64_t>(records->size()))
        .put(static_cast<std::uint64_t>(chunk_.size()));
    chunk_indexes_.emplace_back();
    ci.append_to(chunk_indexes_.back(), detail::McapOp::kChunkIndex);
    chunk_.clear();
    chunk_messages_ = 0;
  }

  static const McapWriterConfig& checked(const McapWriterConfig& c) {
    if (c.chunk_bytes == 0) throw ConfigError("McapWriterConfig.chunk_bytes must be > 0, got 0");
    if (c.zstd_level == 0 || c.zstd_level < ZSTD_minCLevel() || c.zstd_level > ZSTD_maxCLevel()) {
      throw ConfigError("McapWriterConfig.zstd_level must be in [" + std::to_string(ZSTD_minCLevel()) + ", " +
                        std::to_string(ZSTD_maxCLevel()) + "] and not 0, got " + std::to_string(c.zstd_level));
    }
    return c;
  }

  McapWriterConfig config_;
  detail::OutFile file_;
  std::vector<Channel> channels_;
  std::array<std::uint16_t, 2> schema_ids_{};     ///< per RosMessageType: 0 = not used yet
  std::array<bool, 2> schema_written_{};          ///< Schema record already in the data section
  std::uint16_t schemas_ = 0;
  std::vector<std::vector<std::pair<std::uint64_t, std::uint64_t>>> index_;  ///< per channel: (log time, offset in chunk)
  std::vector<std::vector<std::uint8_t>> chunk_indexes_;  ///< ChunkIndex records for the summary
  std::vector<std::uint8_t> chunk_;                       ///< current chunk's records (uncompressed)
  std::vector<std::uint8_t> buffer_;                      ///< serialised message (reused)
  std::uint64_t chunk_start_ns_ = 0;
  std::uint64_t chunk_end_ns_ = 0;
  std::uint64_t start_ns_ = 0;
  std::uint64_t end_ns_ = 0;
  std::size_t chunk_messages_ = 0;
  std::size_t messages_ = 0;
  bool closed_ = false;
};

}  // namespace semlio::io
