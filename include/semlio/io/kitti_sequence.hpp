#pragma once
/// \file
/// A KITTI odometry / SemanticKITTI sequence directory read lazily, frame by
/// frame:
///
///     <dir>/velodyne/NNNNNN.bin      scans, numbered 0..n-1 without gaps
///     <dir>/<label folder>/NNNNNN.label  optional (labels/, predictions/, ...)
///     <dir>/calib.txt                 optional (Tr = T_cam0_velo)
///     <dir>/times.txt                 optional, one stamp per frame
///
/// Ground truth (KITTI 3x4 format, camera-0 frame when calib.txt has `Tr`) is
/// found in this order: an explicit path, `<dir>/poses.txt` (the layout
/// semlio's simulator writes), the official `dataset/poses/NN.txt` beside
/// `dataset/sequences/NN/`.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// Settings of a KittiSequence.
struct KittiSequenceConfig {
  /// Folder (inside the sequence dir) whose NNNNNN.label files are read with
  /// the scans; labels are read when the folder exists. Empty: never read labels.
  std::string label_folder = "labels";
  /// Explicit ground-truth file (KITTI format); empty = discover.
  std::string ground_truth_path;
  /// Frame period used for stamps when there is no times.txt [s] (HDL-64E: 10 Hz).
  double nominal_period_s = 0.1;
  /// A gap in the frame numbering (a deleted scan): false = FormatError on
  /// construction; true = the missing numbers are frames of their own that
  /// is_missing() reports and read() refuses, so one lost file costs one frame.
  bool allow_gaps = false;
};

/// A sequence directory: the frame list, calib and times are read on
/// construction; scans, labels and ground truth only when asked for.
/// Const member functions only read files, so concurrent calls are safe.
class KittiSequence {
 public:
  using Config = KittiSequenceConfig;

  /// Opens `directory`. Throws IoError (no velodyne/ folder, explicit ground
  /// truth missing), FormatError (no scans, a non-numeric scan name, a gap in
  /// the frame numbering: the message names the first missing frame's file)
  /// and ValueError (times.txt count differs from the frame count), plus
  /// whatever read_kitti_calib / read_kitti_times throw.
  explicit KittiSequence(const std::string& directory, const Config& config = {}) : config_(config) {
    namespace fs = std::filesystem;
    fs::path dir = fs::path(directory).lexically_normal();
    if (dir.filename().empty()) dir = dir.parent_path();  // trailing '/'
    dir_ = dir.string();
    list_frames(dir / "velodyne");

    std::error_code ec;
    has_labels_ = !config_.label_folder.empty() && fs::is_directory(dir / config_.label_folder, ec);
    if (fs::exists(dir / "calib.txt", ec)) calib_ = read_kitti_calib((dir / "calib.txt").string());
    if (fs::exists(dir / "times.txt", ec)) {
      const std::string path = (dir / "times.txt").string();
      times_ = read_kitti_times(path);
      if (times_.size() != stems_.size()) {
        throw ValueError(detail::where(path, 0,
                                       "has " + std::to_string(times_.size()) + " times but velodyne/ has " +
                                           std::to_string(stems_.size()) + " scans"));
      }
    }
    discover_ground_truth(dir);
  }

  /// Number of frames.
  [[nodiscard]] std::size_t size() const noexcept { return stems_.size(); }
  /// The sequence directory (normalised, no trailing separator).
  [[nodiscard]] const std::string& directory() const noexcept { return dir_; }
  /// True when frame i's scan file is absent (a gap; only with allow_gaps).
  [[nodiscard]] bool is_missing(std::size_t i) const {
    check_index(i);
    return missing_[i] != 0;
  }
  /// Number of frames whose scan file is absent.
  [[nodiscard]] std::size_t missing_count() const noexcept {
    std::size_t n = 0;
    for (const char m : missing_) n += m != 0 ? 1U : 0U;
    return n;
  }
  /// Path of frame i's scan.
  [[nodiscard]] std::string scan_path(std::size_t i) const {
    check_index(i);
    return (std::filesystem::path(dir_) / "velodyne" / (stems_[i] + ".bin")).string();
  }
  /// Path of frame i's label file in the configured label folder.
  [[nodiscard]] std::string label_path(std::size_t i) const {
    check_index(i);
    return (std::filesystem::path(dir_) / config_.label_folder / (stems_[i] + ".label")).string();
  }
  /// True when the configured label folder exists (scans are read with labels).
  [[nodiscard]] bool has_labels() const noexcept { return has_labels_; }
  /// calib.txt when present.
  [[nodiscard]] const std::optional<Calibration>& calibration() const noexcept { return calib_; }
  /// times.txt (one per frame) or empty when absent.
  [[nodiscard]] const std::vector<double>& times() const noexcept { return times_; }
  /// Stamp of frame i [s]: times.txt, else i * nominal_period_s.
  [[nodiscard]] double stamp(std::size_t i) const {
    check_index(i);
    return times_.empty() ? static_cast<double>(i) * config_.nominal_period_s : times_[i];
  }

  /// Reads frame i: points, intensity, labels/instances when has_labels(),
  /// stamp_s. Dropped points (NaN/Inf, (0,0,0)) are added to `stats`. Throws
  /// ValueError (i out of range) and what read_kitti_scan throws (missing or
  /// empty scan, missing label file, label count mismatch).
  [[nodiscard]] Scan read(std::size_t i, ReadStats* stats = nullptr) const {
    check_index(i);
    if (missing_[i] != 0) throw IoError(detail::where(scan_path(i), 0, "scan file is missing (gap in the frame numbering)"));
    Scan scan =
        read_kitti_scan(scan_path(i), has_labels_ ? std::optional<std::string>(label_path(i)) : std::nullopt, stats);
    scan.stamp_s = stamp(i);
    return scan;
  }

  /// Frame i as read() returns it; when its files cannot be read (scan
  /// missing, empty, truncated or malformed; label file missing or of the
  /// wrong count) an empty scan at the frame's stamp instead, with the reason
  /// in `error` (cleared when the frame is fine). A degraded mode for long
  /// runs: the odometry reports an empty scan as too_few_features and keeps
  /// going on its prediction, so one corrupt file does not end a drive.
  /// Still throws ValueError for i out of range (a caller bug, not bad data).
  [[nodiscard]] Scan read_or_empty(std::size_t i, std::string& error, ReadStats* stats = nullptr) const {
    check_index(i);
    error.clear();
    try {
      return read(i, stats);
    } catch (const Error& e) {
      error = e.what();
    }
    Scan scan;
    scan.stamp_s = stamp(i);
    return scan;
  }

  /// The ground-truth file found (empty when none).
  [[nodiscard]] const std::string& ground_truth_path() const noexcept { return gt_path_; }
  /// True when a ground-truth file was found.
  [[nodiscard]] bool has_ground_truth() const noexcept { return !gt_path_.empty(); }
  /// Ground truth as stored (KITTI poses P_i, camera-0 frame for KITTI data).
  /// Throws IoError when there is none, ValueError when its pose count differs
  /// from the frame count, plus what read_kitti_poses throws.
  [[nodiscard]] std::vector<SE3d> ground_truth_camera() const {
    if (gt_path_.empty()) throw IoError(detail::where(dir_, 0, "no ground truth found for this sequence"));
    std::vector<SE3d> poses = read_kitti_poses(gt_path_);
    if (poses.size() != size()) {
      throw ValueError(detail::where(
          gt_path_, 0,
          "has " + std::to_string(poses.size()) + " poses but the sequence has " + std::to_string(size()) + " frames"));
    }
    return poses;
  }
  /// Ground truth as lidar poses T_i = Tr^-1 P_i Tr (lidar of frame i into
  /// lidar of frame 0) when calib.txt has `Tr`; without it the poses are
  /// returned unchanged (already lidar frame). Throws like ground_truth_camera.
  [[nodiscard]] std::vector<SE3d> ground_truth_lidar() const {
    std::vector<SE3d> poses = ground_truth_camera();
    if (calib_ && calib_->T_cam0_velo) return camera_to_lidar(poses, *calib_->T_cam0_velo);
    return poses;
  }

  /// Input iterator reading one frame per dereference (lazily, by value).
  class Iterator {
   public:
    using iterator_category = std::input_iterator_tag;
    using value_type = Scan;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = Scan;

    Iterator() = default;
    Iterator(const KittiSequence* seq, std::size_t i, ReadStats* stats) : seq_(seq), i_(i), stats_(stats) {}
    /// Reads the current frame (file access on every call).
    Scan operator*() const { return seq_->read(i_, stats_); }
    Iterator& operator++() {
      ++i_;
      return *this;
    }
    Iterator operator++(int) {
      Iterator old = *this;
      ++i_;
      return old;
    }
    bool operator==(const Iterator& other) const { return i_ == other.i_; }
    /// Frame index of the current position.
    [[nodiscard]] std::size_t index() const noexcept { return i_; }

   private:
    const KittiSequence* seq_ = nullptr;
    std::size_t i_ = 0;
    ReadStats* stats_ = nullptr;
  };

  /// First frame; dropped-point counts go to `stats` when given.
  [[nodiscard]] Iterator begin(ReadStats* stats = nullptr) const { return Iterator(this, 0, stats); }
  /// One past the last frame.
  [[nodiscard]] Iterator end() const { return Iterator(this, size(), nullptr); }

 private:
  void check_index(std::size_t i) const {
    if (i >= stems_.size()) {
      throw ValueError(detail::where(
          dir_, 0, "frame " + std::to_string(i) + " out of range (" + std::to_string(stems_.size()) + " frames)"));
    }
  }

  void list_frames(const std::filesystem::path& velodyne) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(velodyne, ec))
      throw IoError(detail::where(velodyne.string(), 0, "scan directory does not exist"));
    std::map<std::uint64_t, std::string> by_number;
    std::size_t width = 6;
    for (const auto& entry : fs::directory_iterator(velodyne, ec)) {
      if (entry.path().extension() != ".bin") continue;
      const std::string stem = entry.path().stem().string();
      const auto number = detail::to_int(stem);
      if (!number || *number < 0 || stem.find_first_not_of("0123456789") != std::string::npos) {
        throw FormatError(detail::where(entry.path().string(), 0, "scan file name is not a frame number"));
      }
      const auto key = static_cast<std::uint64_t>(*number);
      if (by_number.count(key) != 0) {
        throw FormatError(
            detail::where(entry.path().string(), 0,
                          "frame " + std::to_string(key) + " appears twice (also " + by_number[key] + ".bin)"));
      }
      by_number.emplace(key, stem);
      width = stem.size();
    }
    if (ec) throw IoError(detail::where(velodyne.string(), 0, "cannot list directory: " + ec.message()));
    if (by_number.empty()) throw FormatError(detail::where(velodyne.string(), 0, "no .bin scans"));
    std::uint64_t expected = 0;
    for (const auto& [number, stem] : by_number) {
      if (number != expected && !config_.allow_gaps) {
        const std::string missing = detail::frame_stem(expected, static_cast<int>(width)) + ".bin";
        throw FormatError(detail::where((velodyne / missing).string(), 0,
                                        "gap in frame numbering: frame " + std::to_string(expected) +
                                            " is missing (next present: " + stem + ".bin)"));
      }
      // A gap of more than 10 million frames is a misnamed file, not lost scans.
      if (number - expected > 10'000'000U) {
        throw FormatError(detail::where(velodyne.string(), 0,
                                        "frame numbering jumps from " + std::to_string(expected) + " to " + stem +
                                            ".bin: not a sequence of frames"));
      }
      for (; expected < number; ++expected) {
        stems_.push_back(detail::frame_stem(expected, static_cast<int>(width)));
        missing_.push_back(1);
      }
      stems_.push_back(stem);
      missing_.push_back(0);
      ++expected;
    }
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
    if (fs::is_regular_file(dir / "poses.txt", ec)) {
      gt_path_ = (dir / "poses.txt").string();
      return;
    }
    const fs::path parent = dir.parent_path();
    if (parent.filename() == "sequences") {
      const fs::path official = parent.parent_path() / "poses" / (dir.filename().string() + ".txt");
      if (fs::is_regular_file(official, ec)) gt_path_ = official.string();
    }
  }

  Config config_;
  std::string dir_;
  std::vector<std::string> stems_;  // file stem of frame i ("000042")
  std::vector<char> missing_;       // 1: frame i's scan file is absent (allow_gaps)
  bool has_labels_ = false;
  std::optional<Calibration> calib_;
  std::vector<double> times_;
  std::string gt_path_;
};

static_assert(std::input_iterator<KittiSequence::Iterator>);

}  // namespace semlio::io
