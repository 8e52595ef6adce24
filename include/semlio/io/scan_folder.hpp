#pragma once
/// \file
/// A folder of scan files (`.pcd`, `.ply` or KITTI `.bin` float32 x y z
/// intensity), read lazily frame by frame, with optional `times.txt` and
/// `poses.txt`.
///
/// Files: every regular file whose extension is .pcd, .ply or .bin (any case);
/// names starting with '.' (hidden files) and other extensions (times.txt,
/// README, ...) are ignored. One format per folder: a folder mixing them is a
/// FormatError naming one file of each.
///
/// Order (natural sort by the number in the name): a name that is a decimal
/// number (`000012`, `1317357625.123456`) is ordered by its exact value;
/// any other name by its last run of digits (`scan_9` before `scan_10`). A
/// scan name without a digit (a stray `map.pcd`) is a FormatError: a scan
/// silently left out would shift every later frame's ground truth. Two names
/// with the same number (`1.pcd`, `01.pcd`) are a FormatError. Gaps in the
/// numbering are not missing frames: the frames are the files present (a
/// folder of every 5th scan is common).
///
/// Stamps (Scan convention: sweep start), the first rule that applies:
///  1. `times.txt` in the folder: one stamp [s] per scan, in frame order.
///  2. File names, when every name is a decimal number of the same unit,
///     decided by the number of significant integer digits: 9-11 seconds
///     (1e8-1e11 s, 1973-5138; a fraction is allowed: `1317357625.123456`),
///     12-14 milliseconds, 15-17 microseconds, 18-19 nanoseconds
///     (`1599131415123456789`); shorter names are frame numbers. Most
///     recorders (pcl_ros bag_to_pcd, ROS 2 exporters) name files by the
///     message stamp, which is the sweep start for Velodyne/Ouster drivers.
///  3. Config::nominal_period_s: number * period when every name is an integer
///     frame number (so a dropped file keeps later frames' times), else
///     index * period.
/// PCD and PLY headers have no standard stamp field (a few writers put one
/// in a comment, in no agreed form), so headers are never read for stamps.
///
/// Ground truth: Config::ground_truth_path, else `poses.txt` in the folder:
/// KITTI 3x4 (12 columns) or TUM (8 columns: stamp x y z qx qy qz qw),
/// detected by the column count of the first line, one pose per scan, lidar
/// frame, returned as stored.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// File format of the scans in a ScanFolder.
enum class ScanFileFormat {
  pcd,        ///< PCD v0.7 (read_pcd)
  ply,        ///< PLY (read_ply)
  kitti_bin,  ///< KITTI velodyne .bin, float32 x y z intensity (read_kitti_bin)
};

/// Which rule decided the stamps of a ScanFolder (see the file comment).
enum class ScanStampSource {
  times_file,      ///< times.txt in the folder
  file_name,       ///< the file names are times
  nominal_period,  ///< frame number (or index) times Config::nominal_period_s
};

namespace detail {

/// The number in a scan file's name, normalised for exact comparison.
struct ScanNameNumber {
  std::string integer;      ///< integer digits without leading zeros ("0" for zero)
  std::string fraction;     ///< fraction digits without trailing zeros (may be empty)
  bool whole_name = false;  ///< the whole stem is the number (it may be a time)
};

/// The number of a file stem: the whole stem when it is `digits[.digits]`,
/// else its last run of digits; nullopt when it has no digit.
inline std::optional<ScanNameNumber> scan_name_number(std::string_view stem) {
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  const auto all_digits = [&](std::string_view s) { return !s.empty() && std::all_of(s.begin(), s.end(), digit); };
  ScanNameNumber n;
  const std::size_t dot = stem.find('.');
  if (all_digits(stem.substr(0, dot)) && (dot == std::string_view::npos || all_digits(stem.substr(dot + 1)))) {
    n.whole_name = true;
    n.integer = std::string(stem.substr(0, dot));
    if (dot != std::string_view::npos) n.fraction = std::string(stem.substr(dot + 1));
  } else {
    const auto last = std::find_if(stem.rbegin(), stem.rend(), digit);
    if (last == stem.rend()) return std::nullopt;
    const auto end = last.base();  // one past the last digit
    auto begin = end;
    while (begin != stem.begin() && digit(*(begin - 1))) --begin;
    n.integer = std::string(begin, end);
  }
  const std::size_t first = n.integer.find_first_not_of('0');
  n.integer = first == std::string::npos ? "0" : n.integer.substr(first);
  const std::size_t last_nonzero = n.fraction.find_last_not_of('0');
  n.fraction = last_nonzero == std::string::npos ? "" : n.fraction.substr(0, last_nonzero + 1);
  return n;
}

/// Exact three-way comparison of two name numbers (any number of digits).
inline int compare_numbers(const ScanNameNumber& a, const ScanNameNumber& b) noexcept {
  if (a.integer.size() != b.integer.size()) return a.integer.size() < b.integer.size() ? -1 : 1;
  if (const int c = a.integer.compare(b.integer); c != 0) return c < 0 ? -1 : 1;
  if (const int c = a.fraction.compare(b.fraction); c != 0) return c < 0 ? -1 : 1;
  return 0;
}

/// Decimal digits of the seconds' unit a name-number's integer is read in: 0
/// seconds, 3 ms, 6 us, 9 ns; -1 when the name is not a time (see the file
/// comment for the digit ranges).
inline int time_unit_digits(const ScanNameNumber& n) noexcept {
  if (!n.whole_name) return -1;
  const std::size_t d = n.integer.size();
  if (d >= 9 && d <= 11) return 0;
  if (!n.fraction.empty()) return -1;
  if (d >= 12 && d <= 14) return 3;
  if (d >= 15 && d <= 17) return 6;
  if (d >= 18 && d <= 19) return 9;
  return -1;
}

/// Seconds of a time name read with `unit_digits` (time_unit_digits), rounded
/// once from the exact decimal text.
inline double name_seconds(const ScanNameNumber& n, int unit_digits) {
  const std::size_t cut = n.integer.size() - static_cast<std::size_t>(unit_digits);
  std::string text = n.integer.substr(0, cut) + "." + n.integer.substr(cut) + n.fraction;
  if (text.back() == '.') text += '0';
  return to_double(text).value_or(0.0);  // digits only: always parses
}

/// Lower-case extension of a path ("" when none).
inline std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

}  // namespace detail

/// Settings of a ScanFolder.
struct ScanFolderConfig {
  /// Frame period [s] of the nominal-period stamp rule.
  double nominal_period_s = 0.1;
  /// Explicit ground-truth file (KITTI 3x4 or TUM); empty = `<dir>/poses.txt` when present.
  std::string ground_truth_path;
};

/// What a scan folder's file names and times.txt decide: format, frame
/// order and stamps (ScanFolder's constructor, without the file system).
struct ScanFolderPlan {
  ScanFileFormat format = ScanFileFormat::kitti_bin;             ///< format of every scan file
  std::vector<std::string> files;                                 ///< scan file name of frame i
  std::vector<double> stamps;                                     ///< stamp of frame i [s] (sweep start)
  ScanStampSource stamp_source = ScanStampSource::nominal_period;  ///< the rule that decided `stamps`
};

/// Plans the frames of a scan folder from the names of its regular files
/// (any order; non-scan and hidden names are ignored) and the text of its
/// times.txt (nullopt when there is none); `directory` names the folder in
/// messages. The rules are the file comment's. Throws ConfigError
/// (nominal_period_s not positive), FormatError (no scans, mixed formats, a
/// name without a number, two names with the same number), ValueError
/// (times.txt count differs from the scan count) plus what parse_kitti_times
/// throws for malformed times. ScanFolder runs exactly this on its listing.
inline ScanFolderPlan plan_scan_folder(const std::vector<std::string>& names,
                                       const std::optional<std::string_view>& times_text,
                                       const std::string& directory, const ScanFolderConfig& config = {}) {
  namespace fs = std::filesystem;
  if (!(config.nominal_period_s > 0.0 && std::isfinite(config.nominal_period_s))) {
    throw ConfigError("ScanFolderConfig.nominal_period_s must be positive and finite, got " +
                      std::to_string(config.nominal_period_s));
  }
  const fs::path dir(directory);
  ScanFolderPlan plan;
  struct Entry {
    std::string name;
    detail::ScanNameNumber number;
  };
  std::vector<Entry> entries;
  std::string first_of[3];  // one file name per format, for the mixed-format message
  for (const std::string& name : names) {
    if (name.empty() || name.front() == '.') continue;
    const fs::path file(name);
    const std::string ext = detail::lower_extension(file);
    int kind = -1;
    if (ext == ".pcd") kind = 0;
    if (ext == ".ply") kind = 1;
    if (ext == ".bin") kind = 2;
    if (kind < 0) continue;
    std::string& first = first_of[static_cast<std::size_t>(kind)];
    if (first.empty()) first = name;
    const auto number = detail::scan_name_number(file.stem().string());
    if (!number) {
      throw FormatError(detail::where((dir / file).string(), 0,
                                      "scan file name has no number to order it by (move it out of the folder)"));
    }
    entries.push_back({name, *number});
  }
  if (entries.empty()) throw FormatError(detail::where(directory, 0, "no .pcd, .ply or .bin scans"));
  const int kinds = static_cast<int>(!first_of[0].empty()) + static_cast<int>(!first_of[1].empty()) +
                    static_cast<int>(!first_of[2].empty());
  if (kinds > 1) {
    std::string listed;
    for (const std::string& f : first_of) {
      if (f.empty()) continue;
      listed += (listed.empty() ? "" : ", ") + f;
    }
    throw FormatError(detail::where(directory, 0, "mixes scan formats (" + listed + "): keep one format per folder"));
  }
  plan.format = !first_of[0].empty()   ? ScanFileFormat::pcd
                : !first_of[1].empty() ? ScanFileFormat::ply
                                       : ScanFileFormat::kitti_bin;
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return detail::compare_numbers(a.number, b.number) < 0; });
  for (std::size_t i = 1; i < entries.size(); ++i) {
    if (detail::compare_numbers(entries[i - 1].number, entries[i].number) == 0) {
      throw FormatError(detail::where((dir / entries[i].name).string(), 0,
                                      "has the same number as " + entries[i - 1].name + " (frame order is ambiguous)"));
    }
  }
  std::vector<detail::ScanNameNumber> numbers;
  numbers.reserve(entries.size());
  plan.files.reserve(entries.size());
  for (Entry& e : entries) {
    plan.files.push_back(std::move(e.name));
    numbers.push_back(std::move(e.number));
  }

  if (times_text) {
    const std::string times = (dir / "times.txt").string();
    plan.stamps = parse_kitti_times(*times_text, times);
    if (plan.stamps.size() != plan.files.size()) {
      throw ValueError(detail::where(times, 0,
                                     "has " + std::to_string(plan.stamps.size()) + " times but the folder has " +
                                         std::to_string(plan.files.size()) + " scans"));
    }
    plan.stamp_source = ScanStampSource::times_file;
    return plan;
  }
  const int unit = detail::time_unit_digits(numbers.front());
  const bool named_by_time = unit >= 0 && std::all_of(numbers.begin(), numbers.end(), [&](const auto& n) {
                               return detail::time_unit_digits(n) == unit;
                             });
  plan.stamps.reserve(numbers.size());
  if (named_by_time) {
    for (const auto& n : numbers) plan.stamps.push_back(detail::name_seconds(n, unit));
    plan.stamp_source = ScanStampSource::file_name;
    return plan;
  }
  // Integer frame numbers below 1e9 (at most 8 digits here, 9 being a time).
  const bool frame_numbers = std::all_of(numbers.begin(), numbers.end(),
                                         [](const auto& n) { return n.fraction.empty() && n.integer.size() <= 8; });
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    const double k =
        frame_numbers ? static_cast<double>(detail::to_int(numbers[i].integer).value_or(0)) : static_cast<double>(i);
    plan.stamps.push_back(k * config.nominal_period_s);
  }
  plan.stamp_source = ScanStampSource::nominal_period;
  return plan;
}

/// Parses a scan folder's ground truth already in memory (`path` names it):
/// TUM when the first non-blank, non-comment line has 8 fields, else KITTI
/// 3x4; returns the lidar poses as stored. Throws ValueError when the pose
/// count differs from `frame_count`, plus what parse_kitti_poses /
/// parse_tum_trajectory throw.
inline std::vector<SE3d> parse_scan_folder_ground_truth(std::string_view text, const std::string& path,
                                                        std::size_t frame_count) {
  std::vector<SE3d> poses;
  if (looks_like_tum_text(text)) {
    for (const StampedPose& p : parse_tum_trajectory(text, path)) poses.push_back(p.pose);
  } else {
    poses = parse_kitti_poses(text, path);
  }
  if (poses.size() != frame_count) {
    throw ValueError(detail::where(path, 0,
                                   "has " + std::to_string(poses.size()) + " poses but the folder has " +
                                       std::to_string(frame_count) + " scans"));
  }
  return poses;
}

/// A folder of scans: the file list, order and stamps are decided on
/// construction; scans and ground truth are read only when asked for. Const
/// member functions only read files, so concurrent calls are safe.
class ScanFolder {
 public:
  using Config = ScanFolderConfig;

  /// Opens `directory`. Throws ConfigError (nominal_period_s not positive),
  /// IoError (no such folder, explicit ground truth missing), FormatError (no
  /// scans, mixed formats, a name without a number, two names with the same
  /// number) and ValueError (times.txt count differs from the scan count),
  /// plus what read_kitti_times throws for a malformed times.txt. The
  /// decisions are plan_scan_folder's.
  explicit ScanFolder(const std::string& directory, const Config& config = {}) : config_(config) {
    namespace fs = std::filesystem;
    if (!(config_.nominal_period_s > 0.0 && std::isfinite(config_.nominal_period_s))) {
      throw ConfigError("ScanFolderConfig.nominal_period_s must be positive and finite, got " +
                        std::to_string(config_.nominal_period_s));
    }
    fs::path dir = fs::path(directory).lexically_normal();
    if (dir.filename().empty()) dir = dir.parent_path();  // trailing '/'
    dir_ = dir.string();
    // The file system gives the names and times.txt; plan_scan_folder decides
    // (the code the scan_folder fuzz harness runs from memory).
    const std::vector<std::string> names = list_regular_files(dir);
    std::error_code ec;
    const fs::path times = dir / "times.txt";
    std::optional<std::string> times_text;
    if (fs::is_regular_file(times, ec)) times_text = detail::read_file(times.string());
    ScanFolderPlan plan = plan_scan_folder(
        names, times_text ? std::optional<std::string_view>(*times_text) : std::nullopt, dir_, config_);
    format_ = plan.format;
    files_ = std::move(plan.files);
    stamps_ = std::move(plan.stamps);
    source_ = plan.stamp_source;
    discover_ground_truth(dir);
  }

  /// Number of frames (scan files).
  [[nodiscard]] std::size_t size() const noexcept { return files_.size(); }
  /// The folder (normalised, no trailing separator).
  [[nodiscard]] const std::string& directory() const noexcept { return dir_; }
  /// Format of the scan files.
  [[nodiscard]] ScanFileFormat format() const noexcept { return format_; }
  /// Path of frame i's scan file.
  [[nodiscard]] std::string scan_path(std::size_t i) const {
    check_index(i);
    return (std::filesystem::path(dir_) / files_[i]).string();
  }
  /// Stamp of frame i [s] (sweep start; see stamp_source()).
  [[nodiscard]] double stamp(std::size_t i) const {
    check_index(i);
    return stamps_[i];
  }
  /// Every frame's stamp [s].
  [[nodiscard]] const std::vector<double>& stamps() const noexcept { return stamps_; }
  /// Which rule decided the stamps.
  [[nodiscard]] ScanStampSource stamp_source() const noexcept { return source_; }

  /// Reads frame i in the file's (sensor) frame with stamp_s = stamp(i).
  /// Dropped points (NaN/Inf, (0,0,0)) are added to `stats`. Throws ValueError
  /// (i out of range) and what read_pcd / read_ply / read_kitti_bin throw.
  [[nodiscard]] Scan read(std::size_t i, ReadStats* stats = nullptr) const {
    const std::string path = scan_path(i);
    Scan scan;
    switch (format_) {
      case ScanFileFormat::pcd:
        scan = read_pcd(path, stats);
        break;
      case ScanFileFormat::ply:
        scan = read_ply(path, stats);
        break;
      case ScanFileFormat::kitti_bin:
        scan = read_kitti_bin(path, stats);
        break;
    }
    scan.stamp_s = stamps_[i];
    return scan;
  }

  /// Frame i as read() returns it; when its file cannot be read (removed,
  /// empty, truncated, malformed) an empty scan at the frame's stamp instead,
  /// with the reason in `error` (cleared when the frame is fine): one corrupt
  /// file costs one frame, not the run. Still throws ValueError for i out of
  /// range (a caller bug, not bad data).
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

  /// The ground-truth file found (empty when none).
  [[nodiscard]] const std::string& ground_truth_path() const noexcept { return gt_path_; }
  /// True when a ground-truth file was found.
  [[nodiscard]] bool has_ground_truth() const noexcept { return !gt_path_.empty(); }
  /// Ground truth as stored (lidar poses, one per frame). Throws IoError when
  /// there is none, ValueError when its pose count differs from the frame
  /// count, plus what read_kitti_poses / read_tum_trajectory throw.
  [[nodiscard]] std::vector<SE3d> ground_truth_lidar() const {
    if (gt_path_.empty()) throw IoError(detail::where(dir_, 0, "no ground truth (poses.txt) for this folder"));
    return parse_scan_folder_ground_truth(detail::read_file(gt_path_), gt_path_, size());
  }
  /// ground_truth_lidar() (the brief name; the same poses).
  [[nodiscard]] std::vector<SE3d> ground_truth() const { return ground_truth_lidar(); }

 private:
  void check_index(std::size_t i) const {
    if (i >= files_.size()) {
      throw ValueError(detail::where(
          dir_, 0, "frame " + std::to_string(i) + " out of range (" + std::to_string(files_.size()) + " frames)"));
    }
  }

  // Names of the regular files in `dir` (any order).
  static std::vector<std::string> list_regular_files(const std::filesystem::path& dir) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw IoError(detail::where(dir.string(), 0, "scan folder does not exist"));
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      std::error_code ec_file;
      if (entry.is_regular_file(ec_file)) names.push_back(entry.path().filename().string());
    }
    if (ec) throw IoError(detail::where(dir.string(), 0, "cannot list directory: " + ec.message()));
    return names;
  }

  void discover_ground_truth(const std::filesystem::path& dir) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!config_.ground_truth_path.empty()) {
      if (!fs::is_regular_file(config_.ground_truth_path, ec)) {
        throw IoError(detail::where(config_.ground_truth_path, 0, "ground-truth file does not exist"));
      }
      gt_path_ = config_.ground_truth_path;
      return;
    }
    if (fs::is_regular_file(dir / "poses.txt", ec)) gt_path_ = (dir / "poses.txt").string();
  }

  Config config_;
  std::string dir_;
  ScanFileFormat format_ = ScanFileFormat::kitti_bin;
  std::vector<std::string> files_;  // file name of frame i
  std::vector<double> stamps_;
  ScanStampSource source_ = ScanStampSource::nominal_period;
  std::string gt_path_;
};

}  // namespace semlio::io
