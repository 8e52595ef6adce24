#pragma once
// A minimal streaming JSON writer for the example binaries (no dependency).
// Keys and strings are escaped; non-finite numbers are written as null and
// counted, so the output is always valid JSON (RFC 8259 has no inf or nan).

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <ostream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace semlio_examples {

/// Writes one JSON document to a stream; the caller balances begin/end calls.
class JsonWriter {
 public:
  explicit JsonWriter(std::ostream& out) : out_(out) {}

  JsonWriter& begin_object() { return open('{'); }
  JsonWriter& end_object() { return close('}'); }
  JsonWriter& begin_array() { return open('['); }
  JsonWriter& end_array() { return close(']'); }

  /// Writes `"name":` inside an object; the next value call writes its value.
  JsonWriter& key(std::string_view name) {
    comma();
    string_literal(name);
    out_ << ':';
    pending_key_ = true;
    return *this;
  }

  /// A number as JSON: finite values in the shortest form that reads back
  /// as the same double (std::to_chars; ten significant digits
  /// would cut an epoch stamp such as 1317357625.1 to whole seconds), non-finite ones as null, counted in
  /// non_finite_count().
  JsonWriter& value(double v) {
    comma();
    if (std::isfinite(v)) {
      char buf[32];
      const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
      out_ << std::string_view(buf, ec == std::errc() ? static_cast<std::size_t>(end - buf) : 0U);
    } else {
      out_ << "null";
      ++non_finite_;
    }
    return *this;
  }

  /// Non-finite numbers written as null so far (callers report it as a status).
  [[nodiscard]] std::size_t non_finite_count() const { return non_finite_; }
  JsonWriter& value(long long v) {
    comma();
    out_ << v;
    return *this;
  }
  JsonWriter& value(unsigned long long v) {
    comma();
    out_ << v;
    return *this;
  }
  JsonWriter& value(int v) { return value(static_cast<long long>(v)); }
  JsonWriter& value(unsigned v) { return value(static_cast<unsigned long long>(v)); }
  JsonWriter& value(unsigned long v) { return value(static_cast<unsigned long long>(v)); }
  JsonWriter& value(long v) { return value(static_cast<long long>(v)); }
  JsonWriter& value(bool v) {
    comma();
    out_ << (v ? "true" : "false");
    return *this;
  }
  JsonWriter& value(std::string_view s) {
    comma();
    string_literal(s);
    return *this;
  }
  JsonWriter& value(const char* s) { return value(std::string_view(s)); }

  /// `"name": value` in one call.
  template <typename T>
  JsonWriter& field(std::string_view name, const T& v) {
    key(name);
    return value(v);
  }

  /// `"name": [values...]`.
  template <typename Range>
  JsonWriter& array_field(std::string_view name, const Range& values) {
    key(name);
    begin_array();
    for (const auto& v : values) value(v);
    return end_array();
  }

 private:
  JsonWriter& open(char c) {
    comma();
    out_ << c;
    first_.push_back(true);
    return *this;
  }
  JsonWriter& close(char c) {
    out_ << c;
    first_.pop_back();
    return *this;
  }
  void comma() {
    if (pending_key_) {
      pending_key_ = false;
      return;
    }
    if (!first_.empty()) {
      if (!first_.back()) out_ << ',';
      first_.back() = false;
    }
  }
  void string_literal(std::string_view s) {
    out_ << '"';
    for (const char ch : s) {
      switch (ch) {
        case '"': out_ << "\\\""; break;
        case '\\': out_ << "\\\\"; break;
        case '\n': out_ << "\\n"; break;
        case '\t': out_ << "\\t"; break;
        default:
          if (static_cast<unsigned char>(ch) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(ch)));
            out_ << buf;
          } else {
            out_ << ch;
          }
      }
    }
    out_ << '"';
  }

  std::ostream& out_;
  std::vector<bool> first_;
  bool pending_key_ = false;
  std::size_t non_finite_ = 0;
};

}  // namespace semlio_examples
