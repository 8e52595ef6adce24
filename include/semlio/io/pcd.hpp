#pragma once
/// \file
/// PCD v0.7 (the Point Cloud Library's format) reader and writer.
///
/// Reader: header keys VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT,
/// VIEWPOINT, POINTS, DATA; `DATA ascii` and `DATA binary` (little-endian, as
/// PCL writes on every common platform); `binary_compressed` is rejected with a
/// FormatError saying so. Fields may come in any order with any extra fields
/// (skipped by SIZE*COUNT). Used fields (names case-insensitive): x y z
/// (required), intensity, label (integer: SemanticKITTI raw id in the low 16
/// bits -> learning class, instance in the high 16 bits), ring (integer beam
/// index) and time (seconds since sweep start), the last two as Velodyne
/// drivers and LIO-SAM write them. Numeric types F/U/I of 1/2/4/8 bytes are
/// converted. Bytes after the binary payload are ignored (real KITTI raw
/// exports carry ~3.9 kB of zero padding). Points with a NaN/Inf x, y, z,
/// intensity or time and exact (0,0,0) points are dropped and counted in
/// ReadStats. The VIEWPOINT is parsed but not applied (points stay in the
/// file's frame). Organised clouds (HEIGHT > 1) are read row by row.

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/detail/cloud_io.hpp>
#include <semlio/io/read_stats.hpp>

namespace semlio::io {

/// Payload encoding of a written PCD file.
enum class PcdEncoding : std::uint8_t {
  kAscii,   ///< one text line per point, shortest round-trip float text
  kBinary,  ///< packed little-endian records
};

namespace detail::pcd {

/// One declared field: name, scalar type, element count, byte offset in a record.
struct Field {
  std::string name;
  cloud::ScalarType type;
  std::size_t count = 1;
  std::size_t offset = 0;  ///< byte offset in a binary record
  std::size_t token = 0;   ///< index of its first token in an ascii line
};

/// A parsed and validated header.
struct Header {
  std::vector<Field> fields;
  std::size_t width = 0;
  std::size_t height = 0;
  std::size_t points = 0;
  std::size_t record_bytes = 0;  ///< bytes per binary point record
  std::size_t tokens = 0;        ///< tokens per ascii line
  bool ascii = false;
  std::size_t data_offset = 0;  ///< byte offset of the payload
  long data_line = 0;           ///< line number of the DATA line
  cloud::Columns columns;       ///< indices into `fields` of the used columns
};

using semlio::io::detail::checked_add;
using semlio::io::detail::checked_mul;

/// Throws FormatError("path:line: what").
[[noreturn]] inline void fail(const std::string& path, long line, const std::string& what) {
  throw FormatError(cloud::located(path, line, what));
}

/// Parses a non-negative count token of a header line.
inline std::size_t parse_count(const std::string& path, long line, std::string_view key,
                               std::string_view tok) {
  std::uint64_t v = 0;
  if (!cloud::parse_integer(tok, v)) {
    fail(path, line,
         std::string(key) + " value '" + std::string(tok) + "' is not a non-negative integer");
  }
  return static_cast<std::size_t>(v);
}

/// Reads the header lines up to and including DATA and validates them.
inline Header parse_header(const std::string& path, std::string_view bytes) {
  if (bytes.empty()) fail(path, 0, "empty file, expected a PCD header");
  Header h;
  std::vector<std::string_view> tok;
  std::vector<std::string_view> names, sizes, types, counts;
  long fields_line = 0, size_line = 0, type_line = 0, count_line = 0, points_line = 0;
  bool have_width = false, have_height = false, have_points = false, have_data = false;
  cloud::LineCursor cursor(bytes, 0, 1);
  std::string_view line;
  while (!have_data && cursor.next(line)) {
    cloud::split_tokens(line, tok);
    if (tok.empty() || tok.front().front() == '#') continue;
    const std::string_view key = tok.front();
    const long ln = cursor.line();
    const auto need = [&](std::size_t n) {
      if (tok.size() != n + 1) {
        fail(path, ln,
             std::string(key) + " expects " + std::to_string(n) + " value(s), got " +
                 std::to_string(tok.size() - 1));
      }
    };
    const auto rest = [&]() { return std::vector<std::string_view>(tok.begin() + 1, tok.end()); };
    if (key == "VERSION") {
      need(1);
      const std::string_view v = tok[1];
      if (v != "0.7" && v != ".7" && v != "0.6" && v != ".6" && v != "0.5" && v != ".5") {
        fail(path, ln, "unsupported PCD VERSION '" + std::string(v) + "' (expected 0.7)");
      }
    } else if (key == "FIELDS") {
      if (tok.size() < 2) fail(path, ln, "FIELDS lists no field");
      names = rest();
      fields_line = ln;
    } else if (key == "SIZE") {
      sizes = rest();
      size_line = ln;
    } else if (key == "TYPE") {
      types = rest();
      type_line = ln;
    } else if (key == "COUNT") {
      counts = rest();
      count_line = ln;
    } else if (key == "WIDTH") {
      need(1);
      h.width = parse_count(path, ln, key, tok[1]);
      have_width = true;
    } else if (key == "HEIGHT") {
      need(1);
      h.height = parse_count(path, ln, key, tok[1]);
      have_height = true;
    } else if (key == "POINTS") {
      need(1);
      h.points = parse_count(path, ln, key, tok[1]);
      have_points = true;
      points_line = ln;
    } else if (key == "VIEWPOINT") {
      need(7);
      for (std::size_t i = 1; i < tok.size(); ++i) {
        double v = 0.0;
        if (!cloud::parse_double(tok[i], v)) {
          fail(path, ln, "VIEWPOINT value '" + std::string(tok[i]) + "' is not a number");
        }
      }
    } else if (key == "DATA") {
      need(1);
      if (tok[1] == "ascii") {
        h.ascii = true;
      } else if (tok[1] == "binary") {
        h.ascii = false;
      } else if (tok[1] == "binary_compressed") {
        fail(path, ln, "DATA binary_compressed is unsupported (re-save as ascii or binary)");
      } else {
        fail(path, ln, "unknown DATA encoding '" + std::string(tok[1]) + "'");
      }
      have_data = true;
      h.data_line = ln;
      h.data_offset = cursor.offset();
    } else {
      fail(path, ln, "unknown PCD header key '" + std::string(key) + "'");
    }
  }
  if (!have_data) fail(path, 0, "header has no DATA line (not a PCD file, or truncated header)");
  if (names.empty()) fail(path, 0, "header has no FIELDS line");
  if (sizes.empty()) fail(path, 0, "header has no SIZE line");
  if (types.empty()) fail(path, 0, "header has no TYPE line");
  if (!have_width) fail(path, 0, "header has no WIDTH line");
  if (!have_height) fail(path, 0, "header has no HEIGHT line");
  const std::size_t n = names.size();
  if (sizes.size() != n) {
    fail(path, size_line,
         "SIZE has " + std::to_string(sizes.size()) + " values but FIELDS (line " +
             std::to_string(fields_line) + ") has " + std::to_string(n));
  }
  if (types.size() != n) {
    fail(
        path, type_line,
        "TYPE has " + std::to_string(types.size()) + " values but FIELDS has " + std::to_string(n));
  }
  if (!counts.empty() && counts.size() != n) {
    fail(path, count_line,
         "COUNT has " + std::to_string(counts.size()) + " values but FIELDS has " +
             std::to_string(n));
  }
  // Fields: type, size and count per column, record offsets and token indices.
  for (std::size_t i = 0; i < n; ++i) {
    Field f;
    f.name = std::string(names[i]);
    f.type.bytes = parse_count(path, size_line, "SIZE", sizes[i]);
    if (types[i] == "F") {
      f.type.kind = cloud::Kind::kFloat;
    } else if (types[i] == "U") {
      f.type.kind = cloud::Kind::kUint;
    } else if (types[i] == "I") {
      f.type.kind = cloud::Kind::kInt;
    } else {
      fail(path, type_line,
           "TYPE of field '" + f.name + "' is '" + std::string(types[i]) + "', expected F, U or I");
    }
    if (!cloud::is_valid(f.type)) {
      fail(path, size_line,
           "field '" + f.name + "' has SIZE " + std::to_string(f.type.bytes) + " which TYPE " +
               std::string(types[i]) + " does not allow");
    }
    if (!counts.empty()) {
      f.count = parse_count(path, count_line, "COUNT", counts[i]);
      if (f.count == 0) fail(path, count_line, "COUNT of field '" + f.name + "' is 0");
      // Every value takes at least one byte in either encoding, so a COUNT
      // above the file size is a lie; it also keeps the sums below small.
      if (f.count > bytes.size()) {
        fail(path, count_line,
             "COUNT of field '" + f.name + "' is " + std::to_string(f.count) +
                 ", more values per point than the file has bytes (" + std::to_string(bytes.size()) +
                 ")");
      }
    }
    f.offset = h.record_bytes;
    f.token = h.tokens;
    // Checked sums: offsets and token indices index into the payload, so a
    // wrapped sum would read outside it.
    const auto field_bytes = checked_mul(f.type.bytes, f.count);
    const auto record = field_bytes ? checked_add(h.record_bytes, *field_bytes) : std::nullopt;
    const auto tokens = checked_add(h.tokens, f.count);
    if (!record || !tokens) {
      fail(path, count_line,
           "SIZE * COUNT summed over the fields overflows at field '" + f.name + "' (COUNT " +
               std::to_string(f.count) + ")");
    }
    h.record_bytes = *record;
    h.tokens = *tokens;
    const auto index = static_cast<int>(i);
    int* slot = h.columns.slot(f.name);
    if (slot != nullptr) {
      if (*slot >= 0) fail(path, fields_line, "field '" + f.name + "' is declared twice");
      if (f.count != 1) {
        fail(path, count_line,
             "field '" + f.name + "' has COUNT " + std::to_string(f.count) + ", expected 1");
      }
      *slot = index;
    }
    h.fields.push_back(std::move(f));
  }
  const cloud::Columns& c = h.columns;
  if (c.x < 0 || c.y < 0 || c.z < 0) fail(path, fields_line, "FIELDS lacks one of x, y, z");
  for (const int col : {c.label, c.ring}) {
    if (col >= 0 && h.fields[static_cast<std::size_t>(col)].type.kind == cloud::Kind::kFloat) {
      fail(path, type_line,
           "field '" + h.fields[static_cast<std::size_t>(col)].name +
               "' has TYPE F, expected an integer type (U or I)");
    }
  }
  // The point count: POINTS must agree with WIDTH * HEIGHT (a header that lies).
  const std::size_t wh = h.width * h.height;
  if (h.height != 0 && wh / h.height != h.width) fail(path, 0, "WIDTH * HEIGHT overflows");
  if (have_points && h.points != wh) {
    fail(path, points_line,
         "header lies about its point count: POINTS " + std::to_string(h.points) + " but WIDTH " +
             std::to_string(h.width) + " * HEIGHT " + std::to_string(h.height) + " = " +
             std::to_string(wh));
  }
  h.points = wh;
  return h;
}

/// Decodes the binary payload (records of h.record_bytes, little-endian).
inline void read_binary(const std::string& path, const Header& h, std::string_view bytes,
                        Scan& scan, ReadStats& stats) {
  const std::size_t available = bytes.size() - h.data_offset;
  if (h.record_bytes == 0 || h.points > available / h.record_bytes) {
    fail(path, h.data_line,
         "header says POINTS " + std::to_string(h.points) + " (" + std::to_string(h.record_bytes) +
             " bytes each) but only " + std::to_string(available) + " bytes of data follow");
  }
  constexpr bool kSwap = std::endian::native != std::endian::little;
  cloud::reserve(scan, h.points, h.columns);
  const char* data = bytes.data() + h.data_offset;
  for (std::size_t i = 0; i < h.points; ++i) {
    const char* rec = data + i * h.record_bytes;
    const auto field = [&](int col) -> const Field& {
      return h.fields[static_cast<std::size_t>(col)];
    };
    const cloud::PointRecord r = cloud::decode(
        h.columns,
        [&](int col) {
          return cloud::load_as_double(rec + field(col).offset, field(col).type, kSwap);
        },
        [&](int col) {
          return cloud::load_as_u32(rec + field(col).offset, field(col).type, kSwap);
        });
    if (cloud::keep_point(r, stats)) cloud::push_point(scan, h.columns, r);
  }
}

/// Decodes the ascii payload: one line per point, SUM(COUNT) tokens per line.
inline void read_ascii(const std::string& path, const Header& h, std::string_view bytes, Scan& scan,
                       ReadStats& stats) {
  // A lying POINTS must not make us allocate: a line holds at least 2 bytes.
  cloud::reserve(scan, std::min(h.points, (bytes.size() - h.data_offset) / 2 + 1), h.columns);
  std::vector<std::string_view> tok;
  cloud::LineCursor cursor(bytes, h.data_offset, h.data_line + 1);
  std::string_view line;
  std::size_t read = 0;
  // Parses the token of column `col` as its declared type (value and bits).
  const auto parse = [&](int col, double& v, std::uint32_t& bits) {
    const Field& f = h.fields[static_cast<std::size_t>(col)];
    if (!cloud::parse_typed(tok[f.token], f.type, v, bits)) {
      fail(path, cursor.line(),
           "field '" + f.name + "' value '" + std::string(tok[f.token]) + "' is not a valid " +
               std::to_string(f.type.bytes) + "-byte " +
               (f.type.kind == cloud::Kind::kFloat  ? "float"
                : f.type.kind == cloud::Kind::kUint ? "unsigned integer"
                                                    : "integer"));
    }
  };
  const auto real = [&](int col) {
    double v = 0.0;
    std::uint32_t bits = 0;
    parse(col, v, bits);
    return v;
  };
  const auto bits = [&](int col) {
    double v = 0.0;
    std::uint32_t b = 0;
    parse(col, v, b);
    return b;
  };
  while (cursor.next(line)) {
    if (cloud::is_blank(line)) continue;
    if (read == h.points) {
      fail(path, cursor.line(),
           "header lies about its point count: POINTS " + std::to_string(h.points) +
               " but more data lines follow");
    }
    cloud::split_tokens(line, tok);
    if (tok.size() != h.tokens) {
      fail(path, cursor.line(),
           "expected " + std::to_string(h.tokens) + " values, got " + std::to_string(tok.size()));
    }
    ++read;
    const cloud::PointRecord r = cloud::decode(h.columns, real, bits);
    if (cloud::keep_point(r, stats)) cloud::push_point(scan, h.columns, r);
  }
  if (read != h.points) {
    fail(path, h.data_line,
         "header says POINTS " + std::to_string(h.points) + " but only " + std::to_string(read) +
             " data lines follow");
  }
}

}  // namespace detail::pcd

/// Parses the bytes of a PCD v0.7 file already in memory (ascii or binary;
/// `path` names it in error messages) into a scan in the file's frame.
/// Points with a NaN/Inf coordinate, intensity or time and (0,0,0) points are dropped and added to
/// `stats` when given (added to, not reset). Throws FormatError naming the path, line and bad value (bad header, a header that
/// lies about its point count, truncated payload, binary_compressed).
inline Scan parse_pcd(std::string_view bytes, const std::string& path, ReadStats* stats = nullptr) {
  const detail::pcd::Header h = detail::pcd::parse_header(path, bytes);
  Scan scan;
  ReadStats local;
  if (h.ascii) {
    detail::pcd::read_ascii(path, h, bytes, scan, local);
  } else {
    detail::pcd::read_binary(path, h, bytes, scan, local);
  }
  detail::cloud::report(stats, local);
  return scan;
}

/// Reads a PCD v0.7 file; see parse_pcd for the rules and errors, plus
/// IoError when the file is missing, unreadable or larger than
/// kMaxCloudFileBytes.
inline Scan read_pcd(const std::string& path, ReadStats* stats = nullptr) {
  return parse_pcd(detail::cloud::read_file_bytes(path), path, stats);
}

/// The bytes of a PCD v0.7 file: x y z (float32) and, when the scan has them, intensity (float32),
/// label (uint32 raw SemanticKITTI id | instance << 16), ring (uint16) and time
/// (float32 seconds) as PCD v0.7, one row (HEIGHT 1). Ascii floats use the shortest text that reads
/// back bit-exactly. Throws ValueError for an inconsistent scan.
inline std::string format_pcd(const Scan& scan, PcdEncoding encoding = PcdEncoding::kBinary) {
  scan.validate();
  namespace cloud = detail::cloud;
  const bool has_i = scan.has_intensity();
  const bool has_l = scan.has_labels();
  const bool has_r = scan.has_rings();
  const bool has_t = scan.has_times();
  const std::string n = std::to_string(scan.size());
  std::string fields = "FIELDS x y z", sizes = "SIZE 4 4 4", types = "TYPE F F F",
              counts = "COUNT 1 1 1";
  const auto column = [&](bool present, const char* name, const char* size, const char* type) {
    if (!present) return;
    (fields += ' ') += name;
    (sizes += ' ') += size;
    (types += ' ') += type;
    counts += " 1";
  };
  column(has_i, "intensity", "4", "F");
  column(has_l, "label", "4", "U");
  column(has_r, "ring", "2", "U");
  column(has_t, "time", "4", "F");
  std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  out += fields + "\n" + sizes + "\n" + types + "\n" + counts + "\n";
  out += "WIDTH " + n + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + n + "\n";
  const bool ascii = encoding == PcdEncoding::kAscii;
  out += ascii ? "DATA ascii\n" : "DATA binary\n";
  out.reserve(out.size() + scan.size() * (ascii ? 64 : 26));
  constexpr bool kSwap = std::endian::native != std::endian::little;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const auto& p = scan.points[i];
    if (ascii) {
      const auto text = [&out](auto v) {
        out += ' ';
        cloud::append_number(out, v);
      };
      cloud::append_number(out, p.x());
      text(p.y());
      text(p.z());
      if (has_i) text(scan.intensity[i]);
      if (has_l) text(cloud::raw_label_of(scan, i));
      if (has_r) text(std::uint32_t{scan.rings[i]});
      if (has_t) text(scan.times_s[i]);
      out += '\n';
    } else {
      cloud::store(out, p.x(), kSwap);
      cloud::store(out, p.y(), kSwap);
      cloud::store(out, p.z(), kSwap);
      if (has_i) cloud::store(out, scan.intensity[i], kSwap);
      if (has_l) cloud::store(out, cloud::raw_label_of(scan, i), kSwap);
      if (has_r) cloud::store(out, scan.rings[i], kSwap);
      if (has_t) cloud::store(out, scan.times_s[i], kSwap);
    }
  }
  return out;
}

/// Writes a scan as a PCD v0.7 file (format_pcd). Throws ValueError for an
/// inconsistent scan, IoError when the file cannot be written.
inline void write_pcd(const std::string& path, const Scan& scan, PcdEncoding encoding = PcdEncoding::kBinary) {
  detail::cloud::write_file_bytes(path, format_pcd(scan, encoding));
}

}  // namespace semlio::io
