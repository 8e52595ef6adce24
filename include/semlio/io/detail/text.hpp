#pragma once
/// \file
/// Internal helpers shared by the text and binary readers/writers of
/// semlio::io: whole-file read/write, line iteration, whitespace tokenising and
/// locale-independent number parsing/formatting (std::from_chars/to_chars).
/// Stable interface: the PCD/PLY readers use it too.

#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <semlio/core/error.hpp>

namespace semlio::io::detail {

/// "path:line: what": forwards to semlio::detail::where, the one place
/// messages get their location prefix (kept so io code can say detail::where).
inline std::string where(const std::string& path, long line, const std::string& what) {
  return semlio::detail::where(path, line, what);
}

/// Default byte limit of read_file: 1 GiB, far above any text file semlio
/// reads (a 10-million-frame times.txt is ~250 MB) and below the memory of the
/// machines it runs on, so a mistaken path costs an error, not the process.
inline constexpr std::uint64_t kMaxFileBytes = std::uint64_t{1} << 30;

/// a * b, or nullopt when the product does not fit a std::size_t. Used for
/// every size computed from counts read from a file.
[[nodiscard]] inline std::optional<std::size_t> checked_mul(std::size_t a, std::size_t b) noexcept {
  std::size_t out = 0;
  if (__builtin_mul_overflow(a, b, &out)) return std::nullopt;
  return out;
}

/// a + b, or nullopt when the sum does not fit a std::size_t.
[[nodiscard]] inline std::optional<std::size_t> checked_add(std::size_t a, std::size_t b) noexcept {
  std::size_t out = 0;
  if (__builtin_add_overflow(a, b, &out)) return std::nullopt;
  return out;
}

/// Reads a whole regular file as bytes, refusing files larger than `max_bytes`
/// before allocating. Throws IoError naming the path when it is missing, not a
/// regular file (a directory, FIFO or device such as /dev/zero would block or
/// grow without bound), larger than the limit (naming both sizes) or cannot be
/// read.
inline std::string read_file(const std::string& path, std::uint64_t max_bytes = kMaxFileBytes) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) {
    throw IoError(detail::where(path, 0, "cannot open for reading (no such file)"));
  }
  if (!std::filesystem::is_regular_file(st)) {
    throw IoError(detail::where(path, 0,
                                std::filesystem::is_directory(st) ? "is a directory, expected a regular file"
                                                                  : "is not a regular file (a device, FIFO or socket)"));
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw IoError(detail::where(path, 0, "cannot determine the file size (" + ec.message() + ")"));
  if (size > max_bytes) {
    throw IoError(detail::where(path, 0,
                                "file is " + std::to_string(size) + " bytes, more than the limit of " +
                                    std::to_string(max_bytes) + " bytes for this kind of file"));
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    throw IoError(detail::where(path, 0, std::string("cannot open for reading (") + std::strerror(errno) + ")"));
  }
  std::string out;
  out.reserve(static_cast<std::size_t>(size));
  char buffer[1 << 16];
  bool too_big = false;
  for (;;) {
    const std::size_t n = std::fread(buffer, 1, sizeof(buffer), f);
    out.append(buffer, n);
    // The file may grow between stat and read: keep the limit anyway.
    if (out.size() > max_bytes) {
      too_big = true;
      break;
    }
    if (n < sizeof(buffer)) break;
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (too_big) {
    throw IoError(detail::where(path, 0, "file grew past the limit of " + std::to_string(max_bytes) + " bytes while reading"));
  }
  if (failed) throw IoError(detail::where(path, 0, "read error"));
  return out;
}

/// Writes bytes to a file, replacing it. Throws IoError naming the path.
inline void write_file(const std::string& path, std::string_view bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    throw IoError(detail::where(path, 0, std::string("cannot open for writing (") + std::strerror(errno) + ")"));
  }
  const std::size_t n = bytes.empty() ? 0 : std::fwrite(bytes.data(), 1, bytes.size(), f);
  const bool closed = std::fclose(f) == 0;
  if (n != bytes.size() || !closed) throw IoError(detail::where(path, 0, "write error"));
}

/// Removes leading and trailing spaces, tabs, CR and LF.
inline std::string_view trim(std::string_view s) noexcept {
  constexpr std::string_view kSpace = " \t\r\n\f\v";
  const std::size_t b = s.find_first_not_of(kSpace);
  if (b == std::string_view::npos) return {};
  const std::size_t e = s.find_last_not_of(kSpace);
  return s.substr(b, e - b + 1);
}

/// True when the line holds only whitespace.
inline bool is_blank(std::string_view s) noexcept { return trim(s).empty(); }

/// Calls f(line_number, line) for every line of `text` (1-based numbers, the
/// line without its '\n' and without a trailing '\r'). A final line without
/// '\n' is visited; the empty remainder after a final '\n' is not.
template <typename F>
void for_each_line(std::string_view text, F&& f) {
  long number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    f(++number, line);
    start = end + 1;
  }
}

/// Splits at runs of whitespace into `out` (cleared first; views into `line`).
inline void split_ws(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; };
  while (i < line.size()) {
    while (i < line.size() && space(line[i])) ++i;
    const std::size_t b = i;
    while (i < line.size() && !space(line[i])) ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
}

/// Calls f(line_number, line, tokens) for every record line of `text`: the
/// whitespace-separated tokens of each non-blank line. Trailing blank lines
/// are allowed; a blank line followed by another record throws FormatError
/// naming `path`, the blank line and `records` ("poses", "times", ...). The one
/// home of that rule for every line-oriented reader.
template <typename F>
void for_each_record(std::string_view text, const std::string& path, std::string_view records, F&& f) {
  std::vector<std::string_view> tokens;
  long blank_line = 0;
  for_each_line(text, [&](long line, std::string_view s) {
    split_ws(s, tokens);
    if (tokens.empty()) {
      if (blank_line == 0) blank_line = line;
      return;
    }
    if (blank_line != 0) {
      throw FormatError(where(path, blank_line, "blank line between " + std::string(records)));
    }
    f(line, s, tokens);
  });
}

/// Splits at runs of whitespace (allocating convenience form).
inline std::vector<std::string_view> split_ws(std::string_view line) {
  std::vector<std::string_view> out;
  split_ws(line, out);
  return out;
}

/// Parses a whole token as a double, locale independent. Accepts an optional
/// leading '+', decimal and exponent forms, "nan" and "inf"; rejects anything
/// else (hex, trailing characters, empty). Returns nullopt on failure.
inline std::optional<double> to_double(std::string_view token) noexcept {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty() || token.front() == '+') return std::nullopt;
  double value = 0.0;
  const char* first = token.data();
  const char* last = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(first, last, value, std::chars_format::general);
  if (ptr != last) return std::nullopt;
  if (ec == std::errc::result_out_of_range) {
    // from_chars leaves `value` untouched on range errors: saturate like
    // strtod (a negative exponent underflows to 0, otherwise overflow to inf).
    const bool negative = token.front() == '-';
    const std::size_t e = token.find_first_of("eE");
    const bool underflow = e != std::string_view::npos && e + 1 < token.size() && token[e + 1] == '-';
    if (underflow) return negative ? -0.0 : 0.0;
    return negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  }
  if (ec != std::errc()) return std::nullopt;
  return value;
}

/// Parses a whole token as a non-negative or signed 64-bit integer; nullopt on failure.
inline std::optional<std::int64_t> to_int(std::string_view token) noexcept {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty() || token.front() == '+') return std::nullopt;
  std::int64_t value = 0;
  const char* last = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), last, value);
  if (ec != std::errc() || ptr != last) return std::nullopt;
  return value;
}

/// Parses token number `field` (1-based, for the message) as a double or
/// throws FormatError "path:line: <what> field N ('tok') is not a number".
inline double parse_double(std::string_view token, const std::string& path, long line, std::size_t field,
                           std::string_view what = {}) {
  if (const auto v = to_double(token)) return *v;
  std::string msg;
  if (!what.empty()) msg.append(what).append(" ");
  msg += "field " + std::to_string(field) + " ('" + std::string(token) + "') is not a number";
  throw FormatError(detail::where(path, line, msg));
}

/// Appends the shortest decimal text that reads back as exactly `value`
/// (std::to_chars, locale independent; "nan"/"inf" for non-finite values).
inline void append_double(std::string& out, double value) {
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  (void)ec;  // 64 chars always suffice for a double
  out.append(buffer, ptr);
}

/// Appends a double with a fixed number of digits after the point ("%.*f").
inline void append_fixed(std::string& out, double value, int digits) {
  char buffer[400];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed, digits);
  (void)ec;
  out.append(buffer, ptr);
}

/// Appends an integer.
inline void append_int(std::string& out, std::int64_t value) {
  char buffer[32];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  (void)ec;
  out.append(buffer, ptr);
}

/// Appends an unsigned integer left-padded with zeros to `width` digits.
inline void append_padded(std::string& out, std::uint64_t value, int width) {
  char buffer[32];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  (void)ec;
  const auto len = static_cast<int>(ptr - buffer);
  for (int i = len; i < width; ++i) out.push_back('0');
  out.append(buffer, ptr);
}

/// Zero-padded decimal file stem, e.g. frame_stem(7, 6) == "000007".
inline std::string frame_stem(std::size_t index, int width) {
  std::string out;
  append_padded(out, index, width);
  return out;
}

}  // namespace semlio::io::detail
