#pragma once
/// \file
/// KITTI raw OXTS (GPS/IMU) files: `oxts/timestamps.txt` (one date-time string
/// per record, `2011-09-26 13:02:25.594360375`) and `oxts/data/NNNNNNNNNN.txt`
/// (one line of 30 whitespace-separated fields per record), reader and writer,
/// plus conversion into IMU samples and poses.
///
/// Time: timestamps become "Unix-like" seconds: seconds since 1970-01-01
/// 00:00:00 of the same (unspecified) clock, with no time-zone or leap-second
/// correction applied — KITTI's strings are local time, and semlio only needs
/// differences. As a double near 1.3e9 s the resolution is about 0.24 us, so
/// the nanosecond digits are rounded to that.
///
/// Frames (KITTI raw devkit): the IMU body frame is x forward, y left, z up;
/// roll/pitch/yaw rotate it from a local east-north-up frame,
/// R = Rz(yaw) * Ry(pitch) * Rx(roll) (yaw 0 = east, counter-clockwise
/// positive; pitch positive = nose down; roll positive = left side up).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/io/detail/civil_time.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// One OXTS record: all 30 fields of a KITTI raw `oxts/data/*.txt` line in
/// file order, plus its timestamp.
struct OxtsRecord {
  double stamp_s = 0.0;    ///< Unix-like seconds (see the file comment)
  double lat_deg = 0.0;    ///< latitude [deg]
  double lon_deg = 0.0;    ///< longitude [deg]
  double alt_m = 0.0;      ///< altitude [m]
  double roll_rad = 0.0;   ///< roll: 0 = level, positive = left side up
  double pitch_rad = 0.0;  ///< pitch: 0 = level, positive = front down
  double yaw_rad = 0.0;    ///< heading: 0 = east, positive = counter-clockwise
  double vn_mps = 0.0;     ///< velocity towards north
  double ve_mps = 0.0;     ///< velocity towards east
  /// vf, vl, vu: forward/left velocity parallel to the earth surface, upward
  /// velocity perpendicular to it (levelled frame, not the body frame).
  Eigen::Vector3d velocity_flu_mps = Eigen::Vector3d::Zero();
  /// ax, ay, az: specific force in the body frame (x front, y left, z top).
  Eigen::Vector3d accel_body_mps2 = Eigen::Vector3d::Zero();
  /// af, al, au: forward/left/upward acceleration (levelled frame).
  Eigen::Vector3d accel_flu_mps2 = Eigen::Vector3d::Zero();
  /// wx, wy, wz: angular rate about the body axes.
  Eigen::Vector3d gyro_body_radps = Eigen::Vector3d::Zero();
  /// wf, wl, wu: angular rate about the forward/left/upward axes (levelled).
  Eigen::Vector3d gyro_flu_radps = Eigen::Vector3d::Zero();
  double pos_accuracy_m = 0.0;    ///< position accuracy (north/east)
  double vel_accuracy_mps = 0.0;  ///< velocity accuracy (north/east)
  int navstat = 0;                ///< navigation status
  int numsats = 0;                ///< satellites tracked by the primary receiver
  int posmode = 0;                ///< position mode of the primary receiver
  int velmode = 0;                ///< velocity mode of the primary receiver
  int orimode = 0;                ///< orientation mode of the primary receiver
};

/// Number of fields of one OXTS data line.
inline constexpr std::size_t kOxtsFieldCount = 30;

/// Parses `YYYY-MM-DD HH:MM:SS[.fraction]` into Unix-like seconds (no time
/// zone applied). Throws FormatError "path:line: ..." naming the text when
/// malformed or out of range (month 1-12, valid day, hour < 24, minute < 60,
/// second < 61).
inline double parse_oxts_timestamp(std::string_view text, const std::string& path = "<string>", long line = 0) {
  const std::string_view t = detail::trim(text);
  const auto fail = [&](const std::string& why) -> double {
    throw FormatError(detail::where(
        path, line, "timestamp '" + std::string(t) + "' " + why + " (expected YYYY-MM-DD HH:MM:SS.fraction)"));
  };
  const auto tok = detail::split_ws(t);
  if (tok.size() != 2) return fail("does not have a date and a time");
  const std::string_view date = tok[0];
  const std::string_view time = tok[1];
  if (date.size() != 10 || date[4] != '-' || date[7] != '-') return fail("has a malformed date");
  if (time.size() < 8 || time[2] != ':' || time[5] != ':') return fail("has a malformed time");
  const std::int64_t y = detail::digits_value(date.substr(0, 4));
  const std::int64_t mo = detail::digits_value(date.substr(5, 2));
  const std::int64_t d = detail::digits_value(date.substr(8, 2));
  const std::int64_t h = detail::digits_value(time.substr(0, 2));
  const std::int64_t mi = detail::digits_value(time.substr(3, 2));
  const std::string_view sec_text = time.substr(6);
  if (detail::digits_value(sec_text.substr(0, 2)) < 0 || (sec_text.size() > 2 && sec_text[2] != '.') ||
      (sec_text.size() > 3 && !detail::all_digits(sec_text.substr(3))) || sec_text.size() == 3) {
    return fail("has malformed seconds");
  }
  const auto sec = detail::to_double(sec_text);
  if (y < 0 || mo < 1 || mo > 12 || d < 1 || h < 0 || h > 23 || mi < 0 || mi > 59 || !sec || *sec >= 61.0) {
    return fail("is out of range");
  }
  if (d > detail::days_in_month(y, static_cast<int>(mo))) return fail("has no such day");
  const std::int64_t whole =
      detail::days_from_civil(y, static_cast<int>(mo), static_cast<int>(d)) * 86400 + h * 3600 + mi * 60;
  return static_cast<double>(whole) + *sec;  // one rounding
}

/// Formats Unix-like seconds as `YYYY-MM-DD HH:MM:SS.nnnnnnnnn` (9 fraction
/// digits, as KITTI raw writes them), rounded to the nanosecond;
/// parse_oxts_timestamp reads it back to within 0.5 ns (to the same double for
/// Unix-era stamps, whose spacing exceeds 1 ns). Throws ValueError unless 0 <= stamp_s < 253402300800 (the
/// years 1970-9999 the 4-digit format can hold).
inline std::string format_oxts_timestamp(double stamp_s) {
  if (!(stamp_s >= 0.0 && stamp_s < 253402300800.0)) {
    throw ValueError("OXTS timestamp " + std::to_string(stamp_s) +
                     " s is outside 1970-9999 and cannot be written as a date-time string");
  }
  double whole_d = std::floor(stamp_s);
  auto ns = static_cast<std::int64_t>(std::llround((stamp_s - whole_d) * 1e9));
  if (ns >= 1000000000) {
    ns -= 1000000000;
    whole_d += 1.0;
  }
  const auto whole = static_cast<std::int64_t>(whole_d);
  std::int64_t days = whole / 86400;
  std::int64_t sod = whole % 86400;
  if (sod < 0) {
    sod += 86400;
    --days;
  }
  const detail::CivilDate c = detail::civil_from_days(days);
  std::string out;
  detail::append_padded(out, static_cast<std::uint64_t>(c.year), 4);
  out.push_back('-');
  detail::append_padded(out, static_cast<std::uint64_t>(c.month), 2);
  out.push_back('-');
  detail::append_padded(out, static_cast<std::uint64_t>(c.day), 2);
  out.push_back(' ');
  detail::append_padded(out, static_cast<std::uint64_t>(sod / 3600), 2);
  out.push_back(':');
  detail::append_padded(out, static_cast<std::uint64_t>(sod / 60 % 60), 2);
  out.push_back(':');
  detail::append_padded(out, static_cast<std::uint64_t>(sod % 60), 2);
  out.push_back('.');
  detail::append_padded(out, static_cast<std::uint64_t>(ns), 9);
  return out;
}

/// Parses one OXTS data line (30 fields) into `rec` (stamp untouched). Throws
/// FormatError (field count, non-numeric, non-integer status field) and
/// ValueError (NaN/Inf), naming path and line.
inline void parse_oxts_line(std::string_view line_text, const std::string& path, long line, OxtsRecord& rec) {
  const auto tok = detail::split_ws(line_text);
  if (tok.size() != kOxtsFieldCount) {
    throw FormatError(detail::where(
        path, line,
        "OXTS line has " + std::to_string(tok.size()) + " fields, expected " + std::to_string(kOxtsFieldCount)));
  }
  double v[kOxtsFieldCount];
  for (std::size_t i = 0; i < kOxtsFieldCount; ++i) {
    v[i] = detail::parse_double(tok[i], path, line, i + 1, "OXTS");
    if (!std::isfinite(v[i])) {
      throw ValueError(detail::where(
          path, line, "OXTS field " + std::to_string(i + 1) + " ('" + std::string(tok[i]) + "') is not finite"));
    }
  }
  const auto as_int = [&](std::size_t i) {
    if (v[i] != std::floor(v[i]) || std::abs(v[i]) > 1e9) {
      throw FormatError(detail::where(
          path, line, "OXTS field " + std::to_string(i + 1) + " ('" + std::string(tok[i]) + "') must be an integer"));
    }
    return static_cast<int>(v[i]);
  };
  rec.lat_deg = v[0];
  rec.lon_deg = v[1];
  rec.alt_m = v[2];
  rec.roll_rad = v[3];
  rec.pitch_rad = v[4];
  rec.yaw_rad = v[5];
  rec.vn_mps = v[6];
  rec.ve_mps = v[7];
  rec.velocity_flu_mps = Eigen::Vector3d(v[8], v[9], v[10]);
  rec.accel_body_mps2 = Eigen::Vector3d(v[11], v[12], v[13]);
  rec.accel_flu_mps2 = Eigen::Vector3d(v[14], v[15], v[16]);
  rec.gyro_body_radps = Eigen::Vector3d(v[17], v[18], v[19]);
  rec.gyro_flu_radps = Eigen::Vector3d(v[20], v[21], v[22]);
  rec.pos_accuracy_m = v[23];
  rec.vel_accuracy_mps = v[24];
  rec.navstat = as_int(25);
  rec.numsats = as_int(26);
  rec.posmode = as_int(27);
  rec.velmode = as_int(28);
  rec.orimode = as_int(29);
}

/// Appends the 30 fields of `rec` as one line (no newline), numbers as the
/// shortest text that reads back exactly.
inline void append_oxts_line(std::string& out, const OxtsRecord& rec) {
  const double v[25] = {rec.lat_deg,
                        rec.lon_deg,
                        rec.alt_m,
                        rec.roll_rad,
                        rec.pitch_rad,
                        rec.yaw_rad,
                        rec.vn_mps,
                        rec.ve_mps,
                        rec.velocity_flu_mps.x(),
                        rec.velocity_flu_mps.y(),
                        rec.velocity_flu_mps.z(),
                        rec.accel_body_mps2.x(),
                        rec.accel_body_mps2.y(),
                        rec.accel_body_mps2.z(),
                        rec.accel_flu_mps2.x(),
                        rec.accel_flu_mps2.y(),
                        rec.accel_flu_mps2.z(),
                        rec.gyro_body_radps.x(),
                        rec.gyro_body_radps.y(),
                        rec.gyro_body_radps.z(),
                        rec.gyro_flu_radps.x(),
                        rec.gyro_flu_radps.y(),
                        rec.gyro_flu_radps.z(),
                        rec.pos_accuracy_m,
                        rec.vel_accuracy_mps};
  for (std::size_t i = 0; i < 25; ++i) {
    if (i != 0) out.push_back(' ');
    detail::append_double(out, v[i]);
  }
  for (const int k : {rec.navstat, rec.numsats, rec.posmode, rec.velmode, rec.orimode}) {
    out.push_back(' ');
    detail::append_int(out, k);
  }
}

/// Parses the text of an OXTS `timestamps.txt` already in memory (`path`
/// names it in error messages): one `YYYY-MM-DD HH:MM:SS.fraction` per line.
/// Throws FormatError (empty, blank line between timestamps, malformed
/// timestamp) and ValueError (time going backwards; equal times are
/// accepted), naming path and line.
inline std::vector<double> parse_oxts_timestamps(std::string_view text, const std::string& path) {
  std::vector<double> stamps;
  detail::for_each_record(text, path, "timestamps", [&](long line, std::string_view s, const auto&) {
    const double t = parse_oxts_timestamp(s, path, line);
    if (!stamps.empty() && t < stamps.back()) {
      throw ValueError(detail::where(path, line, "timestamp '" + std::string(detail::trim(s)) + "' goes backwards"));
    }
    stamps.push_back(t);
  });
  if (stamps.empty()) throw FormatError(detail::where(path, 0, "empty timestamps file"));
  return stamps;
}

/// Parses the text of one OXTS data file (`data/NNNNNNNNNN.txt`, one line of
/// 30 fields; blank lines allowed) into `rec` (stamp untouched). Throws
/// FormatError (empty, more than one line, and parse_oxts_line's errors) and
/// ValueError (NaN/Inf), naming path and line.
inline void parse_oxts_data(std::string_view text, const std::string& path, OxtsRecord& rec) {
  long data_line = 0;
  detail::for_each_line(text, [&](long line, std::string_view s) {
    if (detail::is_blank(s)) return;
    if (data_line != 0) throw FormatError(detail::where(path, line, "more than one OXTS line"));
    data_line = line;
    parse_oxts_line(s, path, line, rec);
  });
  if (data_line == 0) throw FormatError(detail::where(path, 0, "empty OXTS data file"));
}

/// Parses a KITTI raw `oxts` directory already in memory: the text of
/// `timestamps.txt` and of each `data/NNNNNNNNNN.txt` in index order
/// (`oxts_dir` names them in error messages). Throws FormatError (the data
/// file count differing from the timestamp count, and the errors of
/// parse_oxts_timestamps and parse_oxts_data) and ValueError.
inline std::vector<OxtsRecord> parse_oxts(std::string_view timestamps_text,
                                          const std::vector<std::string_view>& data_texts,
                                          const std::string& oxts_dir) {
  namespace fs = std::filesystem;
  const std::vector<double> stamps =
      parse_oxts_timestamps(timestamps_text, (fs::path(oxts_dir) / "timestamps.txt").string());
  if (data_texts.size() != stamps.size()) {
    throw FormatError(detail::where((fs::path(oxts_dir) / "data").string(), 0,
                                    "holds " + std::to_string(data_texts.size()) +
                                        " .txt files but timestamps.txt has " + std::to_string(stamps.size()) +
                                        " lines"));
  }
  std::vector<OxtsRecord> records(stamps.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    records[i].stamp_s = stamps[i];
    parse_oxts_data(data_texts[i], (fs::path(oxts_dir) / "data" / (detail::frame_stem(i, 10) + ".txt")).string(),
                    records[i]);
  }
  return records;
}

/// Reads a KITTI raw `oxts` directory: `timestamps.txt` and `data/NNNNNNNNNN.txt`
/// (10-digit, from 0, one per timestamp line). Throws IoError (missing
/// directory, timestamps or data file), FormatError (empty timestamps, blank
/// line between timestamps, malformed timestamp or data line, data file count
/// differing from the timestamp count) and ValueError (NaN/Inf, time going
/// backwards; equal times are accepted), naming path and line.
inline std::vector<OxtsRecord> read_oxts(const std::string& oxts_dir) {
  namespace fs = std::filesystem;
  const std::string stamps_path = (fs::path(oxts_dir) / "timestamps.txt").string();
  const std::vector<double> stamps = parse_oxts_timestamps(detail::read_file(stamps_path), stamps_path);
  const fs::path data_dir = fs::path(oxts_dir) / "data";
  std::error_code ec;
  if (!fs::is_directory(data_dir, ec)) {
    throw IoError(detail::where(data_dir.string(), 0, "OXTS data directory does not exist"));
  }
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(data_dir, ec)) {
    if (entry.path().extension() == ".txt") ++files;
  }
  if (ec) throw IoError(detail::where(data_dir.string(), 0, "cannot list directory: " + ec.message()));
  if (files != stamps.size()) {
    throw FormatError(detail::where(data_dir.string(), 0,
                                    "holds " + std::to_string(files) + " .txt files but timestamps.txt has " +
                                        std::to_string(stamps.size()) + " lines"));
  }
  std::vector<OxtsRecord> records(stamps.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    records[i].stamp_s = stamps[i];
    const std::string path = (data_dir / (detail::frame_stem(i, 10) + ".txt")).string();
    parse_oxts_data(detail::read_file(path), path, records[i]);  // IoError names a missing index
  }
  return records;
}

/// The text of an OXTS `timestamps.txt` for `records` (format_oxts_timestamp
/// per line). Throws ValueError for a stamp outside 1970-9999.
inline std::string format_oxts_timestamps(const std::vector<OxtsRecord>& records) {
  std::string stamps;
  for (const OxtsRecord& r : records) {
    stamps += format_oxts_timestamp(r.stamp_s);
    stamps.push_back('\n');
  }
  return stamps;
}

/// Writes a KITTI raw `oxts` directory (created when missing): timestamps.txt
/// and data/NNNNNNNNNN.txt. Throws IoError.
inline void write_oxts(const std::string& oxts_dir, const std::vector<OxtsRecord>& records) {
  namespace fs = std::filesystem;
  const fs::path data_dir = fs::path(oxts_dir) / "data";
  std::error_code ec;
  fs::create_directories(data_dir, ec);
  if (ec) throw IoError(detail::where(data_dir.string(), 0, "cannot create directory: " + ec.message()));
  const std::string stamps = format_oxts_timestamps(records);
  for (std::size_t i = 0; i < records.size(); ++i) {
    std::string line;
    append_oxts_line(line, records[i]);
    line.push_back('\n');
    detail::write_file((data_dir / (detail::frame_stem(i, 10) + ".txt")).string(), line);
  }
  detail::write_file((fs::path(oxts_dir) / "timestamps.txt").string(), stamps);
}

/// IMU samples of OXTS records: gyro = (wx, wy, wz), accel = (ax, ay, az),
/// both in the body frame (x forward, y left, z up); accel is specific force
/// (about +9.81 on z at rest).
inline std::vector<ImuSample> imu_samples(const std::vector<OxtsRecord>& records) {
  std::vector<ImuSample> out;
  out.reserve(records.size());
  for (const OxtsRecord& r : records) out.push_back({r.stamp_s, r.gyro_body_radps, r.accel_body_mps2});
  return out;
}

/// Earth radius of the KITTI devkit's Mercator projection [m].
inline constexpr double kOxtsEarthRadius_m = 6378137.0;

/// Pose of the IMU in a local Mercator east-north-up frame, T_world_imu, with
/// map scale `mercator_scale` = cos(reference latitude) (KITTI devkit
/// convention; use the first record's latitude for a whole drive).
inline SE3d oxts_pose_mercator(const OxtsRecord& r, double mercator_scale) {
  constexpr double kPi = 3.14159265358979323846;
  const double x = mercator_scale * r.lon_deg * kPi * kOxtsEarthRadius_m / 180.0;
  const double y = mercator_scale * kOxtsEarthRadius_m * std::log(std::tan((90.0 + r.lat_deg) * kPi / 360.0));
  const Eigen::Quaterniond q = Eigen::AngleAxisd(r.yaw_rad, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(r.pitch_rad, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(r.roll_rad, Eigen::Vector3d::UnitX());
  return SE3d(q, Eigen::Vector3d(x, y, r.alt_m));
}

/// IMU poses relative to the first record, T_imu0_imu_i (the first is the
/// identity), from the Mercator poses with the first record's latitude scale.
inline std::vector<SE3d> oxts_poses(const std::vector<OxtsRecord>& records) {
  std::vector<SE3d> out;
  if (records.empty()) return out;
  constexpr double kPi = 3.14159265358979323846;
  const double scale = std::cos(records.front().lat_deg * kPi / 180.0);
  const SE3d T_imu0_world = oxts_pose_mercator(records.front(), scale).inverse();
  out.reserve(records.size());
  for (const OxtsRecord& r : records) out.push_back(T_imu0_world * oxts_pose_mercator(r, scale));
  return out;
}

}  // namespace semlio::io
