#pragma once
/// \file
/// PLY (Stanford polygon format) point-cloud reader and writer.
///
/// Reader: `format ascii`, `binary_little_endian` and `binary_big_endian`
/// (version 1.0). Only the `vertex` element is read, property names matched
/// case-insensitively: x y z (required, any scalar type), intensity from
/// `intensity` or `scalar_intensity` (CloudCompare's name), `label` (integer:
/// SemanticKITTI raw id in the low 16 bits -> learning class, instance in the
/// high 16), `ring` (integer beam index) and `time` (seconds since sweep start). Other vertex
/// properties are skipped by their declared type; elements before `vertex` (scalar or list
/// properties) are skipped, elements after it are not read. A list property inside `vertex` is
/// rejected. Points with a NaN/Inf x, y, z, intensity or time and exact
/// (0,0,0) points are dropped and counted in ReadStats.
///
/// Writer: x y z intensity (float), ring (ushort), time (float), label (uint,
/// raw id | instance << 16) and the SemanticKITTI class colour (uchar red green
/// blue) so that CloudCompare and MeshLab show the classes; fields the scan
/// lacks are not written.

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/detail/cloud_io.hpp>
#include <semlio/io/read_stats.hpp>

namespace semlio::io {

/// Payload encoding of a written PLY file.
enum class PlyEncoding : std::uint8_t {
  kAscii,               ///< one text line per vertex
  kBinaryLittleEndian,  ///< packed little-endian records (the default)
  kBinaryBigEndian,     ///< packed big-endian records
};

namespace detail::ply {

/// One declared property of an element.
struct Property {
  std::string name;
  cloud::ScalarType type;
  bool is_list = false;
  cloud::ScalarType count_type;  ///< type of a list's length prefix
  std::size_t offset = 0;        ///< byte offset in a binary vertex record
};

/// One declared element (`element <name> <count>`).
struct Element {
  std::string name;
  std::size_t count = 0;
  long line = 0;
  std::vector<Property> properties;
};

/// A parsed header.
struct Header {
  PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian;
  std::vector<Element> elements;
  std::size_t data_offset = 0;  ///< byte offset of the payload
  long end_line = 0;            ///< line number of end_header
};

/// Throws FormatError("path:line: what").
[[noreturn]] inline void fail(const std::string& path, long line, const std::string& what) {
  throw FormatError(cloud::located(path, line, what));
}

/// Maps a PLY type name (both the classic and the sized spellings).
inline bool parse_type(std::string_view name, cloud::ScalarType& t) noexcept {
  using cloud::Kind;
  struct Row {
    std::string_view name;
    cloud::ScalarType type;
  };
  static constexpr Row kTypes[] = {
      {"char", {Kind::kInt, 1}},      {"int8", {Kind::kInt, 1}},      {"uchar", {Kind::kUint, 1}},
      {"uint8", {Kind::kUint, 1}},    {"short", {Kind::kInt, 2}},     {"int16", {Kind::kInt, 2}},
      {"ushort", {Kind::kUint, 2}},   {"uint16", {Kind::kUint, 2}},   {"int", {Kind::kInt, 4}},
      {"int32", {Kind::kInt, 4}},     {"uint", {Kind::kUint, 4}},     {"uint32", {Kind::kUint, 4}},
      {"float", {Kind::kFloat, 4}},   {"float32", {Kind::kFloat, 4}}, {"double", {Kind::kFloat, 8}},
      {"float64", {Kind::kFloat, 8}},
  };
  for (const Row& row : kTypes) {
    if (row.name == name) {
      t = row.type;
      return true;
    }
  }
  return false;
}

/// Reads the header from the `ply` magic line to `end_header`.
inline Header parse_header(const std::string& path, std::string_view bytes) {
  if (bytes.empty()) fail(path, 0, "empty file, expected a PLY header");
  Header h;
  cloud::LineCursor cursor(bytes, 0, 1);
  std::string_view line;
  std::vector<std::string_view> tok;
  if (!cursor.next(line) || line != "ply") {
    fail(path, 1, "not a PLY file: first line is not 'ply'");
  }
  bool have_format = false;
  bool have_end = false;
  while (!have_end && cursor.next(line)) {
    cloud::split_tokens(line, tok);
    const long ln = cursor.line();
    if (tok.empty()) continue;
    const std::string_view key = tok.front();
    if (key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      if (tok.size() != 3) fail(path, ln, "format line needs an encoding and a version");
      if (tok[1] == "ascii") {
        h.encoding = PlyEncoding::kAscii;
      } else if (tok[1] == "binary_little_endian") {
        h.encoding = PlyEncoding::kBinaryLittleEndian;
      } else if (tok[1] == "binary_big_endian") {
        h.encoding = PlyEncoding::kBinaryBigEndian;
      } else {
        fail(path, ln, "unknown PLY format '" + std::string(tok[1]) + "'");
      }
      if (tok[2] != "1.0") {
        fail(path, ln, "unsupported PLY version '" + std::string(tok[2]) + "' (expected 1.0)");
      }
      have_format = true;
    } else if (key == "element") {
      if (tok.size() != 3) fail(path, ln, "element line needs a name and a count");
      Element e;
      e.name = std::string(tok[1]);
      e.line = ln;
      std::uint64_t count = 0;
      if (!cloud::parse_integer(tok[2], count)) {
        fail(path, ln,
             "element '" + e.name + "' count '" + std::string(tok[2]) +
                 "' is not a non-negative integer");
      }
      e.count = static_cast<std::size_t>(count);
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) fail(path, ln, "property declared before any element");
      Property p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!parse_type(tok[2], p.count_type) || p.count_type.kind == cloud::Kind::kFloat) {
          fail(path, ln, "list count type '" + std::string(tok[2]) + "' is not an integer type");
        }
        if (!parse_type(tok[3], p.type)) {
          fail(path, ln, "unknown property type '" + std::string(tok[3]) + "'");
        }
        p.name = std::string(tok[4]);
      } else if (tok.size() == 3) {
        if (!parse_type(tok[1], p.type)) {
          fail(path, ln, "unknown property type '" + std::string(tok[1]) + "'");
        }
        p.name = std::string(tok[2]);
      } else {
        fail(path, ln, "malformed property line '" + std::string(line) + "'");
      }
      h.elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      have_end = true;
      h.end_line = ln;
      h.data_offset = cursor.offset();
    } else {
      fail(path, ln, "unknown PLY header keyword '" + std::string(key) + "'");
    }
  }
  if (!have_end) fail(path, 0, "header has no end_header line (truncated header)");
  if (!have_format) fail(path, 0, "header has no format line");
  return h;
}

/// Indices of the vertex properties the reader uses (-1 = absent).
struct VertexLayout {
  std::size_t element = 0;       ///< index of the vertex element
  cloud::Columns columns;        ///< indices of the used vertex properties
  std::size_t record_bytes = 0;  ///< bytes per binary vertex record
};

/// Finds the vertex element and its x/y/z/intensity/label/ring/time properties.
inline VertexLayout vertex_layout(const std::string& path, Header& h) {
  VertexLayout v;
  const auto it = std::find_if(h.elements.begin(), h.elements.end(),
                               [](const Element& e) { return e.name == "vertex"; });
  if (it == h.elements.end()) fail(path, 0, "header declares no 'vertex' element");
  v.element = static_cast<std::size_t>(it - h.elements.begin());
  for (std::size_t i = 0; i < it->properties.size(); ++i) {
    Property& p = it->properties[i];
    if (p.is_list) {
      fail(path, it->line, "list property '" + p.name + "' in the vertex element is unsupported");
    }
    p.offset = v.record_bytes;
    v.record_bytes += p.type.bytes;
    int* slot = v.columns.slot(p.name);
    if (slot == nullptr) continue;
    if (*slot >= 0) fail(path, it->line, "vertex property '" + p.name + "' is declared twice");
    *slot = static_cast<int>(i);
  }
  const cloud::Columns& c = v.columns;
  if (c.x < 0 || c.y < 0 || c.z < 0) fail(path, it->line, "vertex element lacks one of x, y, z");
  for (const int col : {c.label, c.ring}) {
    if (col < 0) continue;
    const Property& p = it->properties[static_cast<std::size_t>(col)];
    if (p.type.kind == cloud::Kind::kFloat) {
      fail(path, it->line, "vertex property '" + p.name + "' is a float, expected an integer type");
    }
  }
  return v;
}

/// Skips the binary instances of a non-vertex element; returns the new offset.
inline std::size_t skip_binary(const std::string& path, const Element& e, std::string_view bytes,
                               std::size_t pos, bool swap) {
  const auto need = [&](std::size_t n) {
    if (n > bytes.size() - pos) {
      fail(path, e.line,
           "truncated: element '" + e.name + "' runs past the end of the file (" +
               std::to_string(bytes.size()) + " bytes)");
    }
  };
  // Fixed-size records (no list property) are skipped in one step, so that a
  // huge declared count cannot make us loop.
  const bool has_list = std::any_of(e.properties.begin(), e.properties.end(),
                                    [](const Property& p) { return p.is_list; });
  if (!has_list) {
    std::size_t record = 0;
    for (const Property& p : e.properties) record += p.type.bytes;
    if (record != 0 && e.count > (bytes.size() - pos) / record) need(bytes.size() - pos + 1);
    return pos + record * e.count;
  }
  for (std::size_t k = 0; k < e.count; ++k) {
    for (const Property& p : e.properties) {
      if (p.is_list) {
        need(p.count_type.bytes);
        const std::uint32_t n = cloud::load_as_u32(bytes.data() + pos, p.count_type, swap);
        pos += p.count_type.bytes;
        need(static_cast<std::size_t>(n) * p.type.bytes);
        pos += static_cast<std::size_t>(n) * p.type.bytes;
      } else {
        need(p.type.bytes);
        pos += p.type.bytes;
      }
    }
  }
  return pos;
}

/// Decodes the vertex records of a binary payload starting at `pos`.
inline void read_binary(const std::string& path, const Header& h, const VertexLayout& v,
                        std::string_view bytes, Scan& scan, ReadStats& stats) {
  const bool swap =
      (h.encoding == PlyEncoding::kBinaryBigEndian) != (std::endian::native == std::endian::big);
  std::size_t pos = h.data_offset;
  for (std::size_t e = 0; e < v.element; ++e)
    pos = skip_binary(path, h.elements[e], bytes, pos, swap);
  const Element& ve = h.elements[v.element];
  const std::size_t available = bytes.size() - pos;
  if (v.record_bytes == 0 || ve.count > available / v.record_bytes) {
    fail(path, ve.line,
         "truncated: header declares " + std::to_string(ve.count) + " vertices (" +
             std::to_string(v.record_bytes) + " bytes each) but only " + std::to_string(available) +
             " bytes of vertex data follow");
  }
  cloud::reserve(scan, ve.count, v.columns);
  const auto prop = [&](int col) -> const Property& {
    return ve.properties[static_cast<std::size_t>(col)];
  };
  for (std::size_t k = 0; k < ve.count; ++k) {
    const char* rec = bytes.data() + pos + k * v.record_bytes;
    const cloud::PointRecord r = cloud::decode(
        v.columns,
        [&](int col) {
          return cloud::load_as_double(rec + prop(col).offset, prop(col).type, swap);
        },
        [&](int col) { return cloud::load_as_u32(rec + prop(col).offset, prop(col).type, swap); });
    if (cloud::keep_point(r, stats)) cloud::push_point(scan, v.columns, r);
  }
  // The same lie the ascii reader rejects: when vertex is the last element,
  // bytes after its records mean the header declares fewer vertices than the
  // file holds (or the file is not what the header says).
  const std::size_t rest = available - ve.count * v.record_bytes;
  if (v.element + 1 == h.elements.size() && rest != 0) {
    fail(path, ve.line,
         "header lies about its vertex count: " + std::to_string(ve.count) + " declared (" +
             std::to_string(v.record_bytes) + " bytes each) but " + std::to_string(rest) +
             " more bytes follow the last vertex");
  }
}

/// Decodes an ascii payload: one line per element instance.
inline void read_ascii(const std::string& path, const Header& h, const VertexLayout& v,
                       std::string_view bytes, Scan& scan, ReadStats& stats) {
  cloud::LineCursor cursor(bytes, h.data_offset, h.end_line + 1);
  std::string_view line;
  const auto next_data_line = [&](const Element& e, std::size_t k) {
    while (cursor.next(line)) {
      if (!cloud::is_blank(line)) return;
    }
    fail(path, e.line,
         "truncated: header declares " + std::to_string(e.count) + " '" + e.name +
             "' lines but only " + std::to_string(k) + " follow");
  };
  for (std::size_t e = 0; e < v.element; ++e) {
    for (std::size_t k = 0; k < h.elements[e].count; ++k) next_data_line(h.elements[e], k);
  }
  const Element& ve = h.elements[v.element];
  cloud::reserve(scan, std::min(ve.count, (bytes.size() - h.data_offset) / 2 + 1), v.columns);
  std::vector<std::string_view> tok;
  // Parses the token of property `col` as its declared type (value and bits).
  const auto parse = [&](int col, double& d, std::uint32_t& bits) {
    const Property& p = ve.properties[static_cast<std::size_t>(col)];
    const std::string_view t = tok[static_cast<std::size_t>(col)];
    if (!cloud::parse_typed(t, p.type, d, bits)) {
      fail(path, cursor.line(),
           "vertex property '" + p.name + "' value '" + std::string(t) +
               "' does not parse as its declared type");
    }
  };
  const auto real = [&](int col) {
    double d = 0.0;
    std::uint32_t b = 0;
    parse(col, d, b);
    return d;
  };
  const auto bits = [&](int col) {
    double d = 0.0;
    std::uint32_t b = 0;
    parse(col, d, b);
    return b;
  };
  for (std::size_t k = 0; k < ve.count; ++k) {
    next_data_line(ve, k);
    cloud::split_tokens(line, tok);
    if (tok.size() != ve.properties.size()) {
      fail(path, cursor.line(),
           "expected " + std::to_string(ve.properties.size()) + " vertex values, got " +
               std::to_string(tok.size()));
    }
    const cloud::PointRecord r = cloud::decode(v.columns, real, bits);
    if (cloud::keep_point(r, stats)) cloud::push_point(scan, v.columns, r);
  }
  if (v.element + 1 == h.elements.size()) {
    while (cursor.next(line)) {
      if (!cloud::is_blank(line)) {
        fail(path, cursor.line(),
             "header lies about its vertex count: " + std::to_string(ve.count) +
                 " declared but more lines follow");
      }
    }
  }
}

}  // namespace detail::ply

/// Parses the vertices of a PLY file already in memory (ascii or binary;
/// `path` names it in error messages) into a scan. Points with
/// a NaN/Inf coordinate, intensity or time and (0,0,0) points are dropped and added to `stats` when
/// given (added to, not reset). Throws FormatError naming the
/// path, line and bad value (bad header, truncated payload, list property in
/// the vertex element).
inline Scan parse_ply(std::string_view bytes, const std::string& path, ReadStats* stats = nullptr) {
  detail::ply::Header h = detail::ply::parse_header(path, bytes);
  const detail::ply::VertexLayout v = detail::ply::vertex_layout(path, h);
  Scan scan;
  ReadStats local;
  if (h.encoding == PlyEncoding::kAscii) {
    detail::ply::read_ascii(path, h, v, bytes, scan, local);
  } else {
    detail::ply::read_binary(path, h, v, bytes, scan, local);
  }
  detail::cloud::report(stats, local);
  return scan;
}

/// Reads the vertices of a PLY file; see parse_ply for the rules and errors,
/// plus IoError when the file is missing, unreadable or larger than
/// kMaxCloudFileBytes.
inline Scan read_ply(const std::string& path, ReadStats* stats = nullptr) {
  return parse_ply(detail::cloud::read_file_bytes(path), path, stats);
}

/// The bytes of a scan as PLY (binary little-endian by default): x y z, and when
/// present intensity (float), ring (ushort), time (float) and `label`
/// (uint, raw SemanticKITTI id | instance << 16) plus the class colour (uchar
/// red green blue, SemanticKITTI palette). Throws ValueError for an
/// inconsistent scan.
inline std::string format_ply(const Scan& scan, PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian) {
  scan.validate();
  namespace cloud = detail::cloud;
  const bool has_i = scan.has_intensity();
  const bool has_r = scan.has_rings();
  const bool has_t = scan.has_times();
  const bool has_l = scan.has_labels();
  std::string out = "ply\nformat ";
  out += encoding == PlyEncoding::kAscii                ? "ascii"
         : encoding == PlyEncoding::kBinaryLittleEndian ? "binary_little_endian"
                                                        : "binary_big_endian";
  out += " 1.0\ncomment written by semlio\n";
  if (has_l) out += "comment label: SemanticKITTI raw id | instance << 16; colour: class palette\n";
  out += "element vertex " + std::to_string(scan.size()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (has_i) out += "property float intensity\n";
  if (has_r) out += "property ushort ring\n";
  if (has_t) out += "property float time\n";
  if (has_l) {
    out += "property uint label\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n";
  }
  out += "end_header\n";
  const bool ascii = encoding == PlyEncoding::kAscii;
  const bool swap = !ascii && ((encoding == PlyEncoding::kBinaryBigEndian) !=
                               (std::endian::native == std::endian::big));
  out.reserve(out.size() + scan.size() * (ascii ? 80 : 29));
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const auto& p = scan.points[i];
    const std::uint32_t raw = has_l ? cloud::raw_label_of(scan, i) : 0U;
    const Rgb c = has_l ? class_colour(scan.labels[i]) : Rgb{0, 0, 0};
    if (ascii) {
      const auto text = [&out](auto v) {
        out += ' ';
        cloud::append_number(out, v);
      };
      cloud::append_number(out, p.x());
      text(p.y());
      text(p.z());
      if (has_i) text(scan.intensity[i]);
      if (has_r) text(std::uint32_t{scan.rings[i]});
      if (has_t) text(scan.times_s[i]);
      if (has_l) {
        text(raw);
        text(std::uint32_t{c.r});
        text(std::uint32_t{c.g});
        text(std::uint32_t{c.b});
      }
      out += '\n';
    } else {
      cloud::store(out, p.x(), swap);
      cloud::store(out, p.y(), swap);
      cloud::store(out, p.z(), swap);
      if (has_i) cloud::store(out, scan.intensity[i], swap);
      if (has_r) cloud::store(out, scan.rings[i], swap);
      if (has_t) cloud::store(out, scan.times_s[i], swap);
      if (has_l) {
        cloud::store(out, raw, swap);
        out += static_cast<char>(c.r);
        out += static_cast<char>(c.g);
        out += static_cast<char>(c.b);
      }
    }
  }
  return out;
}

/// Writes a scan as a PLY file (format_ply). Throws ValueError for an
/// inconsistent scan, IoError when the file cannot be written.
inline void write_ply(const std::string& path, const Scan& scan,
                      PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian) {
  detail::cloud::write_file_bytes(path, format_ply(scan, encoding));
}

}  // namespace semlio::io
