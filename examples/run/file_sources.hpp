#pragma once
// FrameSources over files: KITTI raw drives as published and folders of
// PCD / PLY / .bin scans (the KITTI odometry folder is in frame_source.hpp),
// and the input-format detection semlio_run uses.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/kitti_raw.hpp>
#include <semlio/io/scan_folder.hpp>

#include "frame_source.hpp"

namespace semlio_examples {

/// A KITTI raw drive folder as published (velodyne_points/, oxts/, the day's
/// calibration beside it): HDL-64E scans in the sensor's point order, the
/// OXTS record as IMU stream and reference trajectory. Outputs stay in the
/// lidar frame.
class KittiRawSource final : public FrameSource {
 public:
  /// Opens `dir`; `calib_dir` overrides where the calib_*.txt files are looked for.
  KittiRawSource(const std::string& dir, const std::string& calib_dir) : drive_(dir, config(calib_dir)) {
    facts_.format = "kitti-raw";
    facts_.path = dir;
    facts_.decided.emplace_back("stamps", drive_.stamp_source() == semlio::io::KittiRawStampSource::sweep_start
                                              ? "velodyne_points/timestamps_start.txt (sweep start)"
                                              : "velodyne_points/timestamps.txt (sweep middle - half a period)");
    if (drive_.interpolated_stamp_count() > 0) {
      facts_.decided.emplace_back("interpolated_stamps", std::to_string(drive_.interpolated_stamp_count()) +
                                                             " (blank lines in the timestamps files)");
    }
    if (drive_.missing_frame_count() > 0) {
      facts_.decided.emplace_back("missing_frames", std::to_string(drive_.missing_frame_count()));
    }
    facts_.decided.emplace_back("calibration", drive_.has_calibration() ? drive_.calib_dir() : "not found");
    facts_.decided.emplace_back("oxts_packets", std::to_string(drive_.oxts_packet_count()));
  }

  [[nodiscard]] std::size_t size() const override { return drive_.size(); }
  SourceFrame read(std::size_t i) override {
    SourceFrame f;
    f.missing = !drive_.has_scan(i);
    f.scan = drive_.read_or_empty(i, f.error, &f.dropped);
    return f;
  }
  [[nodiscard]] std::optional<double> stamp_hint(std::size_t i) const override { return drive_.stamp(i); }
  [[nodiscard]] std::vector<semlio::Scan> first_scans(std::size_t k) override {
    return first_readable(k, size(), [this](std::size_t i, std::string& e) { return drive_.read_or_empty(i, e); });
  }
  [[nodiscard]] std::optional<std::vector<semlio::SE3d>> ground_truth_lidar() const override {
    if (!drive_.has_ground_truth()) return std::nullopt;
    return drive_.reference_poses_lidar();
  }
  [[nodiscard]] std::string ground_truth_source() const override {
    return drive_.has_ground_truth() ? "oxts (KITTI raw devkit poses)" : "";
  }
  [[nodiscard]] ImuInput imu() const override {
    ImuInput in;
    if (!drive_.has_oxts()) return in;
    const std::vector<semlio::io::OxtsRecord> records = drive_.oxts_records();
    in.samples = semlio::io::imu_samples(records);
    in.velocities = oxts_velocities(records);
    in.source = "oxts";
    if (drive_.has_calibration()) in.T_imu_lidar = drive_.T_velo_imu().inverse();
    return in;
  }
  [[nodiscard]] bool kitti_scans() const override { return true; }

 private:
  static semlio::io::KittiRawDriveConfig config(const std::string& calib_dir) {
    semlio::io::KittiRawDriveConfig c;
    c.calib_dir = calib_dir;
    return c;
  }
  semlio::io::KittiRawDrive drive_;
};

/// A folder of .pcd, .ply or .bin scans (sensor frame), optional times.txt
/// and poses.txt.
class ScanFolderSource final : public FrameSource {
 public:
  /// Opens `dir`; `gt` overrides the folder's poses.txt.
  ScanFolderSource(const std::string& dir, const std::string& gt) : folder_(dir, config(gt)) {
    facts_.format = "folder";
    facts_.path = dir;
    const char* format = folder_.format() == semlio::io::ScanFileFormat::pcd   ? "pcd"
                         : folder_.format() == semlio::io::ScanFileFormat::ply ? "ply"
                                                                                : "KITTI .bin";
    facts_.decided.emplace_back("scan_files", format);
    const char* stamps = folder_.stamp_source() == semlio::io::ScanStampSource::times_file ? "times.txt"
                         : folder_.stamp_source() == semlio::io::ScanStampSource::file_name
                             ? "file names (times)"
                             : "nominal 0.1 s period (no times.txt, names are not times)";
    facts_.decided.emplace_back("stamps", stamps);
  }

  [[nodiscard]] std::size_t size() const override { return folder_.size(); }
  SourceFrame read(std::size_t i) override {
    SourceFrame f;
    f.scan = folder_.read_or_empty(i, f.error, &f.dropped);
    return f;
  }
  [[nodiscard]] std::optional<double> stamp_hint(std::size_t i) const override { return folder_.stamp(i); }
  [[nodiscard]] std::vector<semlio::Scan> first_scans(std::size_t k) override {
    return first_readable(k, size(), [this](std::size_t i, std::string& e) { return folder_.read_or_empty(i, e); });
  }
  [[nodiscard]] std::optional<std::vector<semlio::SE3d>> ground_truth_lidar() const override {
    if (!folder_.has_ground_truth()) return std::nullopt;
    return folder_.ground_truth_lidar();
  }
  [[nodiscard]] std::string ground_truth_source() const override { return folder_.ground_truth_path(); }

 private:
  static semlio::io::ScanFolderConfig config(const std::string& gt) {
    semlio::io::ScanFolderConfig c;
    c.ground_truth_path = gt;
    return c;
  }
  semlio::io::ScanFolder folder_;
};

/// The input format of `path` by its shape, and why: a .bag / .mcap / .db3
/// file; a folder with metadata.yaml or .db3 files (rosbag2); velodyne/
/// (KITTI odometry); velodyne_points/data/ (KITTI raw); else scan files.
inline std::pair<std::string, std::string> detect_format(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  if (!fs::exists(p, ec)) throw semlio::IoError(path + ": --input does not exist");
  if (fs::is_regular_file(p, ec)) {
    const std::string ext = p.extension().string();
    if (ext == ".bag") return {"bag", "detected: .bag file (ROS 1)"};
    if (ext == ".mcap") return {"mcap", "detected: .mcap file"};
    if (ext == ".db3") return {"db3", "detected: .db3 file (rosbag2 sqlite3)"};
    throw semlio::FormatError(path + ": a file that is not .bag, .mcap or .db3; give a folder for scan files, "
                                     "or --format");
  }
  if (fs::is_regular_file(p / "metadata.yaml", ec)) {
    for (const auto& e : fs::directory_iterator(p, ec)) {
      if (e.path().extension() == ".mcap") return {"mcap", "detected: rosbag2 folder with .mcap storage"};
    }
    return {"db3", "detected: rosbag2 folder (metadata.yaml)"};
  }
  if (fs::is_directory(p / "velodyne", ec)) return {"kitti", "detected: velodyne/ folder (KITTI odometry)"};
  if (fs::is_directory(p / "velodyne_points" / "data", ec)) {
    return {"kitti-raw", "detected: velodyne_points/data/ (KITTI raw drive)"};
  }
  for (const auto& e : fs::directory_iterator(p, ec)) {
    if (e.path().extension() == ".db3") return {"db3", "detected: folder with .db3 files"};
  }
  return {"folder", "detected: folder of scan files"};
}

}  // namespace semlio_examples
