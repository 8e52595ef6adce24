#pragma once
/// \file
/// KITTI odometry / SemanticKITTI files: velodyne `.bin` scans, `.label`
/// files, `calib.txt` and `times.txt` (readers and writers).
///
/// `.bin`: little-endian float32 x, y, z, intensity per point (16 bytes).
/// `.label`: little-endian uint32 per point, semantic raw id in the low 16
/// bits, instance id in the high 16 bits. Points with a NaN/Inf value or at
/// exactly (0,0,0) are dropped on reading and counted in ReadStats; their
/// labels are dropped with them (read_kitti_scan), so labels stay aligned.

#include <Eigen/Core>

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/detail/pose_text.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

static_assert(std::endian::native == std::endian::little, "KITTI .bin/.label readers assume a little-endian host");

/// Largest KITTI scan the readers accept: 10 million points (160 MB of
/// `.bin`, 40 MB of `.label`). A real HDL-64E sweep holds ~120 000; the limit
/// only stops a wrong path (a huge file, /dev/zero) from exhausting memory.
inline constexpr std::size_t kMaxKittiBinPoints = 10'000'000;

namespace detail {

/// Checks the size of `.bin` bytes (non-empty, multiple of 16 bytes, at most
/// kMaxKittiBinPoints points); FormatError naming `name` and the size.
inline void check_bin_bytes(std::string_view bytes, const std::string& name) {
  if (bytes.empty()) throw FormatError(detail::where(name, 0, "empty .bin file (0 bytes)"));
  if (bytes.size() % 16 != 0) {
    throw FormatError(detail::where(name, 0,
                                    "size " + std::to_string(bytes.size()) +
                                        " bytes is not a multiple of 16 (float32 x, y, z, intensity per point)"));
  }
  if (bytes.size() / 16 > kMaxKittiBinPoints) {
    throw FormatError(detail::where(name, 0,
                                    "size " + std::to_string(bytes.size()) + " bytes is more than " +
                                        std::to_string(kMaxKittiBinPoints) +
                                        " points (16 bytes each), the limit for a KITTI .bin scan"));
  }
}

/// Reads a `.bin` file and checks its size (non-empty, multiple of 16 bytes,
/// at most kMaxKittiBinPoints points; regular files only).
inline std::string read_bin_bytes(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) {
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxKittiBinPoints * 16) {
      throw IoError(detail::where(path, 0,
                                  "size " + std::to_string(size) + " bytes is more than " +
                                      std::to_string(kMaxKittiBinPoints) +
                                      " points (16 bytes each), the limit for a KITTI .bin scan"));
    }
  }
  std::string bytes = read_file(path, kMaxKittiBinPoints * 16);
  check_bin_bytes(bytes, path);
  return bytes;
}

/// The scan of checked `.bin` bytes, with the raw labels of `raw` (one per
/// point of the file) when given; dropped points lose their label.
inline Scan scan_from_bin(std::string_view bytes, const std::vector<std::uint32_t>* raw, ReadStats* stats) {
  const std::size_t n = bytes.size() / 16;
  Scan scan;
  scan.points.reserve(n);
  scan.intensity.reserve(n);
  if (raw != nullptr) {
    scan.labels.reserve(n);
    scan.instances.reserve(n);
  }
  ReadStats local;
  for (std::size_t i = 0; i < n; ++i) {
    float v[4];
    std::memcpy(v, bytes.data() + 16 * i, sizeof(v));
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]) || !std::isfinite(v[3])) {
      ++local.dropped_nonfinite;
      continue;
    }
    if (v[0] == 0.0F && v[1] == 0.0F && v[2] == 0.0F) {
      ++local.dropped_zero;
      continue;
    }
    scan.points.emplace_back(v[0], v[1], v[2]);
    scan.intensity.push_back(v[3]);
    if (raw != nullptr) {
      scan.labels.push_back(learning_class((*raw)[i]));
      scan.instances.push_back(static_cast<std::uint16_t>((*raw)[i] >> 16));
    }
  }
  if (stats != nullptr) {
    stats->dropped_nonfinite += local.dropped_nonfinite;
    stats->dropped_zero += local.dropped_zero;
  }
  return scan;
}

}  // namespace detail

/// Parses the bytes of a `.label` file already in memory (`name` is used in
/// error messages): one uint32 per point. Throws FormatError (size not a
/// multiple of 4 bytes, more than kMaxKittiBinPoints labels) and ValueError
/// when the count differs from `expected_count` (naming both counts).
inline std::vector<std::uint32_t> parse_label_file(std::string_view bytes, const std::string& name,
                                                   std::size_t expected_count) {
  if (bytes.size() % 4 != 0) {
    throw FormatError(detail::where(
        name, 0, "size " + std::to_string(bytes.size()) + " bytes is not a multiple of 4 (uint32 per point)"));
  }
  const std::size_t n = bytes.size() / 4;
  if (n > kMaxKittiBinPoints) {
    throw FormatError(detail::where(name, 0,
                                    "holds " + std::to_string(n) + " labels, more than the limit of " +
                                        std::to_string(kMaxKittiBinPoints)));
  }
  if (n != expected_count) {
    throw ValueError(detail::where(name, 0,
                                   "label file has " + std::to_string(n) + " labels but the scan has " +
                                       std::to_string(expected_count) + " points"));
  }
  std::vector<std::uint32_t> raw(n);
  if (n != 0) std::memcpy(raw.data(), bytes.data(), bytes.size());
  return raw;
}

/// Reads a `.label` file: one uint32 per point. Throws IoError (missing),
/// FormatError (size not a multiple of 4 bytes) and ValueError when the count
/// differs from `expected_count` (the message names both counts and the path).
inline std::vector<std::uint32_t> read_label_file(const std::string& path, std::size_t expected_count) {
  return parse_label_file(detail::read_file(path, kMaxKittiBinPoints * 4), path, expected_count);
}

/// The bytes of a `.label` file (uint32 per point, little-endian).
inline std::string format_label_file(const std::vector<std::uint32_t>& raw) {
  std::string bytes(raw.size() * 4, '\0');
  if (!raw.empty()) std::memcpy(bytes.data(), raw.data(), bytes.size());
  return bytes;
}

/// Writes a `.label` file (uint32 per point, little-endian). Throws IoError.
inline void write_label_file(const std::string& path, const std::vector<std::uint32_t>& raw) {
  detail::write_file(path, format_label_file(raw));
}

/// Parses a velodyne scan and, when `label_bytes` is given, its labels from
/// bytes already in memory (`bin_name` and `label_name` are used in error
/// messages); the same rules as read_kitti_scan. Throws FormatError (empty
/// .bin, size not a multiple of 16 or 4) and ValueError (label count mismatch).
inline Scan parse_kitti_scan(std::string_view bin_bytes, const std::string& bin_name,
                             std::optional<std::string_view> label_bytes, const std::string& label_name,
                             ReadStats* stats = nullptr) {
  detail::check_bin_bytes(bin_bytes, bin_name);
  if (!label_bytes) return detail::scan_from_bin(bin_bytes, nullptr, stats);
  const std::vector<std::uint32_t> raw = parse_label_file(*label_bytes, label_name, bin_bytes.size() / 16);
  return detail::scan_from_bin(bin_bytes, &raw, stats);
}

/// Parses velodyne `.bin` bytes already in memory (`name` is used in error
/// messages); the same rules as read_kitti_bin. Throws FormatError.
inline Scan parse_kitti_bin(std::string_view bytes, const std::string& name, ReadStats* stats = nullptr) {
  return parse_kitti_scan(bytes, name, std::nullopt, {}, stats);
}

/// Reads a velodyne scan and, when `label_path` is given, its labels (learning
/// classes in `labels`, instance ids in `instances`). The label count must
/// equal the number of points in the file before dropping; dropped points lose
/// their label too. Throws IoError, FormatError (empty file, size not a
/// multiple of 16) and ValueError (label count mismatch).
inline Scan read_kitti_scan(const std::string& bin_path, const std::optional<std::string>& label_path,
                            ReadStats* stats = nullptr) {
  const std::string bytes = detail::read_bin_bytes(bin_path);
  if (!label_path) return detail::scan_from_bin(bytes, nullptr, stats);
  const std::vector<std::uint32_t> raw = read_label_file(*label_path, bytes.size() / 16);
  return detail::scan_from_bin(bytes, &raw, stats);
}

/// Reads a velodyne `.bin` scan (float32 x, y, z, intensity). Points with a
/// NaN/Inf value (coordinate or intensity) or exactly at (0,0,0) are dropped
/// and counted in `stats` (added to, not reset). Throws IoError (missing) and
/// FormatError (empty file, size not a multiple of 16, naming path and size).
inline Scan read_kitti_bin(const std::string& path, ReadStats* stats = nullptr) {
  return read_kitti_scan(path, std::nullopt, stats);
}

/// The bytes of a velodyne `.bin` scan (what write_kitti_bin writes);
/// intensity 0 when the scan has none. Throws ValueError for an inconsistent scan.
inline std::string format_kitti_bin(const Scan& scan) {
  scan.validate();
  std::string bytes(scan.size() * 16, '\0');
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const float v[4] = {scan.points[i].x(), scan.points[i].y(), scan.points[i].z(),
                        scan.has_intensity() ? scan.intensity[i] : 0.0F};
    std::memcpy(bytes.data() + 16 * i, v, sizeof(v));
  }
  return bytes;
}

/// Writes a velodyne `.bin` scan; intensity 0 when the scan has none. An empty
/// scan gives an empty file (which the reader rejects). Throws IoError.
inline void write_kitti_bin(const std::string& path, const Scan& scan) {
  detail::write_file(path, format_kitti_bin(scan));
}

/// Raw SemanticKITTI labels of a scan: raw_id(label) | instance << 16 (all 0
/// when the scan has no labels). Learning classes map back to their static raw
/// id (car -> 10), so moving/static raw distinctions are not preserved.
inline std::vector<std::uint32_t> raw_labels(const Scan& scan) {
  scan.validate();
  std::vector<std::uint32_t> raw(scan.size(), 0U);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const std::uint32_t semantic = scan.has_labels() ? raw_id(scan.labels[i]) : 0U;
    const std::uint32_t instance = scan.has_instances() ? scan.instances[i] : 0U;
    raw[i] = semantic | (instance << 16);
  }
  return raw;
}

/// Writes a scan's `.bin` and, when `label_path` is given, its `.label`
/// (raw_labels(scan)); the pair read_kitti_scan reads back. Throws IoError.
inline void write_kitti_scan(const std::string& bin_path, const std::optional<std::string>& label_path,
                             const Scan& scan) {
  write_kitti_bin(bin_path, scan);
  if (label_path) write_label_file(*label_path, raw_labels(scan));
}

/// KITTI odometry calibration (calib.txt): every `name: numbers` line, with the
/// two transforms semlio uses parsed and validated.
struct Calibration {
  std::optional<SE3d> T_cam0_velo;                     ///< `Tr`: velodyne into camera-0 coordinates
  std::optional<SE3d> T_imu_velo;                      ///< `Tr_imu_velo`: velodyne into IMU coordinates
  std::map<std::string, std::vector<double>> entries;  ///< every named line as read (incl. Tr)
};

/// Parses calib.txt text already in memory (`path` names it in error
/// messages): lines `name: v1 v2 ...` (blank lines skipped). `Tr` and
/// `Tr_imu_velo` must hold 12 numbers forming a valid rigid transform. Throws
/// IoError (missing), FormatError (empty file, no ':', empty or spaced name,
/// no values, non-numeric value, duplicate name, Tr with != 12 values) and
/// ValueError (NaN/Inf, non-orthonormal rotation), naming path and line.
inline Calibration parse_kitti_calib(std::string_view text, const std::string& path) {
  Calibration calib;
  std::vector<std::string_view> tok;
  detail::for_each_line(text, [&](long line, std::string_view s) {
    if (detail::is_blank(s)) return;
    const std::size_t colon = s.find(':');
    if (colon == std::string_view::npos) {
      throw FormatError(
          detail::where(path, line, "calib line has no 'name:' prefix: '" + std::string(detail::trim(s)) + "'"));
    }
    const std::string name(detail::trim(s.substr(0, colon)));
    if (name.empty() || name.find_first_of(" \t") != std::string::npos) {
      throw FormatError(detail::where(path, line, "calib line has a bad name '" + name + "'"));
    }
    if (calib.entries.count(name) != 0) {
      throw FormatError(detail::where(path, line, "calib entry '" + name + "' appears twice"));
    }
    detail::split_ws(s.substr(colon + 1), tok);
    if (tok.empty()) throw FormatError(detail::where(path, line, "calib entry '" + name + "' has no values"));
    std::vector<double> values;
    values.reserve(tok.size());
    for (std::size_t i = 0; i < tok.size(); ++i) {
      const double v = detail::parse_double(tok[i], path, line, i + 1, "calib '" + name + "'");
      if (!std::isfinite(v)) {
        throw ValueError(detail::where(
            path, line,
            "calib '" + name + "' field " + std::to_string(i + 1) + " ('" + std::string(tok[i]) + "') is not finite"));
      }
      values.push_back(v);
    }
    if (name == "Tr" || name == "Tr_imu_velo") {
      if (values.size() != 12) {
        throw FormatError(detail::where(
            path, line,
            "calib '" + name + "' has " + std::to_string(values.size()) + " values, expected 12 (3x4 row-major)"));
      }
      const SE3d T = detail::pose_from_3x4(values.data(), path, line, "calib '" + name + "'");
      (name == "Tr" ? calib.T_cam0_velo : calib.T_imu_velo) = T;
    }
    calib.entries.emplace(name, std::move(values));
  });
  if (calib.entries.empty()) throw FormatError(detail::where(path, 0, "empty calib file (no entries)"));
  return calib;
}

/// Reads calib.txt; see parse_kitti_calib for the rules and errors, plus
/// IoError when the file is missing or unreadable.
inline Calibration read_kitti_calib(const std::string& path) {
  return parse_kitti_calib(detail::read_file(path), path);
}

/// The text of calib.txt: every entry in name order, `Tr` / `Tr_imu_velo` taken from
/// the transforms when set (they override an entry of the same name). Numbers
/// are the shortest text that reads back exactly.
inline std::string format_kitti_calib(const Calibration& calib) {
  std::map<std::string, std::vector<double>> entries = calib.entries;
  const auto put = [&entries](const std::string& name, const std::optional<SE3d>& T) {
    if (!T) return;
    const Eigen::Matrix4d M = T->matrix();
    std::vector<double> v;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) v.push_back(M(r, c));
    }
    entries[name] = std::move(v);
  };
  put("Tr", calib.T_cam0_velo);
  put("Tr_imu_velo", calib.T_imu_velo);
  std::string out;
  for (const auto& [name, values] : entries) {
    out += name;
    out += ':';
    for (const double v : values) {
      out.push_back(' ');
      detail::append_double(out, v);
    }
    out.push_back('\n');
  }
  return out;
}

/// Writes calib.txt (format_kitti_calib). Throws IoError.
inline void write_kitti_calib(const std::string& path, const Calibration& calib) {
  detail::write_file(path, format_kitti_calib(calib));
}

/// Parses times.txt text already in memory (`path` names it in error
/// messages): one timestamp [s] per line (frame i on line i+1). Throws
/// FormatError (empty file, blank line, more than one
/// field, non-numeric) and ValueError (NaN/Inf, time going backwards; equal
/// consecutive times are accepted), naming path and line.
inline std::vector<double> parse_kitti_times(std::string_view text, const std::string& path) {
  std::vector<double> times;
  detail::for_each_record(text, path, "times", [&](long line, std::string_view, const auto& tok) {
    if (tok.size() != 1) {
      throw FormatError(
          detail::where(path, line, "times line has " + std::to_string(tok.size()) + " fields, expected 1"));
    }
    const double t = detail::parse_double(tok[0], path, line, 1, "time");
    if (!std::isfinite(t)) {
      throw ValueError(detail::where(path, line, "time '" + std::string(tok[0]) + "' is not finite"));
    }
    if (!times.empty() && t < times.back()) {
      throw ValueError(detail::where(
          path, line,
          "time " + std::string(tok[0]) + " s goes backwards (previous line: " + std::to_string(times.back()) + " s)"));
    }
    times.push_back(t);
  });
  if (times.empty()) throw FormatError(detail::where(path, 0, "empty times file (no timestamps)"));
  return times;
}

/// Reads times.txt; see parse_kitti_times for the rules and errors, plus
/// IoError when the file is missing or unreadable.
inline std::vector<double> read_kitti_times(const std::string& path) {
  return parse_kitti_times(detail::read_file(path), path);
}

/// The text of times.txt: one timestamp [s] per line as the shortest text
/// that reads back exactly.
inline std::string format_kitti_times(const std::vector<double>& times_s) {
  std::string out;
  out.reserve(times_s.size() * 24);
  for (const double t : times_s) {
    detail::append_double(out, t);
    out.push_back('\n');
  }
  return out;
}

/// Writes times.txt (format_kitti_times). Throws IoError.
inline void write_kitti_times(const std::string& path, const std::vector<double>& times_s) {
  detail::write_file(path, format_kitti_times(times_s));
}

}  // namespace semlio::io
