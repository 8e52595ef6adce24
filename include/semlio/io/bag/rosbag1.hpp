#pragma once
/// \file
/// ROS 1 bag (format 2.0, http://wiki.ros.org/Bags/Format/2.0) reader with
/// the container shape of io/bag/message.hpp, without ROS.
///
/// A bag is "#ROSBAG V2.0\n" then records: a uint32 header length, header
/// fields (uint32 length, "name=value"), a uint32 data length, data. Ops:
/// 0x03 bag header (index_pos, conn_count, chunk_count), 0x05 chunk
/// (compression none/bz2/lz4, uncompressed size; data = connection and
/// message records), 0x04 index data after each chunk (per connection: time
/// and offset of each message inside the uncompressed chunk), and at
/// index_pos the 0x07 connection records and 0x06 chunk info records.
///
/// Opening reads only the index (connections, chunk infos, the index data
/// records after each chunk); messages are then read one chunk at a time
/// (two decompressed chunks cached), in log-time order even when the file
/// stores them out of order. A bag without an index (index_pos 0 or past the
/// end: an interrupted recording), or whose index cannot be read, is
/// re-indexed on the fly by decompressing
/// each chunk once at open; an incomplete record at the end of such a file
/// (the chunk being written when the recorder died) is skipped. Every
/// length, offset and size is checked against the file size or chunk size
/// with overflow-safe arithmetic: a corrupt or hostile file throws
/// FormatError, never reads out of bounds. Not thread-safe (one file cursor).

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/detail/decompress.hpp>
#include <semlio/io/bag/message.hpp>
#include <semlio/io/ros1_msgs.hpp>

namespace semlio::io {

namespace detail::rosbag1 {

inline constexpr std::string_view kMagic = "#ROSBAG V2.0\n";
inline constexpr std::uint8_t kOpMessage = 0x02;
inline constexpr std::uint8_t kOpBagHeader = 0x03;
inline constexpr std::uint8_t kOpIndexData = 0x04;
inline constexpr std::uint8_t kOpChunk = 0x05;
inline constexpr std::uint8_t kOpChunkInfo = 0x06;
inline constexpr std::uint8_t kOpConnection = 0x07;
/// Largest record header accepted [bytes]: rosbag headers are < 1 KiB; a
/// larger stated length is a lie (and would be allocated).
inline constexpr std::uint32_t kMaxHeaderBytes = 1U << 24;

/// The "name=value" fields of a record header (or of a connection record's data).
struct Fields {
  std::vector<std::pair<std::string, std::string>> items;

  [[nodiscard]] const std::string* find(std::string_view name) const {
    for (const auto& kv : items) {
      if (kv.first == name) return &kv.second;
    }
    return nullptr;
  }
};

/// Parses header fields from `n` bytes; `what` locates the record in messages.
inline Fields parse_fields(const std::uint8_t* p, std::size_t n, const std::string& what) {
  Fields out;
  std::size_t pos = 0;
  while (pos < n) {
    if (n - pos < 4) throw FormatError(what + ": header ends inside a field length");
    std::uint32_t len = 0;
    std::memcpy(&len, p + pos, 4);
    pos += 4;
    if (len > n - pos) {
      throw FormatError(what + ": header field of " + std::to_string(len) + " bytes overruns the header (" +
                        std::to_string(n - pos) + " bytes left)");
    }
    const auto* f = reinterpret_cast<const char*>(p + pos);
    const auto* eq = static_cast<const char*>(std::memchr(f, '=', len));
    if (eq == nullptr) throw FormatError(what + ": header field without '='");
    const auto name_len = static_cast<std::size_t>(eq - f);
    out.items.emplace_back(std::string(f, name_len), std::string(eq + 1, len - name_len - 1));
    pos += len;
  }
  return out;
}

/// The value of a required field.
inline const std::string& need(const Fields& h, std::string_view name, const std::string& what) {
  const std::string* v = h.find(name);
  if (v == nullptr) throw FormatError(what + ": header has no '" + std::string(name) + "' field");
  return *v;
}

/// A required little-endian integer field of exactly sizeof(T) bytes.
template <typename T>
T need_int(const Fields& h, std::string_view name, const std::string& what) {
  const std::string& v = need(h, name, what);
  if (v.size() != sizeof(T)) {
    throw FormatError(what + ": field '" + std::string(name) + "' is " + std::to_string(v.size()) +
                      " bytes, expected " + std::to_string(sizeof(T)));
  }
  T out;
  std::memcpy(&out, v.data(), sizeof(T));
  return out;
}

/// A ROS time (uint32 sec, uint32 nsec) as nanoseconds since the epoch.
inline std::int64_t time_ns(const std::uint8_t* p) {
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
  std::memcpy(&sec, p, 4);
  std::memcpy(&nsec, p + 4, 4);
  return std::int64_t{sec} * 1'000'000'000 + std::int64_t{nsec};
}

/// A required time field as nanoseconds.
inline std::int64_t need_time(const Fields& h, std::string_view name, const std::string& what) {
  const std::string& v = need(h, name, what);
  if (v.size() != 8) {
    throw FormatError(what + ": field '" + std::string(name) + "' is " + std::to_string(v.size()) +
                      " bytes, expected 8");
  }
  return time_ns(reinterpret_cast<const std::uint8_t*>(v.data()));
}

/// One record inside a memory buffer: header fields and where its data lies.
struct BufferRecord {
  Fields header;
  std::size_t data_offset = 0;  ///< in the buffer
  std::size_t data_len = 0;
  std::size_t end = 0;          ///< offset just past the record
};

/// Parses the record at `pos` of a buffer of `n` bytes (a chunk).
inline BufferRecord buffer_record(const std::uint8_t* p, std::size_t n, std::size_t pos, const std::string& what) {
  BufferRecord r;
  if (pos > n || n - pos < 4) throw FormatError(what + ": record header length beyond the chunk's end");
  std::uint32_t hlen = 0;
  std::memcpy(&hlen, p + pos, 4);
  pos += 4;
  if (hlen > n - pos || n - pos - hlen < 4) {
    throw FormatError(what + ": record header of " + std::to_string(hlen) + " bytes overruns the chunk");
  }
  r.header = parse_fields(p + pos, hlen, what);
  pos += hlen;
  std::uint32_t dlen = 0;
  std::memcpy(&dlen, p + pos, 4);
  pos += 4;
  if (dlen > n - pos) {
    throw FormatError(what + ": record data of " + std::to_string(dlen) + " bytes overruns the chunk (" +
                      std::to_string(n - pos) + " bytes left)");
  }
  r.data_offset = pos;
  r.data_len = dlen;
  r.end = pos + dlen;
  return r;
}

/// The op code of a record header.
inline std::uint8_t op(const Fields& h, const std::string& what) { return need_int<std::uint8_t>(h, "op", what); }

/// Chunk compression.
enum class Compression : std::uint8_t { kNone, kBz2, kLz4 };

/// A chunk record: where its (compressed) data lies in the file.
struct Chunk {
  std::uint64_t pos = 0;          ///< offset of the chunk record
  std::uint64_t data_offset = 0;  ///< offset of its data
  std::uint64_t data_len = 0;     ///< bytes of (compressed) data
  std::uint64_t size = 0;         ///< uncompressed bytes
  Compression compression = Compression::kNone;
};

/// One message in the index.
struct Entry {
  std::int64_t time_ns = 0;
  std::uint32_t chunk = 0;   ///< index into the reader's chunks
  std::uint32_t offset = 0;  ///< record offset inside the uncompressed chunk
  std::uint32_t conn = 0;    ///< connection id
};

}  // namespace detail::rosbag1

/// Reads a ROS 1 bag (format 2.0); see the file comment. Messages come out
/// as ROS 1 serialised bytes (MessageEncoding::kRos1): deserialise them with
/// io/ros1_msgs.hpp. Not thread-safe.
class RosBag1Reader {
 public:
  /// Opens `path` and reads its index (or re-indexes it). Throws IoError when
  /// it cannot be opened, FormatError when it is not a valid bag.
  explicit RosBag1Reader(const std::string& path) : path_(path) {
    file_.open(path, std::ios::binary);
    if (!file_) throw IoError(path + ": cannot open ROS bag");
    file_.seekg(0, std::ios::end);
    const std::streamoff end = file_.tellg();
    if (end < 0) throw IoError(path + ": cannot determine the file size");
    file_size_ = static_cast<std::uint64_t>(end);
    open_index();
    select({});
  }

  /// Opens a bag held in memory (copied; `name` stands for the path in error
  /// messages): the same reader as the path constructor, with reads served
  /// from the copy. Throws FormatError when it is not a valid bag.
  static RosBag1Reader from_bytes(std::string_view bytes, const std::string& name) {
    return RosBag1Reader(InMemory{}, bytes, name);
  }

  /// Topics of the bag, in the order of their first connection id.
  [[nodiscard]] const std::vector<BagTopic>& topics() const noexcept { return topics_; }

  /// Restarts reading with only these topics (empty: all). Throws ValueError
  /// for a name the bag does not have.
  void select(const std::vector<std::string>& topic_names) {
    std::vector<bool> want(topics_.size(), topic_names.empty());
    for (const std::string& name : topic_names) {
      const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == name; });
      if (it == topics_.end()) {
        std::string have;
        for (const BagTopic& t : topics_) have += (have.empty() ? "" : ", ") + t.name;
        throw ValueError(path_ + ": no topic '" + name + "' in the bag (it has: " + have + ")");
      }
      want[static_cast<std::size_t>(it - topics_.begin())] = true;
    }
    selected_.clear();
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (want[conn_topic_.at(entries_[i].conn)]) selected_.push_back(i);
    }
    cursor_ = 0;
  }

  /// The next selected message in log-time order (ties in file order); false at the end.
  bool next(BagMessage& out) {
    if (cursor_ >= selected_.size()) return false;
    const detail::rosbag1::Entry& e = entries_[selected_[cursor_++]];
    const std::vector<std::uint8_t>& chunk = load_chunk(e.chunk);
    const std::string what = where_chunk(e.chunk) + ", message at offset " + std::to_string(e.offset);
    const detail::rosbag1::BufferRecord r = detail::rosbag1::buffer_record(chunk.data(), chunk.size(), e.offset, what);
    if (detail::rosbag1::op(r.header, what) != detail::rosbag1::kOpMessage) {
      throw FormatError(what + ": the index points at a record that is not a message");
    }
    const auto conn = detail::rosbag1::need_int<std::uint32_t>(r.header, "conn", what);
    if (conn != e.conn) {
      throw FormatError(what + ": message of connection " + std::to_string(conn) + " where the index says " +
                        std::to_string(e.conn));
    }
    out.topic = conn_topic_.at(conn);
    out.log_time_ns = e.time_ns;
    out.data.assign(chunk.data() + r.data_offset, chunk.data() + r.data_offset + r.data_len);
    return true;
  }

  /// True when the bag had no usable index and was re-indexed at open.
  [[nodiscard]] bool reindexed() const noexcept { return reindexed_; }
  /// Number of chunk records.
  [[nodiscard]] std::size_t chunk_count() const noexcept { return chunks_.size(); }
  /// The path given to the constructor.
  [[nodiscard]] const std::string& path() const noexcept { return path_; }

 private:
  struct InMemory {};
  RosBag1Reader(InMemory, std::string_view bytes, const std::string& name)
      : path_(name), memory_(bytes), in_memory_(true) {
    file_size_ = memory_.size();
    open_index();
    select({});
  }

  /// A record read from the file: header fields and where its data lies.
  struct FileRecord {
    detail::rosbag1::Fields header;
    std::uint64_t data_offset = 0;
    std::uint64_t data_len = 0;
    std::uint64_t end = 0;
  };

  [[nodiscard]] std::string where(std::uint64_t pos) const {
    return path_ + ": record at byte " + std::to_string(pos);
  }
  [[nodiscard]] std::string where_chunk(std::uint32_t chunk) const {
    return path_ + ": chunk at byte " + std::to_string(chunks_[chunk].pos);
  }

  /// Reads `n` bytes at `pos` into `out`; FormatError when they are not all in the file.
  void read_at(std::uint64_t pos, std::uint64_t n, std::uint8_t* out, const std::string& what) {
    if (pos > file_size_ || n > file_size_ - pos) {
      throw FormatError(what + ": needs " + std::to_string(n) + " bytes at byte " + std::to_string(pos) +
                        ", beyond the end of the " + std::to_string(file_size_) + "-byte file (truncated?)");
    }
    if (in_memory_) {
      if (n != 0) std::memcpy(out, memory_.data() + pos, static_cast<std::size_t>(n));
      return;
    }
    file_.clear();
    file_.seekg(static_cast<std::streamoff>(pos));
    file_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(n));
    if (!file_) throw IoError(what + ": read error at byte " + std::to_string(pos));
  }

  /// Reads the header of the record at `pos` and checks that its data lies in the file.
  FileRecord file_record(std::uint64_t pos) {
    const std::string what = where(pos);
    FileRecord r;
    std::uint32_t hlen = 0;
    read_at(pos, 4, reinterpret_cast<std::uint8_t*>(&hlen), what);
    if (hlen > detail::rosbag1::kMaxHeaderBytes) {
      throw FormatError(what + ": header length " + std::to_string(hlen) + " is not plausible (limit " +
                        std::to_string(detail::rosbag1::kMaxHeaderBytes) + ")");
    }
    // Checked before the buffer grows: a lying length in a tiny file must not
    // cost a 16 MiB allocation (pos + 4 <= file_size_ after the read above).
    if (hlen > file_size_ - (pos + 4)) {
      throw FormatError(what + ": header of " + std::to_string(hlen) + " bytes at byte " + std::to_string(pos + 4) +
                        " runs beyond the end of the " + std::to_string(file_size_) + "-byte file (truncated?)");
    }
    scratch_.resize(hlen);
    read_at(pos + 4, hlen, scratch_.data(), what);
    r.header = detail::rosbag1::parse_fields(scratch_.data(), hlen, what);
    std::uint32_t dlen = 0;
    read_at(pos + 4 + hlen, 4, reinterpret_cast<std::uint8_t*>(&dlen), what);
    r.data_offset = pos + 8 + hlen;
    r.data_len = dlen;
    if (r.data_len > file_size_ - r.data_offset) {  // data_offset <= file_size_ after the read above
      throw FormatError(what + ": data of " + std::to_string(dlen) + " bytes runs past the end of the file (" +
                        std::to_string(file_size_ - r.data_offset) + " bytes left; truncated?)");
    }
    r.end = r.data_offset + r.data_len;
    return r;
  }

  /// Reads the data of a record into a vector.
  std::vector<std::uint8_t> record_data(const FileRecord& r, std::uint64_t pos) {
    std::vector<std::uint8_t> data(static_cast<std::size_t>(r.data_len));
    read_at(r.data_offset, r.data_len, data.data(), where(pos));
    return data;
  }

  /// Magic, bag header, then the index or a re-index.
  void open_index() {
    std::array<std::uint8_t, detail::rosbag1::kMagic.size()> magic{};
    if (file_size_ < magic.size()) throw FormatError(path_ + ": " + std::to_string(file_size_) + " bytes, not a ROS bag");
    read_at(0, magic.size(), magic.data(), path_);
    const std::string_view got(reinterpret_cast<const char*>(magic.data()), magic.size());
    if (got != detail::rosbag1::kMagic) {
      if (got.substr(0, 9) == "#ROSBAG V") {
        throw FormatError(path_ + ": bag format '" + std::string(got.substr(1, 11)) +
                          "' is unsupported (only V2.0; migrate old bags with `rosbag fix`)");
      }
      throw FormatError(path_ + ": not a ROS bag (no '#ROSBAG V2.0' line)");
    }
    const std::uint64_t header_pos = magic.size();
    const FileRecord h = file_record(header_pos);
    const std::string what = where(header_pos);
    if (detail::rosbag1::op(h.header, what) != detail::rosbag1::kOpBagHeader) {
      throw FormatError(what + ": the first record is not the bag header");
    }
    const auto index_pos = detail::rosbag1::need_int<std::uint64_t>(h.header, "index_pos", what);
    // index_pos 0: the recorder never finished the file; past the end: the
    // index was cut off. Either way the chunks are all there is.
    if (index_pos == 0 || index_pos >= file_size_ || index_pos < h.end) {
      reindex(h.end);
    } else {
      try {
        read_index(index_pos);
      } catch (const FormatError&) {
        // A damaged index section (e.g. a copy cut short inside it): the
        // chunks may still be whole, and re-indexing reads only those.
        topics_.clear();
        conn_topic_.clear();
        chunks_.clear();
        entries_.clear();
        for (Slot& slot : cache_) slot.valid = false;
        reindex(h.end);
      }
    }
    // Log-time order; ties in file order (chunks are in file order, offsets within a chunk).
    std::sort(entries_.begin(), entries_.end(), [](const auto& a, const auto& b) {
      if (a.time_ns != b.time_ns) return a.time_ns < b.time_ns;
      if (a.chunk != b.chunk) return a.chunk < b.chunk;
      return a.offset < b.offset;
    });
    for (const auto& e : entries_) ++topics_[conn_topic_.at(e.conn)].message_count;
  }

  /// Adds a connection (header: conn, topic; data: type, md5sum, ...); repeats are ignored.
  void add_connection(const detail::rosbag1::Fields& header, const std::uint8_t* data, std::size_t n,
                      const std::string& what) {
    const auto conn = detail::rosbag1::need_int<std::uint32_t>(header, "conn", what);
    const std::string& topic = detail::rosbag1::need(header, "topic", what);
    const detail::rosbag1::Fields d = detail::rosbag1::parse_fields(data, n, what + " (connection data)");
    const std::string& type = detail::rosbag1::need(d, "type", what);
    const std::string& md5 = detail::rosbag1::need(d, "md5sum", what);
    check_ros1_md5sum(type, md5, what + " (topic " + topic + ")");
    if (conn_topic_.count(conn) != 0) return;  // the same connection in a chunk and in the index
    auto it = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == topic; });
    if (it == topics_.end()) {
      topics_.push_back(BagTopic{topic, type, MessageEncoding::kRos1, 0});
      it = topics_.end() - 1;
    } else if (it->type != type) {
      throw FormatError(what + ": topic " + topic + " is recorded as both " + it->type + " and " + type);
    }
    conn_topic_[conn] = static_cast<std::size_t>(it - topics_.begin());
  }

  /// Parses a chunk record header into chunks_ (without reading its data).
  std::uint32_t add_chunk(const FileRecord& r, std::uint64_t pos) {
    const std::string what = where(pos);
    const std::string& comp = detail::rosbag1::need(r.header, "compression", what);
    detail::rosbag1::Chunk c;
    c.pos = pos;
    c.data_offset = r.data_offset;
    c.data_len = r.data_len;
    c.size = detail::rosbag1::need_int<std::uint32_t>(r.header, "size", what);
    if (comp == "none") {
      c.compression = detail::rosbag1::Compression::kNone;
      if (c.size != c.data_len) {
        throw FormatError(what + ": uncompressed chunk states size " + std::to_string(c.size) + " but holds " +
                          std::to_string(c.data_len) + " bytes");
      }
    } else if (comp == "bz2") {
      c.compression = detail::rosbag1::Compression::kBz2;
    } else if (comp == "lz4") {
      c.compression = detail::rosbag1::Compression::kLz4;
      // LZ4 expands at most ~255:1: a larger stated size is a lie, refused
      // before the output buffer is allocated for it.
      if (c.size / 256 > c.data_len + 64) {
        throw FormatError(what + ": lz4 chunk states " + std::to_string(c.size) + " bytes from " +
                          std::to_string(c.data_len) + " compressed bytes (more than LZ4 can expand)");
      }
    } else {
      throw FormatError(what + ": unknown chunk compression '" + comp + "' (expected none, bz2 or lz4)");
    }
    if (chunks_.size() >= std::numeric_limits<std::uint32_t>::max()) throw FormatError(what + ": too many chunks");
    chunks_.push_back(c);
    return static_cast<std::uint32_t>(chunks_.size() - 1);
  }

  /// Reads the index section at index_pos and each chunk's index data records.
  void read_index(std::uint64_t index_pos) {
    std::vector<std::uint64_t> chunk_pos;
    std::uint64_t pos = index_pos;
    while (pos < file_size_) {
      const FileRecord r = file_record(pos);
      const std::string what = where(pos);
      const std::uint8_t op = detail::rosbag1::op(r.header, what);
      if (op == detail::rosbag1::kOpConnection) {
        const std::vector<std::uint8_t> data = record_data(r, pos);
        add_connection(r.header, data.data(), data.size(), what);
      } else if (op == detail::rosbag1::kOpChunkInfo) {
        const auto ver = detail::rosbag1::need_int<std::uint32_t>(r.header, "ver", what);
        if (ver != 1) throw FormatError(what + ": chunk info version " + std::to_string(ver) + " (expected 1)");
        chunk_pos.push_back(detail::rosbag1::need_int<std::uint64_t>(r.header, "chunk_pos", what));
      } else {
        throw FormatError(what + ": op " + std::to_string(op) + " in the index section (expected connection or chunk info)");
      }
      pos = r.end;
    }
    std::sort(chunk_pos.begin(), chunk_pos.end());
    chunk_pos.erase(std::unique(chunk_pos.begin(), chunk_pos.end()), chunk_pos.end());
    for (const std::uint64_t cp : chunk_pos) {
      const FileRecord c = file_record(cp);
      if (detail::rosbag1::op(c.header, where(cp)) != detail::rosbag1::kOpChunk) {
        throw FormatError(where(cp) + ": chunk info points at a record that is not a chunk");
      }
      const std::uint32_t chunk = add_chunk(c, cp);
      // The chunk's index data records follow it, one per connection.
      std::uint64_t ipos = c.end;
      while (ipos < index_pos) {
        const FileRecord r = file_record(ipos);
        const std::string what = where(ipos);
        if (detail::rosbag1::op(r.header, what) != detail::rosbag1::kOpIndexData) break;
        read_index_data(r, ipos, chunk);
        ipos = r.end;
      }
    }
  }

  /// Index data record: ver 1, conn, count; data = count x (time, offset).
  void read_index_data(const FileRecord& r, std::uint64_t pos, std::uint32_t chunk) {
    const std::string what = where(pos);
    const auto ver = detail::rosbag1::need_int<std::uint32_t>(r.header, "ver", what);
    if (ver != 1) throw FormatError(what + ": index data version " + std::to_string(ver) + " (expected 1)");
    const auto conn = detail::rosbag1::need_int<std::uint32_t>(r.header, "conn", what);
    const auto count = detail::rosbag1::need_int<std::uint32_t>(r.header, "count", what);
    if (std::uint64_t{count} * 12 != r.data_len) {
      throw FormatError(what + ": index data states " + std::to_string(count) + " entries but holds " +
                        std::to_string(r.data_len) + " bytes (12 per entry)");
    }
    if (conn_topic_.count(conn) == 0) {
      throw FormatError(what + ": index data of connection " + std::to_string(conn) + ", which has no connection record");
    }
    const std::vector<std::uint8_t> data = record_data(r, pos);
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint8_t* p = data.data() + 12 * i;
      std::uint32_t offset = 0;
      std::memcpy(&offset, p + 8, 4);
      if (offset >= chunks_[chunk].size) {
        throw FormatError(what + ": message offset " + std::to_string(offset) + " beyond the chunk's " +
                          std::to_string(chunks_[chunk].size) + " bytes");
      }
      entries_.push_back({detail::rosbag1::time_ns(p), chunk, offset, conn});
    }
  }

  /// Walks every chunk from `pos` on, collecting connections and messages.
  void reindex(std::uint64_t pos) {
    reindexed_ = true;
    while (pos < file_size_) {
      FileRecord r;
      try {
        r = file_record(pos);
      } catch (const FormatError&) {
        // An incomplete record at the end: the one being written when the
        // recording stopped. What precedes it is complete.
        break;
      }
      const std::string what = where(pos);
      const std::uint8_t op = detail::rosbag1::op(r.header, what);
      if (op == detail::rosbag1::kOpChunk) {
        const std::uint32_t chunk = add_chunk(r, pos);
        const std::vector<std::uint8_t>& data = load_chunk(chunk);
        std::size_t q = 0;
        while (q < data.size()) {
          const std::string inner = where_chunk(chunk) + ", record at offset " + std::to_string(q);
          const detail::rosbag1::BufferRecord br = detail::rosbag1::buffer_record(data.data(), data.size(), q, inner);
          const std::uint8_t iop = detail::rosbag1::op(br.header, inner);
          if (iop == detail::rosbag1::kOpConnection) {
            add_connection(br.header, data.data() + br.data_offset, br.data_len, inner);
          } else if (iop == detail::rosbag1::kOpMessage) {
            const auto conn = detail::rosbag1::need_int<std::uint32_t>(br.header, "conn", inner);
            if (conn_topic_.count(conn) == 0) {
              throw FormatError(inner + ": message of connection " + std::to_string(conn) + " before its connection record");
            }
            const std::int64_t t = detail::rosbag1::need_time(br.header, "time", inner);
            entries_.push_back({t, chunk, static_cast<std::uint32_t>(q), conn});
          } else {
            throw FormatError(inner + ": op " + std::to_string(iop) + " inside a chunk");
          }
          q = br.end;
        }
      } else if (op == detail::rosbag1::kOpConnection) {
        const std::vector<std::uint8_t> data = record_data(r, pos);
        add_connection(r.header, data.data(), data.size(), what);
      } else if (op != detail::rosbag1::kOpIndexData && op != detail::rosbag1::kOpChunkInfo) {
        throw FormatError(what + ": unexpected op " + std::to_string(op));
      }
      pos = r.end;
    }
  }

  /// The uncompressed bytes of a chunk, from the two-slot cache or the file.
  const std::vector<std::uint8_t>& load_chunk(std::uint32_t chunk) {
    for (Slot& s : cache_) {
      if (s.valid && s.chunk == chunk) {
        s.used = ++clock_;
        return s.bytes;
      }
    }
    Slot& s = cache_[0].used <= cache_[1].used ? cache_[0] : cache_[1];
    s.valid = false;  // stays invalid if decompression throws
    const detail::rosbag1::Chunk& c = chunks_[chunk];
    const std::string what = where_chunk(chunk);
    detail::check_chunk_size(c.size, what);
    if (c.compression == detail::rosbag1::Compression::kNone) {
      s.bytes.resize(static_cast<std::size_t>(c.data_len));
      read_at(c.data_offset, c.data_len, s.bytes.data(), what);
    } else {
      compressed_.resize(static_cast<std::size_t>(c.data_len));
      read_at(c.data_offset, c.data_len, compressed_.data(), what);
      if (c.compression == detail::rosbag1::Compression::kBz2) {
        detail::decompress_bz2(compressed_.data(), compressed_.size(), c.size, s.bytes, what);
      } else {
        detail::decompress_lz4_frame(compressed_.data(), compressed_.size(), c.size, s.bytes, what);
      }
    }
    s.chunk = chunk;
    s.valid = true;
    s.used = ++clock_;
    return s.bytes;
  }

  /// One decompressed chunk of the cache.
  struct Slot {
    std::vector<std::uint8_t> bytes;
    std::uint32_t chunk = 0;
    std::uint64_t used = 0;
    bool valid = false;
  };

  std::string path_;
  std::ifstream file_;
  std::string memory_;     ///< the whole file when opened with from_bytes
  bool in_memory_ = false;  ///< reads come from memory_, not file_
  std::uint64_t file_size_ = 0;
  std::vector<BagTopic> topics_;
  std::map<std::uint32_t, std::size_t> conn_topic_;  ///< connection id -> topic index
  std::vector<detail::rosbag1::Chunk> chunks_;       ///< in file order
  std::vector<detail::rosbag1::Entry> entries_;      ///< every message, sorted by time
  std::vector<std::size_t> selected_;                ///< indices into entries_
  std::size_t cursor_ = 0;
  bool reindexed_ = false;
  std::array<Slot, 2> cache_{};
  std::uint64_t clock_ = 0;
  std::vector<std::uint8_t> scratch_;     ///< record headers
  std::vector<std::uint8_t> compressed_;  ///< compressed chunk bytes
};

}  // namespace semlio::io
