#pragma once
/// \file
/// Error types: every bad input or API misuse throws a subclass of semlio::Error.
/// Data-dependent outcomes (too few matches, degenerate geometry) are statuses
/// in reports, never exceptions.

#include <stdexcept>
#include <string>

namespace semlio {

/// Base of every exception semlio throws; catch this to catch them all.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file or directory could not be opened, listed or written.
class IoError : public Error {
 public:
  using Error::Error;
};

/// File content violates its format (truncated, non-numeric, wrong field
/// count, a header that lies). The message names the path and line or byte.
class FormatError : public Error {
 public:
  using Error::Error;
};

/// Values that parse but are not acceptable: NaN, non-orthonormal rotation,
/// time going backwards, mismatched sizes.
class ValueError : public Error {
 public:
  using Error::Error;
};

/// A configuration field outside its valid range; the message names the field.
class ConfigError : public Error {
 public:
  using Error::Error;
};

namespace detail {

/// "path:line: what" — the one place messages get their location prefix.
inline std::string where(const std::string& path, long line, const std::string& what) {
  // Appends only: GCC 12 at -O3 reports a false -Wrestrict on
  // `":" + std::to_string(line)`.
  std::string out = path;
  if (line > 0) {
    out += ':';
    out += std::to_string(line);
  }
  out += ": ";
  out += what;
  return out;
}

}  // namespace detail
}  // namespace semlio
