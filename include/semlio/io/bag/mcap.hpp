#pragma once
/// \file
/// MCAP reader (mcap.dev/spec, version 0) with the shape of every bag reader
/// (io/bag/message.hpp): topics, select, next in non-decreasing log time.
///
/// File: magic, records <uint8 opcode><uint64 length><content>, magic.
/// Integers little-endian, strings <uint32 length><bytes>. Two ways in:
///  - Indexed files (Footer.summary_start != 0 and the summary holds the
///    Channels, one Statistics and a ChunkIndex per chunk): channels, types
///    and message counts come from the summary; chunks are read lazily in
///    the order of their ChunkIndex.message_start_time.
///  - Everything else (streamed files without summary, unchunked files, a
///    summary without chunk indexes or statistics, a file cut off without
///    its footer): the data section is scanned once at open, decompressing
///    each chunk once to learn its channels, message counts and exact time
///    range; only offsets are kept.
/// next() merges the selected channels' messages of all chunks with a heap
/// keyed by (log time, file order): a chunk is opened when its start time is
/// reached, so chunks that overlap in time still come out sorted. At most
/// two decompressed chunks are cached. Chunk compression "", "zstd", "lz4"
/// (LZ4 frame); a chunk's uncompressed CRC-32 is verified when non-zero.
///
/// Channels with message encoding "cdr" (profile ros2) are topics with
/// MessageEncoding::kCdr, "ros1" ones kRos1; channels of other encodings
/// (json, protobuf, ...) are not listed. Channels sharing a topic name are
/// one topic. Every length and offset read from the file is checked against
/// the bytes present with overflow-safe arithmetic: a bad file throws
/// FormatError naming the file and the byte offset, never over-reads.
/// A rosbag2 folder with one .mcap file (ROS 2 Jazzy's default storage)
/// opens like the file itself.
/// Thread safety: none (one reader per thread).

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define SEMLIO_MCAP_CRC_PCLMUL 1
#else
#define SEMLIO_MCAP_CRC_PCLMUL 0
#endif

#include <semlio/core/error.hpp>
#include <semlio/io/bag/detail/decompress.hpp>
#include <semlio/io/bag/message.hpp>

namespace semlio::io {

/// Options of McapReader.
struct McapReaderConfig {
  bool verify_chunk_crc = true;  ///< check each chunk's uncompressed CRC-32 when the writer stored one
};

namespace detail::mcap {

inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
inline constexpr std::uint64_t kRecordHeaderBytes = 9;  ///< opcode + uint64 length
inline constexpr std::uint64_t kFooterContentBytes = 20;

enum Op : std::uint8_t {
  kOpHeader = 0x01,
  kOpFooter = 0x02,
  kOpSchema = 0x03,
  kOpChannel = 0x04,
  kOpMessage = 0x05,
  kOpChunk = 0x06,
  kOpChunkIndex = 0x08,
  kOpStatistics = 0x0B,
  kOpDataEnd = 0x0F,
};

/// CRC-32 (IEEE 802.3 / ISO-HDLC, zlib's) register update, slice-by-16:
/// `c` is the inverted running value (0xFFFFFFFF at the start), returned
/// the same way. The portable path and the tail of the PCLMUL one.
inline std::uint32_t crc32_update_sliced(std::uint32_t c, const std::uint8_t* p, std::size_t n) {
  static const auto t = [] {
    std::array<std::array<std::uint32_t, 256>, 16> tables{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t r = i;
      for (int k = 0; k < 8; ++k) r = (r & 1U) != 0 ? 0xEDB88320U ^ (r >> 1) : r >> 1;
      tables[0][i] = r;
    }
    for (std::size_t i = 0; i < 256; ++i) {
      for (std::size_t s = 1; s < 16; ++s) tables[s][i] = (tables[s - 1][i] >> 8) ^ tables[0][tables[s - 1][i] & 0xFFU];
    }
    return tables;
  }();
  static_assert(std::endian::native == std::endian::little, "the slice-by-16 CRC assumes a little-endian host");
  while (n >= 16) {
    std::array<std::uint32_t, 4> w{};
    std::memcpy(w.data(), p, 16);
    w[0] ^= c;
    c = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const std::size_t s = 15 - 4 * k;  // word k's byte b is folded with table 15 - 4k - b
      c ^= t[s][w[k] & 0xFFU] ^ t[s - 1][(w[k] >> 8) & 0xFFU] ^ t[s - 2][(w[k] >> 16) & 0xFFU] ^ t[s - 3][w[k] >> 24];
    }
    p += 16;
    n -= 16;
  }
  while (n-- > 0) c = t[0][(c ^ *p++) & 0xFFU] ^ (c >> 8);
  return c;
}

#if SEMLIO_MCAP_CRC_PCLMUL
/// 16 unaligned bytes (for crc32_update_pclmul; lambdas would not inherit its target).
__attribute__((target("pclmul,sse4.1"))) inline __m128i crc_load(const std::uint8_t* q) {
  return _mm_loadu_si128(reinterpret_cast<const __m128i*>(q));
}
/// Folds lane x forward by the distance whose constants k holds, onto `next`.
__attribute__((target("pclmul,sse4.1"))) inline __m128i crc_fold(__m128i x, __m128i k, __m128i next) {
  return _mm_xor_si128(_mm_xor_si128(_mm_clmulepi64_si128(x, k, 0x11), _mm_clmulepi64_si128(x, k, 0x00)), next);
}

/// The same register update by carry-less multiplication (Gopal et al., "Fast
/// CRC Computation for Generic Polynomials Using PCLMULQDQ Instruction",
/// Intel 2009; the bit-reflected constants of its appendix, as zlib-ng and
/// Chromium's zlib use them): four 128-bit lanes folded 64 bytes at a time,
/// then Barrett reduction. n >= 64 and a multiple of 16.
__attribute__((target("pclmul,sse4.1"))) inline std::uint32_t crc32_update_pclmul(std::uint32_t c,
                                                                                   const std::uint8_t* p,
                                                                                   std::size_t n) {
  const __m128i k1k2 = _mm_set_epi64x(0x01c6e41596, 0x0154442bd4);
  const __m128i k3k4 = _mm_set_epi64x(0x00ccaa009e, 0x01751997d0);
  const __m128i k5k0 = _mm_set_epi64x(0, 0x0163cd6124);
  const __m128i poly = _mm_set_epi64x(0x01f7011641, 0x01db710641);
  __m128i x1 = _mm_xor_si128(crc_load(p), _mm_cvtsi32_si128(static_cast<int>(c)));
  __m128i x2 = crc_load(p + 16);
  __m128i x3 = crc_load(p + 32);
  __m128i x4 = crc_load(p + 48);
  p += 64;
  n -= 64;
  for (; n >= 64; p += 64, n -= 64) {
    x1 = crc_fold(x1, k1k2, crc_load(p));
    x2 = crc_fold(x2, k1k2, crc_load(p + 16));
    x3 = crc_fold(x3, k1k2, crc_load(p + 32));
    x4 = crc_fold(x4, k1k2, crc_load(p + 48));
  }
  x1 = crc_fold(x1, k3k4, x2);  // four lanes into one
  x1 = crc_fold(x1, k3k4, x3);
  x1 = crc_fold(x1, k3k4, x4);
  for (; n >= 16; p += 16, n -= 16) x1 = crc_fold(x1, k3k4, crc_load(p));
  // 128 -> 64 bits.
  const __m128i mask32 = _mm_setr_epi32(~0, 0, ~0, 0);
  x1 = _mm_xor_si128(_mm_srli_si128(x1, 8), _mm_clmulepi64_si128(x1, k3k4, 0x10));
  x1 = _mm_xor_si128(_mm_clmulepi64_si128(_mm_and_si128(x1, mask32), k5k0, 0x00), _mm_srli_si128(x1, 4));
  // Barrett reduction to 32 bits.
  __m128i r = _mm_clmulepi64_si128(_mm_and_si128(x1, mask32), poly, 0x10);
  r = _mm_clmulepi64_si128(_mm_and_si128(r, mask32), poly, 0x00);
  return static_cast<std::uint32_t>(_mm_extract_epi32(_mm_xor_si128(x1, r), 1));
}
#endif

/// CRC-32 (IEEE 802.3 / ISO-HDLC, zlib's) of n bytes: carry-less
/// multiplication on x86-64 CPUs with PCLMULQDQ and SSE4.1 (checked once at
/// run time), else the slice-by-16 tables. A chunk of a 120k-point cloud is
/// ~2 MB, verified by default on every read.
inline std::uint32_t crc32(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFU;
#if SEMLIO_MCAP_CRC_PCLMUL
  static const bool have_pclmul = __builtin_cpu_supports("pclmul") && __builtin_cpu_supports("sse4.1");
  if (have_pclmul && n >= 64) {
    const std::size_t whole = n & ~std::size_t{15};
    c = crc32_update_pclmul(c, p, whole);
    p += whole;
    n -= whole;
  }
#endif
  return crc32_update_sliced(c, p, n) ^ 0xFFFFFFFFU;
}

/// Bounds-checked little-endian reader over one record's content.
class Cursor {
 public:
  /// `base` is the file offset (or chunk offset) of data[0], for messages.
  Cursor(const std::uint8_t* data, std::uint64_t size, std::uint64_t base, const std::string& what)
      : data_(data), size_(size), base_(base), what_(what) {}

  [[noreturn]] void fail(const std::string& msg) const {
    throw FormatError(what_ + ", byte " + std::to_string(base_ + pos_) + ": " + msg);
  }
  void need(std::uint64_t n, const char* field) const {
    if (n > size_ - pos_) {
      fail("truncated reading '" + std::string(field) + "' (needs " + std::to_string(n) + " bytes, " +
           std::to_string(size_ - pos_) + " left)");
    }
  }
  std::uint8_t u8(const char* field) { return fixed<std::uint8_t>(field); }
  std::uint16_t u16(const char* field) { return fixed<std::uint16_t>(field); }
  std::uint32_t u32(const char* field) { return fixed<std::uint32_t>(field); }
  std::uint64_t u64(const char* field) { return fixed<std::uint64_t>(field); }
  std::string string(const char* field) {
    const std::uint32_t n = u32(field);
    need(n, field);
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return s;
  }
  /// Skips a <uint32 byte length><bytes> field (a map or schema data).
  void skip_prefixed(const char* field) { skip(u32(field), field); }
  void skip(std::uint64_t n, const char* field) {
    need(n, field);
    pos_ += n;
  }
  [[nodiscard]] std::uint64_t pos() const noexcept { return pos_; }
  [[nodiscard]] std::uint64_t remaining() const noexcept { return size_ - pos_; }
  [[nodiscard]] const std::uint8_t* here() const noexcept { return data_ + pos_; }

 private:
  template <typename T>
  T fixed(const char* field) {
    static_assert(std::endian::native == std::endian::little, "the MCAP reader assumes a little-endian host");
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }

  const std::uint8_t* data_;
  std::uint64_t size_;
  std::uint64_t pos_ = 0;
  std::uint64_t base_;
  const std::string& what_;
};

/// A Channel record (the fields semlio uses).
struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;
};

/// Where a chunk is and what it covers.
struct ChunkRef {
  std::uint64_t start_ns = 0;           ///< earliest message log time in it
  std::uint64_t record_offset = 0;      ///< file offset of its opcode
  std::vector<std::uint16_t> channels;  ///< channels with messages in it (sorted); empty and !channels_known: unknown
  bool channels_known = false;
};

/// A message outside chunks.
struct LooseMessage {
  std::uint64_t log_time_ns = 0;
  std::uint64_t record_offset = 0;  ///< file offset of its opcode
  std::uint64_t data_offset = 0;    ///< file offset of its data
  std::uint64_t data_length = 0;
  std::uint16_t channel = 0;
};

/// One heap entry: a chunk to open, or a message to hand out.
struct Item {
  std::uint64_t time_ns = 0;
  std::uint8_t kind = 0;             ///< 0 = open chunk, 1 = message (chunks open before same-time messages)
  std::uint64_t source = 0;          ///< file offset of the chunk or loose message record (file order)
  std::uint64_t inner = 0;           ///< offset inside the decompressed chunk (file order within it)
  std::size_t chunk = 0;             ///< index into chunks_, or kLoose
  std::uint64_t data_offset = 0;     ///< in the decompressed chunk, or in the file for loose messages
  std::uint64_t data_length = 0;
  std::uint16_t channel = 0;
};
inline constexpr std::size_t kLoose = std::numeric_limits<std::size_t>::max();

/// Heap order: the smallest (time, kind, source, inner) on top.
struct Later {
  bool operator()(const Item& a, const Item& b) const noexcept {
    if (a.time_ns != b.time_ns) return a.time_ns > b.time_ns;
    if (a.kind != b.kind) return a.kind > b.kind;
    if (a.source != b.source) return a.source > b.source;
    return a.inner > b.inner;
  }
};

/// `path` itself, or for a folder (a rosbag2 bag) its only *.mcap file.
inline std::string resolve_path(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return path;
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(path, ec)) {
    if (e.path().extension() == ".mcap") files.push_back(e.path());
  }
  if (files.empty()) throw IoError(path + ": a folder without an .mcap file");
  if (files.size() > 1) {
    throw FormatError(path + ": a bag split into " + std::to_string(files.size()) +
                      " .mcap files; open each file with its own McapReader");
  }
  return files.front().string();
}

}  // namespace detail::mcap

/// Reads an MCAP file's messages in log-time order (see the file comment).
class McapReader {
 public:
  using Config = McapReaderConfig;

  /// Opens `path` and reads its summary (or scans it). `path` may also be a
  /// rosbag2 bag folder holding exactly one .mcap file (ROS 2 Jazzy's default
  /// storage; split bags of several files are rejected). Throws IoError when
  /// it cannot be opened, FormatError when it is not a valid MCAP file.
  explicit McapReader(const std::string& path, const Config& config = {})
      : path_(detail::mcap::resolve_path(path)), config_(config) {
    file_.open(path_, std::ios::binary);
    if (!file_) throw IoError(path_ + ": cannot open MCAP file");
    file_.seekg(0, std::ios::end);
    const std::streamoff end = file_.tellg();
    if (end < 0) throw IoError(path_ + ": cannot determine the file size");
    file_size_ = static_cast<std::uint64_t>(end);
    open();
    select({});
  }

  /// Opens an MCAP file held in memory (copied; `name` stands for the path in
  /// error messages): the same reader as the path constructor, with reads
  /// served from the copy. Throws FormatError when it is not a valid MCAP file.
  static McapReader from_bytes(std::string_view bytes, const std::string& name, const Config& config = {}) {
    return McapReader(InMemory{}, bytes, name, config);
  }

  /// Topics of the file (one per topic name, in the order of their first channel id).
  [[nodiscard]] const std::vector<BagTopic>& topics() const noexcept { return topics_; }

  /// Restarts reading with only these topics (empty: all). Throws ValueError
  /// for a name the file does not have.
  void select(const std::vector<std::string>& topic_names) {
    std::vector<bool> want(topics_.size(), topic_names.empty());
    for (const std::string& name : topic_names) {
      const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == name; });
      if (it == topics_.end()) {
        std::string have;
        for (const BagTopic& t : topics_) have += (have.empty() ? "" : ", ") + t.name;
        throw ValueError(path_ + ": no topic '" + name + "' in the MCAP file (it has: " + have + ")");
      }
      want[static_cast<std::size_t>(it - topics_.begin())] = true;
    }
    selected_.assign(65536, false);
    for (const auto& [id, topic] : channel_topic_) selected_[id] = want[topic];
    heap_.clear();
    for (std::size_t i = 0; i < chunks_.size(); ++i) {
      const detail::mcap::ChunkRef& c = chunks_[i];
      const bool any = !c.channels_known ||
                       std::any_of(c.channels.begin(), c.channels.end(), [&](std::uint16_t ch) { return selected_[ch]; });
      if (any) push({.time_ns = c.start_ns, .kind = 0, .source = c.record_offset, .chunk = i});
    }
    for (const detail::mcap::LooseMessage& m : loose_) {
      if (!selected_[m.channel]) continue;
      push({.time_ns = m.log_time_ns,
            .kind = 1,
            .source = m.record_offset,
            .chunk = detail::mcap::kLoose,
            .data_offset = m.data_offset,
            .data_length = m.data_length,
            .channel = m.channel});
    }
    last_time_ns_ = 0;
  }

  /// The next selected message in log-time order (ties in file order); false at the end.
  bool next(BagMessage& out) {
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), detail::mcap::Later{});
      const detail::mcap::Item item = heap_.back();
      heap_.pop_back();
      if (item.kind == 0) {
        open_chunk(item.chunk);
        continue;
      }
      if (item.time_ns < last_time_ns_) {
        throw FormatError(where(item) + ": message log time " + std::to_string(item.time_ns) +
                          " ns is earlier than its chunk's index start time (the index is wrong)");
      }
      last_time_ns_ = item.time_ns;
      if (item.time_ns > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
        throw FormatError(where(item) + ": message log time " + std::to_string(item.time_ns) + " ns overflows int64");
      }
      out.topic = channel_topic_.at(item.channel);
      out.log_time_ns = static_cast<std::int64_t>(item.time_ns);
      const auto n = static_cast<std::size_t>(item.data_length);
      if (item.chunk == detail::mcap::kLoose) {
        out.data.resize(n);
        read_at(item.data_offset, n, out.data.data(), "message");
      } else {
        const std::vector<std::uint8_t>& records = chunk_records(item.chunk);
        // A chunk decompressed again after eviction must hold the message
        // where it did (it will, unless the file changed under the reader).
        if (item.data_offset > records.size() || n > records.size() - item.data_offset) {
          throw FormatError(where(item) + ": chunk no longer holds the message it indexed (file changed?)");
        }
        const std::uint8_t* p = records.data() + item.data_offset;
        out.data.assign(p, p + n);
      }
      return true;
    }
    return false;
  }

 private:
  struct CacheEntry {
    std::size_t chunk = detail::mcap::kLoose;
    std::uint64_t last_use = 0;
    std::vector<std::uint8_t> records;  ///< the chunk's decompressed records
  };

  struct InMemory {};
  McapReader(InMemory, std::string_view bytes, const std::string& name, const Config& config)
      : path_(name), config_(config), memory_(bytes), in_memory_(true) {
    file_size_ = memory_.size();
    open();
    select({});
  }

  void push(const detail::mcap::Item& item) {
    heap_.push_back(item);
    std::push_heap(heap_.begin(), heap_.end(), detail::mcap::Later{});
  }

  [[nodiscard]] std::string where_offset(std::uint64_t offset) const {
    return path_ + ": record at offset " + std::to_string(offset);
  }
  [[nodiscard]] std::string where(const detail::mcap::Item& item) const {
    return item.chunk == detail::mcap::kLoose ? where_offset(item.source)
                                              : path_ + ": chunk at offset " + std::to_string(item.source);
  }

  /// Reads n bytes at `offset` (already checked against the file size).
  void read_at(std::uint64_t offset, std::size_t n, std::uint8_t* dst, const char* what) {
    if (in_memory_) {
      if (offset > memory_.size() || n > memory_.size() - offset) {
        throw FormatError(path_ + ": " + std::to_string(n) + " bytes of " + what + " at offset " +
                          std::to_string(offset) + " lie past the end of the " + std::to_string(memory_.size()) +
                          "-byte file");
      }
      if (n != 0) std::memcpy(dst, memory_.data() + offset, n);
      return;
    }
    file_.clear();
    file_.seekg(static_cast<std::streamoff>(offset));
    file_.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (!file_ || static_cast<std::size_t>(file_.gcount()) != n) {
      throw IoError(path_ + ": cannot read " + std::to_string(n) + " bytes of " + what + " at offset " +
                    std::to_string(offset));
    }
  }

  /// Reads the 9-byte record header at `offset` (< end) and checks the record
  /// fits before `end`. Returns {opcode, content length}.
  std::pair<std::uint8_t, std::uint64_t> record_header(std::uint64_t offset, std::uint64_t end) {
    if (end - offset < detail::mcap::kRecordHeaderBytes) {
      throw FormatError(where_offset(offset) + ": truncated record header (" + std::to_string(end - offset) +
                        " bytes left)");
    }
    std::array<std::uint8_t, 9> h{};
    read_at(offset, h.size(), h.data(), "record header");
    std::uint64_t len = 0;
    std::memcpy(&len, h.data() + 1, 8);
    if (len > end - offset - detail::mcap::kRecordHeaderBytes) {
      throw FormatError(where_offset(offset) + ": record (opcode " + std::to_string(h[0]) + ") states " +
                        std::to_string(len) + " bytes, only " +
                        std::to_string(end - offset - detail::mcap::kRecordHeaderBytes) + " left");
    }
    return {h[0], len};
  }

  /// Reads a record's content (checked to fit) into `buf`.
  void read_content(std::uint64_t offset, std::uint64_t len, std::vector<std::uint8_t>& buf) {
    if (len > detail::kMaxChunkBytes) {
      throw FormatError(where_offset(offset) + ": record of " + std::to_string(len) + " bytes exceeds the 2 GiB limit");
    }
    buf.resize(static_cast<std::size_t>(len));
    read_at(offset + detail::mcap::kRecordHeaderBytes, buf.size(), buf.data(), "record");
  }

  void open() {
    using namespace detail::mcap;
    const auto magic_len = static_cast<std::uint64_t>(kMagic.size());
    std::array<std::uint8_t, 8> m{};
    if (file_size_ < magic_len) throw FormatError(path_ + ": " + std::to_string(file_size_) + " bytes, not an MCAP file");
    read_at(0, m.size(), m.data(), "magic");
    if (m != kMagic) throw FormatError(path_ + ": does not start with the MCAP magic (not an MCAP file)");
    // A complete file ends with Footer + magic; a file cut off while recording does not.
    const std::uint64_t footer_bytes = kRecordHeaderBytes + kFooterContentBytes + magic_len;
    std::uint64_t data_end = file_size_;
    std::uint64_t summary_start = 0;
    std::uint64_t summary_end = 0;
    if (file_size_ >= magic_len + footer_bytes) {
      read_at(file_size_ - magic_len, m.size(), m.data(), "trailing magic");
      if (m == kMagic) {
        const std::uint64_t footer_offset = file_size_ - footer_bytes;
        std::array<std::uint8_t, kRecordHeaderBytes + kFooterContentBytes> f{};
        read_at(footer_offset, f.size(), f.data(), "footer");
        std::uint64_t len = 0;
        std::memcpy(&len, f.data() + 1, 8);
        if (f[0] != kOpFooter || len != kFooterContentBytes) {
          throw FormatError(where_offset(footer_offset) + ": expected the Footer record before the trailing magic");
        }
        std::uint64_t summary_offset_start = 0;
        std::memcpy(&summary_start, f.data() + 9, 8);
        std::memcpy(&summary_offset_start, f.data() + 17, 8);
        data_end = footer_offset;
        if (summary_start != 0) {
          summary_end = summary_offset_start != 0 ? summary_offset_start : footer_offset;
          if (summary_start < magic_len || summary_start > summary_end || summary_end > footer_offset) {
            throw FormatError(where_offset(footer_offset) + ": Footer summary offsets " + std::to_string(summary_start) +
                              ".." + std::to_string(summary_end) + " lie outside the file");
          }
          data_end = summary_start;
        }
      }
    }
    if (summary_start == 0 || !read_summary(summary_start, summary_end)) scan(magic_len, data_end);
    make_topics();
  }

  /// Reads the summary section; false when it lacks what lazy reading needs.
  bool read_summary(std::uint64_t begin, std::uint64_t end) {
    using namespace detail::mcap;
    channels_.clear();
    schema_names_.clear();
    chunks_.clear();
    counts_.clear();
    bool have_stats = false;
    std::uint64_t stats_messages = 0;
    std::uint64_t stats_chunks = 0;
    std::vector<std::uint8_t> buf;
    for (std::uint64_t off = begin; off < end;) {
      const auto [op, len] = record_header(off, end);
      const std::string what = where_offset(off);
      if (op == kOpSchema || op == kOpChannel || op == kOpChunkIndex || op == kOpStatistics) {
        read_content(off, len, buf);
        Cursor c(buf.data(), buf.size(), off + kRecordHeaderBytes, what);
        if (op == kOpSchema) {
          parse_schema(c);
        } else if (op == kOpChannel) {
          parse_channel(c);
        } else if (op == kOpStatistics) {
          have_stats = true;
          stats_messages = c.u64("message_count");
          c.u16("schema_count");
          c.u32("channel_count");
          c.u32("attachment_count");
          c.u32("metadata_count");
          stats_chunks = c.u32("chunk_count");
          c.u64("message_start_time");
          c.u64("message_end_time");
          const std::uint32_t map_len = c.u32("channel_message_counts");
          c.need(map_len, "channel_message_counts");
          Cursor map(c.here(), map_len, off + kRecordHeaderBytes + c.pos(), what);
          while (map.remaining() > 0) {
            const std::uint16_t ch = map.u16("channel_message_counts.channel_id");
            counts_[ch] += map.u64("channel_message_counts.count");
          }
        } else {
          ChunkRef ref;
          ref.start_ns = c.u64("message_start_time");
          c.u64("message_end_time");
          ref.record_offset = c.u64("chunk_start_offset");
          const std::uint64_t chunk_length = c.u64("chunk_length");
          if (ref.record_offset < kMagic.size() || ref.record_offset > begin ||
              chunk_length > begin - ref.record_offset) {
            c.fail("ChunkIndex points at " + std::to_string(ref.record_offset) + " + " + std::to_string(chunk_length) +
                   " bytes, outside the data section");
          }
          const std::uint32_t map_len = c.u32("message_index_offsets");
          c.need(map_len, "message_index_offsets");
          Cursor map(c.here(), map_len, off + kRecordHeaderBytes + c.pos(), what);
          while (map.remaining() > 0) {
            ref.channels.push_back(map.u16("message_index_offsets.channel_id"));
            map.u64("message_index_offsets.offset");
          }
          // Without message indexes the writer does not say which channels a chunk holds.
          ref.channels_known = !ref.channels.empty();
          std::sort(ref.channels.begin(), ref.channels.end());
          chunks_.push_back(std::move(ref));
        }
      }
      off += kRecordHeaderBytes + len;
    }
    if (!have_stats || stats_chunks != chunks_.size() || (stats_messages > 0 && chunks_.empty())) return false;
    for (const auto& [ch, n] : counts_) {
      if (n > 0 && channels_.count(ch) == 0) return false;  // channels only inside chunks: scan
    }
    std::sort(chunks_.begin(), chunks_.end(),
              [](const ChunkRef& a, const ChunkRef& b) { return a.record_offset < b.record_offset; });
    return true;
  }

  void parse_schema(detail::mcap::Cursor& c) {
    const std::uint16_t id = c.u16("schema.id");
    schema_names_[id] = c.string("schema.name");
  }
  void parse_channel(detail::mcap::Cursor& c) {
    detail::mcap::Channel ch;
    ch.id = c.u16("channel.id");
    ch.schema_id = c.u16("channel.schema_id");
    ch.topic = c.string("channel.topic");
    ch.message_encoding = c.string("channel.message_encoding");
    channels_.emplace(ch.id, std::move(ch));
  }

  /// Scans the data section [begin, end) record by record (see the file comment).
  void scan(std::uint64_t begin, std::uint64_t end) {
    using namespace detail::mcap;
    channels_.clear();
    schema_names_.clear();
    chunks_.clear();
    loose_.clear();
    counts_.clear();
    std::vector<std::uint8_t> buf;
    std::vector<std::uint8_t> records;
    for (std::uint64_t off = begin; off < end;) {
      const auto [op, len] = record_header(off, end);
      const std::string what = where_offset(off);
      if (op == kOpDataEnd || op == kOpFooter) break;
      if (op == kOpSchema || op == kOpChannel) {
        read_content(off, len, buf);
        Cursor c(buf.data(), buf.size(), off + kRecordHeaderBytes, what);
        op == kOpSchema ? parse_schema(c) : parse_channel(c);
      } else if (op == kOpMessage) {
        std::array<std::uint8_t, 22> h{};
        if (len < h.size()) throw FormatError(what + ": Message record of " + std::to_string(len) + " bytes (< 22)");
        read_at(off + kRecordHeaderBytes, h.size(), h.data(), "message header");
        LooseMessage msg;
        std::memcpy(&msg.channel, h.data(), 2);
        std::memcpy(&msg.log_time_ns, h.data() + 6, 8);
        msg.record_offset = off;
        msg.data_offset = off + kRecordHeaderBytes + h.size();
        msg.data_length = len - h.size();
        ++counts_[msg.channel];
        loose_.push_back(msg);
      } else if (op == kOpChunk) {
        read_content(off, len, buf);
        decompress_chunk(buf, off, records);
        ChunkRef ref;
        ref.record_offset = off;
        ref.channels_known = true;
        ref.start_ns = std::numeric_limits<std::uint64_t>::max();
        for_each_record(records, off, [&](std::uint8_t inner_op, Cursor& c, std::uint64_t) {
          if (inner_op == kOpSchema) parse_schema(c);
          if (inner_op == kOpChannel) parse_channel(c);
          if (inner_op == kOpMessage) {
            const std::uint16_t ch = c.u16("message.channel_id");
            c.u32("message.sequence");
            ref.start_ns = std::min(ref.start_ns, c.u64("message.log_time"));
            ++counts_[ch];
            if (!std::binary_search(ref.channels.begin(), ref.channels.end(), ch)) {
              ref.channels.insert(std::upper_bound(ref.channels.begin(), ref.channels.end(), ch), ch);
            }
          }
        });
        if (!ref.channels.empty()) chunks_.push_back(std::move(ref));
      }
      off += kRecordHeaderBytes + len;
    }
  }

  /// Decompresses the Chunk record content `chunk` (at file offset `off`) into `out`.
  void decompress_chunk(const std::vector<std::uint8_t>& chunk, std::uint64_t off, std::vector<std::uint8_t>& out) {
    using namespace detail::mcap;
    const std::string what = path_ + ": chunk at offset " + std::to_string(off);
    Cursor c(chunk.data(), chunk.size(), off + kRecordHeaderBytes, what);
    c.u64("message_start_time");
    c.u64("message_end_time");
    const std::uint64_t uncompressed_size = c.u64("uncompressed_size");
    const std::uint32_t crc = c.u32("uncompressed_crc");
    const std::string compression = c.string("compression");
    const std::uint64_t n = c.u64("records");
    c.need(n, "records");
    const std::uint8_t* in = c.here();
    const auto in_size = static_cast<std::size_t>(n);
    if (compression.empty()) {
      if (uncompressed_size != n) {
        c.fail("uncompressed chunk holds " + std::to_string(n) + " bytes of records, uncompressed_size says " +
               std::to_string(uncompressed_size));
      }
      out.assign(in, in + in_size);
    } else if (compression == "zstd") {
      // Check a stated size against the frame's own before allocating it:
      // a damaged uncompressed_size must not cost gigabytes.
      const unsigned long long frame_size = ZSTD_getFrameContentSize(in, in_size);
      if (frame_size == ZSTD_CONTENTSIZE_ERROR) c.fail("chunk records are not a zstd frame");
      if (frame_size != ZSTD_CONTENTSIZE_UNKNOWN && frame_size != uncompressed_size) {
        c.fail("zstd frame holds " + std::to_string(frame_size) + " bytes, uncompressed_size says " +
               std::to_string(uncompressed_size));
      }
      // As detail::decompress_zstd, with one decompression context kept for
      // the reader's life instead of one allocated per chunk.
      detail::check_chunk_size(uncompressed_size, what);
      detail::check_expansion(in_size, uncompressed_size, detail::kMaxZstdRatio, "zstd", what);
      if (!zstd_) zstd_.reset(ZSTD_createDCtx());
      if (!zstd_) throw FormatError(what + ": cannot create a zstd decompression context");
      out.resize(static_cast<std::size_t>(uncompressed_size));
      const std::size_t got = ZSTD_decompressDCtx(zstd_.get(), out.data(), out.size(), in, in_size);
      if (ZSTD_isError(got) != 0U) c.fail(std::string("zstd data is corrupt (") + ZSTD_getErrorName(got) + ")");
      if (got != uncompressed_size) {
        c.fail("zstd chunk decompresses to " + std::to_string(got) + " bytes, uncompressed_size says " +
               std::to_string(uncompressed_size));
      }
    } else if (compression == "lz4") {
      // LZ4 cannot compress better than 255:1 (a match adds at most 255 bytes per byte of input).
      if (uncompressed_size / 255 > n + 64) {
        c.fail("uncompressed_size " + std::to_string(uncompressed_size) + " is impossible for " + std::to_string(n) +
               " bytes of LZ4");
      }
      detail::decompress_lz4_frame(in, in_size, uncompressed_size, out, what);
    } else {
      c.fail("unknown chunk compression '" + compression + "' (expected \"\", zstd or lz4)");
    }
    if (config_.verify_chunk_crc && crc != 0) {
      const std::uint32_t got = crc32(out.data(), out.size());
      if (got != crc) {
        throw FormatError(what + ": CRC-32 of the uncompressed records is " + std::to_string(got) + ", the chunk says " +
                          std::to_string(crc));
      }
    }
  }

  /// Calls f(opcode, cursor over the content, content offset in `records`) for each record of a chunk.
  template <typename F>
  void for_each_record(const std::vector<std::uint8_t>& records, std::uint64_t chunk_offset, F&& f) {
    using namespace detail::mcap;
    const std::string what = path_ + ": chunk at offset " + std::to_string(chunk_offset) + ", records";
    Cursor all(records.data(), records.size(), 0, what);
    while (all.remaining() > 0) {
      const std::uint8_t op = all.u8("opcode");
      const std::uint64_t len = all.u64("length");
      all.need(len, "record content");
      const std::uint64_t content = all.pos();
      Cursor c(all.here(), len, content, what);
      f(op, c, content);
      all.skip(len, "record content");
    }
  }

  /// Returns the decompressed records of chunk `i`, from the cache or the file.
  const std::vector<std::uint8_t>& chunk_records(std::size_t i) {
    ++use_clock_;
    for (CacheEntry& e : cache_) {
      if (e.chunk == i) {
        e.last_use = use_clock_;
        return e.records;
      }
    }
    CacheEntry& e = *std::min_element(cache_.begin(), cache_.end(), [](const CacheEntry& a, const CacheEntry& b) {
      return a.last_use < b.last_use;
    });
    e.chunk = detail::mcap::kLoose;  // invalid until decompressed
    const std::uint64_t off = chunks_[i].record_offset;
    const auto [op, len] = record_header(off, file_size_);
    if (op != detail::mcap::kOpChunk) {
      throw FormatError(where_offset(off) + ": the index points at a record that is not a Chunk (opcode " +
                        std::to_string(op) + ")");
    }
    read_content(off, len, compressed_);
    decompress_chunk(compressed_, off, e.records);
    e.chunk = i;
    e.last_use = use_clock_;
    return e.records;
  }

  /// Pushes the selected messages of chunk `i` onto the heap.
  void open_chunk(std::size_t i) {
    using namespace detail::mcap;
    const std::vector<std::uint8_t>& records = chunk_records(i);
    const std::uint64_t source = chunks_[i].record_offset;
    for_each_record(records, source, [&](std::uint8_t op, Cursor& c, std::uint64_t content) {
      if (op != kOpMessage) return;
      const std::uint16_t ch = c.u16("message.channel_id");
      if (!selected_[ch]) return;
      if (channel_topic_.count(ch) == 0) {
        if (channels_.count(ch) == 0) c.fail("message on channel " + std::to_string(ch) + ", which no Channel record defines");
        return;  // a channel of an encoding semlio does not read
      }
      c.u32("message.sequence");
      const std::uint64_t log_time = c.u64("message.log_time");
      c.u64("message.publish_time");
      push({.time_ns = log_time,
            .kind = 1,
            .source = source,
            .inner = content,
            .chunk = i,
            .data_offset = content + c.pos(),
            .data_length = c.remaining(),
            .channel = ch});
    });
  }

  void make_topics() {
    topics_.clear();
    channel_topic_.clear();
    for (const auto& [id, ch] : channels_) {  // std::map: ascending channel id
      MessageEncoding enc{};
      if (ch.message_encoding == "cdr") {
        enc = MessageEncoding::kCdr;
      } else if (ch.message_encoding == "ros1") {
        enc = MessageEncoding::kRos1;
      } else {
        continue;
      }
      const std::string& name = ch.topic;  // clang < 16 cannot capture a structured binding
      auto it = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == name; });
      if (it == topics_.end()) {
        BagTopic t;
        t.name = ch.topic;
        const auto s = schema_names_.find(ch.schema_id);
        t.type = ch.schema_id != 0 && s != schema_names_.end() ? s->second : std::string();
        t.encoding = enc;
        topics_.push_back(std::move(t));
        it = topics_.end() - 1;
      }
      const auto n = counts_.find(id);
      if (n != counts_.end()) it->message_count += static_cast<std::size_t>(n->second);
      channel_topic_[id] = static_cast<std::size_t>(it - topics_.begin());
    }
  }

  std::string path_;
  Config config_;
  std::ifstream file_;
  std::string memory_;     ///< the whole file when opened with from_bytes
  bool in_memory_ = false;  ///< reads come from memory_, not file_
  std::uint64_t file_size_ = 0;
  std::map<std::uint16_t, detail::mcap::Channel> channels_;
  std::map<std::uint16_t, std::string> schema_names_;
  std::map<std::uint16_t, std::uint64_t> counts_;            ///< messages per channel id
  std::vector<detail::mcap::ChunkRef> chunks_;               ///< in file order
  std::vector<detail::mcap::LooseMessage> loose_;            ///< messages outside chunks
  std::vector<BagTopic> topics_;
  std::map<std::uint16_t, std::size_t> channel_topic_;       ///< channel id -> topics_ index (readable channels)
  std::vector<bool> selected_;                               ///< by channel id
  std::vector<detail::mcap::Item> heap_;
  std::uint64_t last_time_ns_ = 0;
  std::array<CacheEntry, 2> cache_{};
  std::uint64_t use_clock_ = 0;
  std::vector<std::uint8_t> compressed_;
  struct FreeZstd {
    void operator()(ZSTD_DCtx* d) const noexcept { ZSTD_freeDCtx(d); }
  };
  std::unique_ptr<ZSTD_DCtx, FreeZstd> zstd_;
};

}  // namespace semlio::io
