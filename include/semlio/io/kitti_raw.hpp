#pragma once
/// \file
/// A KITTI raw drive exactly as published, read lazily frame by frame:
///
///     <date>/calib_imu_to_velo.txt, calib_velo_to_cam.txt    (R: 9, T: 3 numbers)
///     <date>/<date>_drive_NNNN_sync/velodyne_points/data/NNNNNNNNNN.bin
///                                  velodyne_points/timestamps.txt        sweep middle
///                                  velodyne_points/timestamps_start.txt  sweep start (optional)
///                                  oxts/data/NNNNNNNNNN.txt, oxts/timestamps.txt
///
/// The calibration folder is, in this order: Config::calib_dir, the drive's
/// parent folder (the published layout), a sibling folder `calib_YYYY_MM_DD`
/// (the date taken from the drive folder's name).
///
/// Frames: frame i is the i-th line of timestamps.txt and the file
/// NNNNNNNNNN.bin numbered i (sync data: OXTS packet i belongs to frame i). A
/// partial download is normal: the drive has frames 0 .. (highest .bin
/// number), whatever timestamps.txt lists beyond. A .bin file missing below
/// the highest one (a gap) is a *missing frame*: it keeps its index and stamp,
/// read() throws IoError for it and read_or_empty() returns an empty scan, so
/// it costs that one frame, not the run (see missing_frame_count()).
///
/// Stamps (Scan convention: sweep start): the line of timestamps_start.txt
/// when that file exists and the line is not blank, else the line of
/// timestamps.txt (sweep middle) minus half the sweep period (the median
/// difference of consecutive stamps; Config::nominal_period_s when fewer than
/// two consecutive lines carry stamps). Real drives have blank lines where
/// the recorder dropped sweeps (drive 0009: lines 178-181): those frames get
/// a stamp interpolated linearly between the nearest stamped lines (or
/// extrapolated by the period at the ends) and stamp_interpolated(i) is true.
///
/// OXTS: stamped 12-22 ms after the sweep middle on drive 0009 (the recorder
/// logs the packet nearest the sweep's middle when it arrives);
/// oxts_minus_scan_stamp_s(i) gives the offset per frame. Both streams use
/// the same clock, so imu_samples() need no shift against Scan::stamp_s.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/io/detail/pose_text.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// Parses the text of a KITTI raw calibration file already in memory (`path`
/// names it in error messages): lines `key: values`; `R` (9 numbers,
/// row-major) and `T` (3 numbers) are required once each, other keys
/// (`calib_time`, `delta_f`, ...) are ignored. Returns T_to_from
/// (calib_imu_to_velo gives T_velo_imu). Throws FormatError (line without
/// ':', R/T missing, repeated or of the wrong count, non-numeric value) and
/// ValueError (NaN/Inf, rotation not orthonormal), naming path and line.
inline SE3d parse_kitti_raw_calib(std::string_view text, const std::string& path) {
  double v[12] = {};
  long r_line = 0;
  long t_line = 0;
  std::vector<std::string_view> tok;
  detail::for_each_line(text, [&](long line, std::string_view s) {
    if (detail::is_blank(s)) return;
    const std::size_t colon = s.find(':');
    if (colon == std::string_view::npos) {
      throw FormatError(
          detail::where(path, line, "calibration line has no 'key:' prefix: '" + std::string(detail::trim(s)) + "'"));
    }
    const std::string_view key = detail::trim(s.substr(0, colon));
    if (key != "R" && key != "T") return;
    long& seen = key == "R" ? r_line : t_line;
    if (seen != 0) {
      throw FormatError(detail::where(
          path, line,
          "calibration key '" + std::string(key) + "' appears twice (first on line " + std::to_string(seen) + ")"));
    }
    seen = line;
    detail::split_ws(s.substr(colon + 1), tok);
    const std::size_t expected = key == "R" ? 9 : 3;
    if (tok.size() != expected) {
      throw FormatError(detail::where(path, line,
                                      "calibration '" + std::string(key) + "' has " + std::to_string(tok.size()) +
                                          " values, expected " + std::to_string(expected)));
    }
    for (std::size_t i = 0; i < expected; ++i) {
      const double x = detail::parse_double(tok[i], path, line, i + 1, "calibration '" + std::string(key) + "'");
      // Row-major 3x4 [R | T] as pose_from_3x4 takes it.
      if (key == "R") {
        v[4 * (i / 3) + i % 3] = x;
      } else {
        v[4 * i + 3] = x;
      }
    }
  });
  if (r_line == 0 || t_line == 0) {
    throw FormatError(
        detail::where(path, 0, std::string("calibration has no '") + (r_line == 0 ? "R" : "T") + ":' line"));
  }
  return detail::pose_from_3x4(v, path, r_line, "calibration [R|T]");
}

/// Reads a KITTI raw calibration file (`calib_imu_to_velo.txt`,
/// `calib_velo_to_cam.txt`); see parse_kitti_raw_calib for the rules and
/// errors, plus IoError when the file is missing or unreadable.
inline SE3d read_kitti_raw_calib(const std::string& path) {
  return parse_kitti_raw_calib(detail::read_file(path), path);
}

namespace detail {

/// One stamp per line of the text of a KITTI raw timestamps file (`path`
/// names it in error messages); nullopt for a blank line (a sweep or packet
/// the recorder dropped). Throws FormatError (no lines, malformed date-time)
/// and ValueError (a stamp earlier than the previous one), naming path and line.
inline std::vector<std::optional<double>> parse_raw_stamp_lines(std::string_view text, const std::string& path) {
  std::vector<std::optional<double>> out;
  std::optional<double> last;
  long last_line = 0;
  for_each_line(text, [&](long line, std::string_view s) {
    if (is_blank(s)) {
      out.emplace_back();
      return;
    }
    const double t = parse_oxts_timestamp(s, path, line);
    if (last && t < *last) {
      throw ValueError(
          where(path, line,
                "timestamp '" + std::string(trim(s)) + "' is earlier than line " + std::to_string(last_line) + "'s"));
    }
    last = t;
    last_line = line;
    out.emplace_back(t);
  });
  if (out.empty()) throw FormatError(where(path, 0, "empty timestamps file"));
  return out;
}

/// parse_raw_stamp_lines of a file; IoError when it is missing or unreadable.
inline std::vector<std::optional<double>> read_raw_stamp_lines(const std::string& path) {
  return parse_raw_stamp_lines(read_file(path), path);
}

/// The names `<digits><ext>` among `names` (the files of folder `dir`) by
/// number. Other extensions are ignored. Throws FormatError (a name that is
/// not a number, two names with the same number), naming the file.
inline std::map<std::uint64_t, std::string> numbered_names(const std::vector<std::string>& names,
                                                          const std::filesystem::path& dir, std::string_view ext) {
  namespace fs = std::filesystem;
  std::map<std::uint64_t, std::string> out;
  for (const std::string& name : names) {
    const fs::path file(name);
    if (file.extension() != ext) continue;
    const std::string stem = file.stem().string();
    const auto number = to_int(stem);
    if (!number || *number < 0 || stem.find_first_not_of("0123456789") != std::string::npos) {
      throw FormatError(where((dir / file).string(), 0, "file name is not a frame number"));
    }
    const auto key = static_cast<std::uint64_t>(*number);
    const auto [it, fresh] = out.emplace(key, stem);
    if (!fresh) {
      throw FormatError(where((dir / file).string(), 0,
                              "frame " + std::to_string(key) + " appears twice (also " + it->second +
                                  std::string(ext) + ")"));
    }
  }
  return out;
}

/// Names of the entries of a directory (any order). Throws IoError (cannot list).
inline std::vector<std::string> directory_names(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) out.push_back(entry.path().filename().string());
  if (ec) throw IoError(where(dir.string(), 0, "cannot list directory: " + ec.message()));
  return out;
}

/// Files `<digits><ext>` of a directory by number (numbered_names of its
/// listing). Throws IoError (cannot list) and FormatError (a name that is not
/// a number, two names with the same number), naming the file.
inline std::map<std::uint64_t, std::string> numbered_files(const std::filesystem::path& dir, std::string_view ext) {
  return numbered_names(directory_names(dir), dir, ext);
}

/// Median of the differences between consecutive stamped lines; nullopt when
/// no two consecutive lines carry stamps.
inline std::optional<double> median_period(const std::vector<std::optional<double>>& lines) {
  std::vector<double> d;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    if (lines[i] && lines[i - 1]) d.push_back(*lines[i] - *lines[i - 1]);
  }
  if (d.empty()) return std::nullopt;
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return *mid;
}

}  // namespace detail

/// Which file decided the stamps of a KittiRawDrive.
enum class KittiRawStampSource {
  sweep_start,           ///< velodyne_points/timestamps_start.txt
  sweep_middle_shifted,  ///< timestamps.txt minus half the sweep period (no timestamps_start.txt)
};

/// Settings of a KittiRawDrive.
struct KittiRawDriveConfig {
  /// Folder holding calib_imu_to_velo.txt / calib_velo_to_cam.txt; empty =
  /// the drive's parent folder, else the sibling `calib_YYYY_MM_DD`.
  std::string calib_dir;
  /// Sweep period [s] used only when the timestamps give no two consecutive
  /// stamps to measure it from (HDL-64E in KITTI: about 0.1035 s).
  double nominal_period_s = 0.1;
};

/// What the file system gives a KittiRawDrive before it decides anything:
/// the timestamps texts and the names in the data folders.
struct KittiRawDriveListing {
  std::string_view timestamps;                         ///< velodyne_points/timestamps.txt (sweep middle)
  std::optional<std::string_view> timestamps_start;    ///< velodyne_points/timestamps_start.txt, when present
  std::optional<std::vector<std::string>> scan_names;  ///< names in velodyne_points/data/; nullopt: no such folder
  std::optional<std::string_view> oxts_timestamps;     ///< oxts/timestamps.txt, when present
  std::optional<std::vector<std::string>> oxts_names;  ///< names in oxts/data/, when that folder exists
};

/// What a drive's listing decides (see the file comment): frames, their
/// stamps and the OXTS packets present.
struct KittiRawDrivePlan {
  std::vector<std::string> stems;                    ///< .bin stem of frame i; empty = missing (a gap)
  std::size_t missing = 0;                           ///< frames whose .bin is missing
  std::vector<std::optional<double>> middle_lines;   ///< timestamps.txt, every line (nullopt: blank)
  std::vector<std::optional<double>> start_lines;    ///< timestamps_start.txt, every line, or empty
  std::vector<double> stamps;                        ///< sweep start of frame i [s]
  std::vector<bool> interpolated;                    ///< frame i's stamp interpolated (blank line)
  double period_s = 0.1;                             ///< sweep period [s] (median, else nominal)
  std::vector<std::optional<double>> oxts_lines;     ///< oxts/timestamps.txt, every line, or empty
  std::map<std::uint64_t, std::string> oxts_stems;   ///< OXTS packet number -> file stem
};

/// Plans a KITTI raw drive from its listing; `directory` (the drive folder)
/// names the files in messages. KittiRawDrive runs exactly this on what it
/// reads (the kitti_raw_drive fuzz harness runs it from memory). Throws
/// ConfigError (nominal_period_s not positive), IoError (no
/// velodyne_points/data/ folder), FormatError (no .bin scan, a non-numeric or
/// repeated scan or packet name, a scan numbered beyond the lines of
/// timestamps.txt, timestamps_start.txt with a different line count, no stamp
/// at all), ValueError (a line blank in timestamps_start.txt whose
/// timestamps.txt stamp goes back before an earlier line's start) plus what
/// parse_raw_stamp_lines throws.
inline KittiRawDrivePlan plan_kitti_raw_drive(const KittiRawDriveListing& in, const std::string& directory,
                                              const KittiRawDriveConfig& config = {}) {
  namespace fs = std::filesystem;
  if (!(config.nominal_period_s > 0.0 && std::isfinite(config.nominal_period_s))) {
    throw ConfigError("KittiRawDriveConfig.nominal_period_s must be positive and finite, got " +
                      std::to_string(config.nominal_period_s));
  }
  const fs::path dir(directory);
  const fs::path velo = dir / "velodyne_points";
  KittiRawDrivePlan plan;

  // Stamp lines.
  plan.middle_lines = detail::parse_raw_stamp_lines(in.timestamps, (velo / "timestamps.txt").string());
  if (in.timestamps_start) {
    const fs::path start = velo / "timestamps_start.txt";
    plan.start_lines = detail::parse_raw_stamp_lines(*in.timestamps_start, start.string());
    if (plan.start_lines.size() != plan.middle_lines.size()) {
      throw FormatError(detail::where(start.string(), 0,
                                      "has " + std::to_string(plan.start_lines.size()) +
                                          " lines but timestamps.txt has " + std::to_string(plan.middle_lines.size())));
    }
  }

  // Frames: 0 .. highest .bin number, the absent ones missing.
  const fs::path data = velo / "data";
  if (!in.scan_names) throw IoError(detail::where(data.string(), 0, "scan directory does not exist"));
  const auto files = detail::numbered_names(*in.scan_names, data, ".bin");
  if (files.empty()) throw FormatError(detail::where(data.string(), 0, "no .bin scans"));
  const std::uint64_t last = files.rbegin()->first;
  // Bounds the frame count by the lines actually present, so a stray huge
  // number cannot make us allocate for it.
  if (last >= plan.middle_lines.size()) {
    throw FormatError(detail::where((data / (files.rbegin()->second + ".bin")).string(), 0,
                                    "frame " + std::to_string(last) + " has no line in timestamps.txt (" +
                                        std::to_string(plan.middle_lines.size()) + " lines)"));
  }
  plan.stems.assign(static_cast<std::size_t>(last) + 1, std::string());
  for (const auto& [k, stem] : files) plan.stems[static_cast<std::size_t>(k)] = stem;
  plan.missing = plan.stems.size() - files.size();

  // Stamps of every line of the drive (start, else middle - period/2), the
  // blank ones interpolated; then the first stems.size() of them are kept.
  const bool have_start = !plan.start_lines.empty();
  const auto& base = have_start ? plan.start_lines : plan.middle_lines;
  plan.period_s = detail::median_period(base).value_or(config.nominal_period_s);
  if (!(plan.period_s > 0.0)) plan.period_s = config.nominal_period_s;  // all stamps equal: keep a usable period
  const std::size_t n = plan.middle_lines.size();
  std::vector<std::optional<double>> line_stamp(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (have_start && plan.start_lines[k]) {
      line_stamp[k] = plan.start_lines[k];
    } else if (plan.middle_lines[k]) {
      line_stamp[k] = *plan.middle_lines[k] - 0.5 * plan.period_s;
    }
  }
  std::vector<std::size_t> known;
  for (std::size_t k = 0; k < n; ++k) {
    if (line_stamp[k]) known.push_back(k);
  }
  if (known.empty()) {
    throw FormatError(detail::where(directory, 0, "velodyne_points/timestamps.txt has no stamp (every line is blank)"));
  }
  // Each file is non-decreasing on its own, but a line blank in
  // timestamps_start.txt takes its stamp from timestamps.txt: when the two
  // files disagree the stamps could go backwards. Refused, so the frames'
  // stamps (interpolated ones included) never decrease.
  for (std::size_t j = 1; j < known.size(); ++j) {
    const std::size_t a = known[j - 1];
    const std::size_t b = known[j];
    if (*line_stamp[b] < *line_stamp[a]) {
      throw ValueError(detail::where((velo / "timestamps_start.txt").string(), static_cast<long>(b) + 1,
                                     "sweep start of line " + std::to_string(b + 1) + " is earlier than line " +
                                         std::to_string(a + 1) +
                                         "'s (timestamps_start.txt and timestamps.txt disagree where a line is blank)"));
    }
  }
  const std::size_t frames = plan.stems.size();
  plan.stamps.resize(frames);
  plan.interpolated.assign(frames, false);
  for (std::size_t i = 0; i < frames; ++i) {
    if (line_stamp[i]) {
      plan.stamps[i] = *line_stamp[i];
      continue;
    }
    plan.interpolated[i] = true;
    const auto after = std::lower_bound(known.begin(), known.end(), i);
    if (after == known.begin()) {
      plan.stamps[i] = *line_stamp[*after] - static_cast<double>(*after - i) * plan.period_s;
    } else if (after == known.end()) {
      const std::size_t b = known.back();
      plan.stamps[i] = *line_stamp[b] + static_cast<double>(i - b) * plan.period_s;
    } else {
      const std::size_t a = *(after - 1);
      const std::size_t b = *after;
      const double w = static_cast<double>(i - a) / static_cast<double>(b - a);
      plan.stamps[i] = *line_stamp[a] + w * (*line_stamp[b] - *line_stamp[a]);
    }
  }

  // OXTS (a drive downloaded without it has no oxts/timestamps.txt).
  if (in.oxts_timestamps) {
    const fs::path oxts = dir / "oxts";
    plan.oxts_lines = detail::parse_raw_stamp_lines(*in.oxts_timestamps, (oxts / "timestamps.txt").string());
    if (in.oxts_names) plan.oxts_stems = detail::numbered_names(*in.oxts_names, oxts / "data", ".txt");
  }
  return plan;
}

/// A KITTI raw drive folder (`YYYY_MM_DD_drive_NNNN_sync`): the frame list,
/// stamps and calibration are read on construction; scans and OXTS packets
/// only when asked for. Const member functions only read files, so
/// concurrent calls are safe.
class KittiRawDrive {
 public:
  using Config = KittiRawDriveConfig;

  /// Opens `directory`. Throws ConfigError (nominal_period_s not positive),
  /// IoError (no velodyne_points/data/ folder, no timestamps.txt, an explicit
  /// calib_dir without calib_imu_to_velo.txt), FormatError (no .bin scan, a
  /// non-numeric or repeated scan name, a scan numbered beyond the lines of
  /// timestamps.txt, timestamps_start.txt with a different line count, no
  /// stamp at all), ValueError (timestamps_start.txt and timestamps.txt giving
  /// stamps that go backwards) plus what the timestamps and calibration
  /// readers throw. The decisions are plan_kitti_raw_drive's.
  explicit KittiRawDrive(const std::string& directory, const Config& config = {}) : config_(config) {
    namespace fs = std::filesystem;
    if (!(config_.nominal_period_s > 0.0 && std::isfinite(config_.nominal_period_s))) {
      throw ConfigError("KittiRawDriveConfig.nominal_period_s must be positive and finite, got " +
                        std::to_string(config_.nominal_period_s));
    }
    fs::path dir = fs::path(directory).lexically_normal();
    if (dir.filename().empty()) dir = dir.parent_path();  // trailing '/'
    dir_ = dir.string();
    // Read what the drive holds, then let plan_kitti_raw_drive decide (the
    // code the kitti_raw_drive fuzz harness runs from memory).
    const fs::path velo = dir / "velodyne_points";
    const fs::path oxts = dir / "oxts";
    std::error_code ec;
    const std::string middle = detail::read_file((velo / "timestamps.txt").string());
    std::optional<std::string> start;
    if (fs::exists(velo / "timestamps_start.txt", ec)) {
      start = detail::read_file((velo / "timestamps_start.txt").string());
    }
    KittiRawDriveListing listing;
    listing.timestamps = middle;
    if (start) listing.timestamps_start = *start;
    if (fs::is_directory(velo / "data", ec)) listing.scan_names = detail::directory_names(velo / "data");
    std::optional<std::string> oxts_stamps;
    if (fs::exists(oxts / "timestamps.txt", ec)) {
      oxts_stamps = detail::read_file((oxts / "timestamps.txt").string());
      listing.oxts_timestamps = *oxts_stamps;
      if (fs::is_directory(oxts / "data", ec)) listing.oxts_names = detail::directory_names(oxts / "data");
    }
    KittiRawDrivePlan plan = plan_kitti_raw_drive(listing, dir_, config_);
    stems_ = std::move(plan.stems);
    missing_ = plan.missing;
    middle_lines_ = std::move(plan.middle_lines);
    start_lines_ = std::move(plan.start_lines);
    stamps_ = std::move(plan.stamps);
    interpolated_ = std::move(plan.interpolated);
    period_s_ = plan.period_s;
    oxts_lines_ = std::move(plan.oxts_lines);
    oxts_stems_ = std::move(plan.oxts_stems);
    find_calibration(dir);
  }

  /// Number of frames: the highest .bin number + 1 (missing files included).
  [[nodiscard]] std::size_t size() const noexcept { return stems_.size(); }
  /// The drive directory (normalised, no trailing separator).
  [[nodiscard]] const std::string& directory() const noexcept { return dir_; }
  /// Path of frame i's scan (which may be missing: see has_scan).
  [[nodiscard]] std::string scan_path(std::size_t i) const {
    check_index(i);
    const std::string stem = stems_[i].empty() ? detail::frame_stem(i, 10) : stems_[i];
    return (std::filesystem::path(dir_) / "velodyne_points" / "data" / (stem + ".bin")).string();
  }
  /// False when frame i's .bin file is missing (a gap in a partial download).
  [[nodiscard]] bool has_scan(std::size_t i) const {
    check_index(i);
    return !stems_[i].empty();
  }
  /// Number of frames whose .bin file is missing.
  [[nodiscard]] std::size_t missing_frame_count() const noexcept { return missing_; }

  /// Stamp of frame i [s]: sweep START (see the file comment).
  [[nodiscard]] double stamp(std::size_t i) const {
    check_index(i);
    return stamps_[i];
  }
  /// True when frame i's timestamps line was blank and its stamp interpolated.
  [[nodiscard]] bool stamp_interpolated(std::size_t i) const {
    check_index(i);
    return interpolated_[i];
  }
  /// Number of frames with an interpolated stamp.
  [[nodiscard]] std::size_t interpolated_stamp_count() const noexcept {
    return static_cast<std::size_t>(std::count(interpolated_.begin(), interpolated_.end(), true));
  }
  /// Which file decided the stamps.
  [[nodiscard]] KittiRawStampSource stamp_source() const noexcept {
    return start_lines_.empty() ? KittiRawStampSource::sweep_middle_shifted : KittiRawStampSource::sweep_start;
  }
  /// Sweep period [s] measured from the stamps (median), or the nominal one.
  [[nodiscard]] double sweep_period_s() const noexcept { return period_s_; }
  /// Frame i's line of timestamps.txt (sweep middle) [s]; nullopt when blank.
  [[nodiscard]] std::optional<double> sweep_middle_stamp(std::size_t i) const {
    check_index(i);
    return middle_lines_[i];
  }
  /// Number of lines of velodyne_points/timestamps.txt (the whole drive).
  [[nodiscard]] std::size_t timestamp_line_count() const noexcept { return middle_lines_.size(); }

  /// Reads frame i: points and reflectance (sensor frame), stamp_s = stamp(i).
  /// Dropped points (NaN/Inf, (0,0,0)) are added to `stats`. Throws ValueError
  /// (i out of range), IoError (the frame's file is missing) and what
  /// read_kitti_bin throws (empty, truncated).
  [[nodiscard]] Scan read(std::size_t i, ReadStats* stats = nullptr) const {
    check_index(i);
    if (stems_[i].empty()) {
      throw IoError(detail::where(scan_path(i), 0,
                                  "frame " + std::to_string(i) + " is missing (a gap among the downloaded scans)"));
    }
    Scan scan = read_kitti_bin(scan_path(i), stats);
    scan.stamp_s = stamps_[i];
    return scan;
  }

  /// Frame i as read() returns it; when its file is missing or cannot be read,
  /// an empty scan at the frame's stamp instead, with the reason in `error`
  /// (cleared when the frame is fine): one bad frame costs that frame, not the
  /// run. Still throws ValueError for i out of range (a caller bug).
  [[nodiscard]] Scan read_or_empty(std::size_t i, std::string& error, ReadStats* stats = nullptr) const {
    check_index(i);
    error.clear();
    try {
      return read(i, stats);
    } catch (const Error& e) {
      error = e.what();
    }
    Scan scan;
    scan.stamp_s = stamps_[i];
    return scan;
  }

  /// True when an oxts/ folder with timestamps.txt exists.
  [[nodiscard]] bool has_oxts() const noexcept { return !oxts_lines_.empty(); }
  /// Number of OXTS data files present.
  [[nodiscard]] std::size_t oxts_packet_count() const noexcept { return oxts_stems_.size(); }
  /// OXTS stamp minus frame i's sweep-middle stamp (timestamps.txt) [s]
  /// (12-22 ms on drive 0009; add stamp(i)'s half period for the offset to
  /// the sweep start). nullopt when either line is blank or missing.
  [[nodiscard]] std::optional<double> oxts_minus_scan_stamp_s(std::size_t i) const {
    check_index(i);
    if (!middle_lines_[i] || i >= oxts_lines_.size() || !oxts_lines_[i]) return std::nullopt;
    return *oxts_lines_[i] - *middle_lines_[i];
  }

  /// Every OXTS packet present whose timestamps line is not blank, in packet
  /// order, with its stamp. Throws IoError (no oxts/) and what parse_oxts_line
  /// throws for a malformed packet (naming file and line).
  [[nodiscard]] std::vector<OxtsRecord> oxts_records() const {
    require_oxts();
    std::vector<OxtsRecord> out;
    out.reserve(oxts_stems_.size());
    for (const auto& [k, stem] : oxts_stems_) {
      if (k >= oxts_lines_.size() || !oxts_lines_[k]) continue;  // no stamp: cannot be placed in time
      OxtsRecord rec = read_packet(k);
      rec.stamp_s = *oxts_lines_[k];
      out.push_back(rec);
    }
    return out;
  }
  /// IMU samples of oxts_records() (io::imu_samples: body-frame gyro and
  /// specific force, 10 Hz in sync drives). Throws like oxts_records().
  [[nodiscard]] std::vector<ImuSample> imu_samples() const { return io::imu_samples(oxts_records()); }

  /// The calibration folder found (empty when none).
  [[nodiscard]] const std::string& calib_dir() const noexcept { return calib_dir_; }
  /// True when calib_imu_to_velo.txt was found.
  [[nodiscard]] bool has_calibration() const noexcept { return T_velo_imu_.has_value(); }
  /// T_velo_imu from calib_imu_to_velo.txt (IMU points into the velodyne
  /// frame). Throws IoError when none was found.
  [[nodiscard]] SE3d T_velo_imu() const {
    if (!T_velo_imu_) throw IoError(detail::where(dir_, 0, "no calib_imu_to_velo.txt found for this drive"));
    return *T_velo_imu_;
  }
  /// T_cam0_velo from calib_velo_to_cam.txt (velodyne points into the
  /// unrectified camera-0 frame). Throws IoError when none was found.
  [[nodiscard]] SE3d T_cam0_velo() const {
    if (!T_cam0_velo_) throw IoError(detail::where(dir_, 0, "no calib_velo_to_cam.txt found for this drive"));
    return *T_cam0_velo_;
  }

  /// True when reference_poses_lidar() can be computed: calibration found and
  /// an OXTS packet for every frame.
  [[nodiscard]] bool has_ground_truth() const {
    if (!T_velo_imu_ || !has_oxts()) return false;
    for (std::size_t i = 0; i < size(); ++i) {
      if (oxts_stems_.count(i) == 0) return false;
    }
    return true;
  }
  /// The OXTS trajectory as lidar poses T_velo0_velo_i, one per frame (frame 0
  /// the identity): KITTI raw devkit convention (Mercator with packet 0's
  /// latitude scale, R = Rz(yaw) Ry(pitch) Rx(roll)), T_world_velo =
  /// T_world_imu * T_velo_imu^-1, re-based on frame 0. GNSS/INS accuracy
  /// (about 0.45 m on drive 0009), not a centimetre ground truth. Throws
  /// IoError (no calibration, no oxts/, a frame's packet missing) and what
  /// parse_oxts_line throws.
  [[nodiscard]] std::vector<SE3d> reference_poses_lidar() const {
    const SE3d T_vi = T_velo_imu();
    require_oxts();
    std::vector<OxtsRecord> records;
    records.reserve(size());
    for (std::size_t i = 0; i < size(); ++i) records.push_back(read_packet(i));
    const SE3d T_iv = T_vi.inverse();
    std::vector<SE3d> out;
    out.reserve(records.size());
    for (const SE3d& T_imu0_imu : oxts_poses(records)) out.push_back(T_vi * T_imu0_imu * T_iv);
    return out;
  }
  /// reference_poses_lidar(), under the name the other sequence readers use.
  [[nodiscard]] std::vector<SE3d> ground_truth_lidar() const { return reference_poses_lidar(); }

 private:
  void check_index(std::size_t i) const {
    if (i >= stems_.size()) {
      throw ValueError(detail::where(
          dir_, 0, "frame " + std::to_string(i) + " out of range (" + std::to_string(stems_.size()) + " frames)"));
    }
  }

  void require_oxts() const {
    if (!has_oxts()) throw IoError(detail::where(dir_, 0, "drive has no oxts/timestamps.txt"));
  }

  [[nodiscard]] std::string packet_path(std::size_t k) const {
    const auto it = oxts_stems_.find(k);
    const std::string stem = it == oxts_stems_.end() ? detail::frame_stem(k, 10) : it->second;
    return (std::filesystem::path(dir_) / "oxts" / "data" / (stem + ".txt")).string();
  }

  // One OXTS data file: exactly one non-blank line of 30 fields (stamp unset).
  [[nodiscard]] OxtsRecord read_packet(std::size_t k) const {
    const std::string path = packet_path(k);
    if (oxts_stems_.count(k) == 0)
      throw IoError(detail::where(path, 0, "OXTS packet " + std::to_string(k) + " is missing"));
    OxtsRecord rec;
    parse_oxts_data(detail::read_file(path), path, rec);
    return rec;
  }

  void find_calibration(const std::filesystem::path& dir) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const auto has_calib = [&](const fs::path& d) { return fs::is_regular_file(d / "calib_imu_to_velo.txt", ec); };
    fs::path found;
    if (!config_.calib_dir.empty()) {
      if (!has_calib(config_.calib_dir)) {
        throw IoError(detail::where((fs::path(config_.calib_dir) / "calib_imu_to_velo.txt").string(), 0,
                                    "KittiRawDriveConfig.calib_dir has no calib_imu_to_velo.txt"));
      }
      found = config_.calib_dir;
    } else if (has_calib(dir.parent_path())) {
      found = dir.parent_path();
    } else {
      // `2011_09_26_drive_0009_sync` -> sibling `calib_2011_09_26`.
      const std::string name = dir.filename().string();
      const bool dated = name.size() >= 10 && name[4] == '_' && name[7] == '_' &&
                         detail::digits_value(std::string_view(name).substr(0, 4)) >= 0 &&
                         detail::digits_value(std::string_view(name).substr(5, 2)) >= 0 &&
                         detail::digits_value(std::string_view(name).substr(8, 2)) >= 0;
      if (dated && has_calib(dir.parent_path() / ("calib_" + name.substr(0, 10)))) {
        found = dir.parent_path() / ("calib_" + name.substr(0, 10));
      }
    }
    if (found.empty()) return;
    calib_dir_ = found.string();
    T_velo_imu_ = read_kitti_raw_calib((found / "calib_imu_to_velo.txt").string());
    if (fs::is_regular_file(found / "calib_velo_to_cam.txt", ec)) {
      T_cam0_velo_ = read_kitti_raw_calib((found / "calib_velo_to_cam.txt").string());
    }
  }

  Config config_;
  std::string dir_;
  std::vector<std::string> stems_;  // file stem of frame i; empty = missing
  std::size_t missing_ = 0;
  std::vector<std::optional<double>> middle_lines_;  // timestamps.txt, every line
  std::vector<std::optional<double>> start_lines_;   // timestamps_start.txt or empty
  std::vector<double> stamps_;                       // sweep start per frame
  std::vector<bool> interpolated_;
  double period_s_ = 0.1;
  std::vector<std::optional<double>> oxts_lines_;    // oxts/timestamps.txt, every line
  std::map<std::uint64_t, std::string> oxts_stems_;  // packet number -> file stem
  std::string calib_dir_;
  std::optional<SE3d> T_velo_imu_;
  std::optional<SE3d> T_cam0_velo_;
};

}  // namespace semlio::io
