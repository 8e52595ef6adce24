#pragma once
/// \file
/// Internals shared by the PCD and PLY readers and writers: whole-file reads,
/// endian-aware scalar loads and stores, strict number parsing, line and token
/// splitting, and the one rule for dropping NaN/Inf and (0,0,0) points.

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/read_stats.hpp>

namespace semlio::io::detail::cloud {

/// "path:line: what": semlio::detail::where under the short name the PCD/PLY
/// readers use.
inline std::string located(const std::string& path, long line, const std::string& what) {
  return semlio::detail::where(path, line, what);
}

/// Kind of a stored scalar.
enum class Kind : std::uint8_t { kInt, kUint, kFloat };

/// A stored scalar type: signed/unsigned integer or IEEE float of 1/2/4/8 bytes.
struct ScalarType {
  Kind kind = Kind::kFloat;
  std::size_t bytes = 4;
};

/// True for the combinations both formats allow (floats of 4 or 8 bytes).
inline bool is_valid(ScalarType t) noexcept {
  if (t.kind == Kind::kFloat) return t.bytes == 4 || t.bytes == 8;
  return t.bytes == 1 || t.bytes == 2 || t.bytes == 4 || t.bytes == 8;
}

/// Largest PCD/PLY file the readers accept: 10 million points (the KITTI
/// .bin limit) at up to ~100 bytes per point (an ascii line with ring, label
/// and time), i.e. 1 GiB. Larger files are refused before any allocation.
inline constexpr std::uint64_t kMaxCloudFileBytes = std::uint64_t{1} << 30;

/// Whole file as bytes; IoError when it is missing, not a regular file (a
/// directory, FIFO or device), larger than `max_bytes` or unreadable.
inline std::string read_file_bytes(const std::string& path, std::uint64_t max_bytes = kMaxCloudFileBytes) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw IoError(located(path, 0, "file does not exist"));
  }
  if (std::filesystem::is_directory(path, ec)) {
    throw IoError(located(path, 0, "is a directory, expected a file"));
  }
  return semlio::io::detail::read_file(path, max_bytes);
}

/// Writes bytes to a file, replacing it; IoError when it cannot be written.
inline void write_file_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw IoError(located(path, 0, "cannot open file for writing"));
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.flush();
  if (!out) throw IoError(located(path, 0, "write failed"));
}

/// Copies n bytes from p, reversing them when `swap` (foreign byte order).
template <typename T>
T load(const char* p, bool swap) noexcept {
  std::array<char, sizeof(T)> raw{};
  std::memcpy(raw.data(), p, sizeof(T));
  if (swap) std::reverse(raw.begin(), raw.end());
  T value{};
  std::memcpy(&value, raw.data(), sizeof(T));
  return value;
}

/// Loads a scalar of type t at p as double (exact for every 32-bit integer).
inline double load_as_double(const char* p, ScalarType t, bool swap) noexcept {
  switch (t.kind) {
    case Kind::kFloat:
      return t.bytes == 4 ? static_cast<double>(load<float>(p, swap)) : load<double>(p, swap);
    case Kind::kInt:
      switch (t.bytes) {
        case 1:
          return static_cast<double>(load<std::int8_t>(p, swap));
        case 2:
          return static_cast<double>(load<std::int16_t>(p, swap));
        case 4:
          return static_cast<double>(load<std::int32_t>(p, swap));
        default:
          return static_cast<double>(load<std::int64_t>(p, swap));
      }
    case Kind::kUint:
      switch (t.bytes) {
        case 1:
          return static_cast<double>(load<std::uint8_t>(p, swap));
        case 2:
          return static_cast<double>(load<std::uint16_t>(p, swap));
        case 4:
          return static_cast<double>(load<std::uint32_t>(p, swap));
        default:
          return static_cast<double>(load<std::uint64_t>(p, swap));
      }
  }
  return 0.0;
}

/// Loads an integer scalar at p as its low 32 bits (labels: raw id + instance).
inline std::uint32_t load_as_u32(const char* p, ScalarType t, bool swap) noexcept {
  switch (t.bytes) {
    case 1:
      return load<std::uint8_t>(p, swap);
    case 2:
      return load<std::uint16_t>(p, swap);
    case 4:
      return load<std::uint32_t>(p, swap);
    default:
      return static_cast<std::uint32_t>(load<std::uint64_t>(p, swap));
  }
}

/// Appends the bytes of v to out, reversed when `swap`.
template <typename T>
void store(std::string& out, T v, bool swap) {
  std::array<char, sizeof(T)> raw{};
  std::memcpy(raw.data(), &v, sizeof(T));
  if (swap) std::reverse(raw.begin(), raw.end());
  out.append(raw.data(), raw.size());
}

/// Appends the shortest text that reads back as exactly the same float.
inline void append_number(std::string& out, float v) {
  std::array<char, 64> buf{};
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  out.append(buf.data(), res.ptr);
}

/// Appends an unsigned integer as decimal text.
inline void append_number(std::string& out, std::uint32_t v) {
  std::array<char, 16> buf{};
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  out.append(buf.data(), res.ptr);
}

/// True for the ASCII whitespace the text formats use between tokens.
constexpr bool is_space(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/// Splits a line into whitespace-separated tokens (appends to `out`, cleared first).
inline void split_tokens(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
}

/// Iterates over the '\n'-terminated lines of a buffer from a byte offset,
/// counting line numbers (1-based, from the start of the file).
class LineCursor {
 public:
  /// Starts at byte `offset`, which begins line number `line`.
  LineCursor(std::string_view text, std::size_t offset, long line) noexcept
      : text_(text), pos_(offset), next_line_(line) {}

  /// Next line without its terminator ('\n' or "\r\n"); false at end of text.
  bool next(std::string_view& line) noexcept {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    line = text_.substr(pos_, stop - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end == std::string_view::npos ? text_.size() : end + 1;
    line_ = next_line_++;
    return true;
  }
  /// Line number of the line last returned by next().
  [[nodiscard]] long line() const noexcept { return line_; }
  /// Byte offset just past the line last returned by next().
  [[nodiscard]] std::size_t offset() const noexcept { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_;
  long next_line_;
  long line_ = 0;
};

/// True when the line holds only whitespace.
inline bool is_blank(std::string_view line) noexcept {
  return std::all_of(line.begin(), line.end(), is_space);
}

/// Parses a whole token as a double (accepts "nan", "inf", a leading '+').
inline bool parse_double(std::string_view tok, double& out) noexcept {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return res.ec == std::errc() && res.ptr == tok.data() + tok.size();
}

/// Parses a whole token as a float, rounding once (accepts "nan", "inf", '+').
inline bool parse_float(std::string_view tok, float& out) noexcept {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return res.ec == std::errc() && res.ptr == tok.data() + tok.size();
}

/// Parses a whole token as an integer of type T (decimal, optional leading '+').
template <typename T>
bool parse_integer(std::string_view tok, T& out) noexcept {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return res.ec == std::errc() && res.ptr == tok.data() + tok.size();
}

/// Parses a text token as a value of the declared scalar type: integers must be
/// integral and fit the declared size. Returns false on any mismatch.
inline bool parse_typed(std::string_view tok, ScalarType t, double& value, std::uint32_t& bits) {
  if (t.kind == Kind::kFloat) {
    bits = 0;
    if (t.bytes == 8) return parse_double(tok, value);
    // 4-byte floats parse as float: going through double could round twice and
    // break the writers' bit-exact round trip. Text beyond float's range
    // (1e39, 1e-50) falls back to double; to_float() then saturates it.
    float f = 0.0F;
    if (parse_float(tok, f)) {
      value = static_cast<double>(f);
      return true;
    }
    return parse_double(tok, value);
  }
  if (t.kind == Kind::kUint) {
    std::uint64_t u = 0;
    if (!parse_integer(tok, u)) return false;
    if (t.bytes < 8 && u >= (std::uint64_t{1} << (8 * t.bytes))) return false;
    value = static_cast<double>(u);
    bits = static_cast<std::uint32_t>(u);
    return true;
  }
  std::int64_t s = 0;
  if (!parse_integer(tok, s)) return false;
  if (t.bytes < 8) {
    const std::int64_t lim = std::int64_t{1} << (8 * t.bytes - 1);
    if (s < -lim || s >= lim) return false;
  }
  value = static_cast<double>(s);
  bits = static_cast<std::uint32_t>(static_cast<std::uint64_t>(s));
  return true;
}

/// Narrows to float; values beyond float's range become +-inf (counted as
/// non-finite later) instead of undefined behaviour.
inline float to_float(double v) noexcept {
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  if (v > kMax) return std::numeric_limits<float>::infinity();
  if (v < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

/// Column indices of the fields the readers use; -1 when the file lacks one.
struct Columns {
  int x = -1, y = -1, z = -1;
  int intensity = -1;  ///< `intensity`, or CloudCompare's `scalar_intensity`
  int label = -1;      ///< integer: SemanticKITTI raw id | instance << 16
  int ring = -1;       ///< integer: beam index (Velodyne/LIO-SAM convention)
  int time = -1;       ///< seconds since sweep start (Velodyne/LIO-SAM `time`)

  /// The slot a field name (compared case-insensitively) fills, nullptr for
  /// fields the readers skip.
  int* slot(std::string_view name) noexcept {
    std::string low(name);
    for (char& c : low) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (low == "x") return &x;
    if (low == "y") return &y;
    if (low == "z") return &z;
    if (low == "intensity" || low == "scalar_intensity") return &intensity;
    if (low == "label") return &label;
    if (low == "ring") return &ring;
    if (low == "time") return &time;
    return nullptr;
  }
};

/// One decoded point before the drop rule.
struct PointRecord {
  float x = 0.0F, y = 0.0F, z = 0.0F, intensity = 0.0F, time_s = 0.0F;
  std::uint32_t label = 0;
  std::uint16_t ring = 0;
};

/// Decodes one point through the format's accessors: real(col) -> double,
/// bits(col) -> std::uint32_t (integer columns: label, ring).
template <typename Real, typename Bits>
PointRecord decode(const Columns& c, Real real, Bits bits) {
  PointRecord r;
  r.x = to_float(real(c.x));
  r.y = to_float(real(c.y));
  r.z = to_float(real(c.z));
  if (c.intensity >= 0) r.intensity = to_float(real(c.intensity));
  if (c.time >= 0) r.time_s = to_float(real(c.time));
  if (c.label >= 0) r.label = bits(c.label);
  if (c.ring >= 0) r.ring = static_cast<std::uint16_t>(bits(c.ring));
  return r;
}

/// The one drop rule of both readers: a point with a NaN/Inf coordinate,
/// intensity or time is dropped and counted as non-finite; an exact (0,0,0)
/// point (the "no return" marker of many drivers) is dropped and counted as
/// zero.
inline bool keep_point(const PointRecord& r, ReadStats& stats) noexcept {
  if (!std::isfinite(r.x) || !std::isfinite(r.y) || !std::isfinite(r.z) ||
      !std::isfinite(r.intensity) || !std::isfinite(r.time_s)) {
    ++stats.dropped_nonfinite;
    return false;
  }
  if (r.x == 0.0F && r.y == 0.0F && r.z == 0.0F) {
    ++stats.dropped_zero;
    return false;
  }
  return true;
}

/// Reserves room for n points in positions and in the fields the file declares.
inline void reserve(Scan& scan, std::size_t n, const Columns& c) {
  scan.points.reserve(n);
  if (c.intensity >= 0) scan.intensity.reserve(n);
  if (c.label >= 0) {
    scan.labels.reserve(n);
    scan.instances.reserve(n);
  }
  if (c.ring >= 0) scan.rings.reserve(n);
  if (c.time >= 0) scan.times_s.reserve(n);
}

/// Appends one decoded point to the scan (the fields the file declares).
inline void push_point(Scan& scan, const Columns& c, const PointRecord& r) {
  scan.points.emplace_back(r.x, r.y, r.z);
  if (c.intensity >= 0) scan.intensity.push_back(r.intensity);
  if (c.label >= 0) {
    scan.labels.push_back(learning_class(r.label));
    scan.instances.push_back(static_cast<std::uint16_t>(r.label >> 16));
  }
  if (c.ring >= 0) scan.rings.push_back(r.ring);
  if (c.time >= 0) scan.times_s.push_back(r.time_s);
}

/// The raw SemanticKITTI label a writer stores for point i: the raw id of its
/// learning class in the low 16 bits, its instance (if any) in the high 16.
inline std::uint32_t raw_label_of(const Scan& scan, std::size_t i) noexcept {
  std::uint32_t raw = raw_id(scan.labels[i]);
  if (scan.has_instances()) raw |= static_cast<std::uint32_t>(scan.instances[i]) << 16;
  return raw;
}

/// Adds a read's counts to the caller's stats (never resets them, so one
/// ReadStats can accumulate over many files).
inline void report(ReadStats* out, const ReadStats& local) noexcept {
  if (out == nullptr) return;
  out->dropped_nonfinite += local.dropped_nonfinite;
  out->dropped_zero += local.dropped_zero;
}

}  // namespace semlio::io::detail::cloud
