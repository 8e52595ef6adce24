#pragma once
// What the odometry tools read their frames from. semlio_kitti and semlio_run
// share one run loop (odometry_tool.hpp); each input format is a FrameSource:
// a KITTI odometry folder, a KITTI raw drive, a folder of scans, a ROS 1 bag,
// an MCAP file or a rosbag2 sqlite3 bag. A source hands out frames in order,
// one scan per call, plus what the run needs besides scans: ground truth,
// the camera calibration for KITTI-style outputs, an IMU stream, and the facts
// report.json records about how the input was read.
//
// Virtual calls are fine here: one per frame, outside the odometry's loops.

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/sensor_profiles.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/io/kitti_sequence.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/lie/se3.hpp>

#include "imu_oxts.hpp"

namespace semlio_examples {

/// How the input was read, for the summary and report.json's "input" object:
/// (key, value) pairs in the order they were decided.
struct SourceFacts {
  std::string format;                                        ///< kitti | kitti-raw | folder | bag | mcap | db3
  std::string path;                                          ///< the input path as given
  std::vector<std::pair<std::string, std::string>> decided;  ///< e.g. {"format", "detected: velodyne/ folder"}
};

/// An IMU stream with what the lidar-inertial odometry needs beside it.
struct ImuInput {
  std::vector<semlio::ImuSample> samples;    ///< in time order
  std::vector<OxtsVelocity> velocities;      ///< optional INS velocities (KITTI OXTS), else empty
  std::optional<semlio::SE3d> T_imu_lidar;   ///< lidar -> IMU extrinsic when the input states it
  std::string source;                        ///< e.g. "oxts", "/imu/data"
};

/// One frame as read: the scan (empty when unreadable), why it could not be
/// read (empty: read fine), whether its file is missing altogether, and the
/// points the reader dropped (NaN/Inf, (0,0,0)).
struct SourceFrame {
  semlio::Scan scan;
  std::string error;
  bool missing = false;
  semlio::io::ReadStats dropped;
};

/// Frames in order plus their side information. read() is called with
/// increasing indices (a bag is read sequentially); it never throws for bad
/// data in one frame, which comes back in SourceFrame::error, so that a bad
/// frame costs one frame.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Number of frames (known before reading: file counts, bag index counts).
  [[nodiscard]] virtual std::size_t size() const = 0;
  /// Reads frame i (i increasing from call to call).
  virtual SourceFrame read(std::size_t i) = 0;
  /// Up to k of the first readable scans, read aside (the frame order of
  /// read() is not disturbed): what beam detection looks at.
  [[nodiscard]] virtual std::vector<semlio::Scan> first_scans(std::size_t k) = 0;
  /// Stamp of frame i [s] when known before reading it (files with times.txt), else nullopt.
  [[nodiscard]] virtual std::optional<double> stamp_hint(std::size_t /*i*/) const { return std::nullopt; }
  /// What a message's header stamp means (the sensor profile's driver
  /// convention) and the sweep period [s]: a source whose stamps are header
  /// stamps moves a scan without per-point times to its sweep start
  /// (Scan::stamp_s); a scan with them starts at its earliest point anyway.
  /// Called once, before the first read(). Other sources ignore it.
  virtual void set_header_stamp(semlio::StampMeaning /*meaning*/, double /*sweep_period_s*/) {}
  /// True when frames carry per-point labels (SemanticKITTI labels/ folder).
  [[nodiscard]] virtual bool has_labels() const { return false; }
  /// Ground truth as lidar poses, one per frame (frame 0 need not be identity);
  /// nullopt when the input has none. Read and checked before the first frame.
  [[nodiscard]] virtual std::optional<std::vector<semlio::SE3d>> ground_truth_lidar() const { return std::nullopt; }
  /// Where the ground truth came from ("" when none).
  [[nodiscard]] virtual std::string ground_truth_source() const { return {}; }
  /// T_cam0_lidar when outputs are written in KITTI's camera-0 frame.
  [[nodiscard]] virtual std::optional<semlio::SE3d> T_cam0_lidar() const { return std::nullopt; }
  /// The input's IMU stream (empty samples when it has none).
  [[nodiscard]] virtual ImuInput imu() const { return {}; }
  /// True for semlio_simulate drives (sim.json): no KITTI vertical correction,
  /// sweeps start facing backwards.
  [[nodiscard]] virtual bool simulated() const { return false; }
  /// True when the scans are KITTI HDL-64E .bin files in the sensor's point
  /// order (rings from point order, KITTI's vertical-angle correction).
  [[nodiscard]] virtual bool kitti_scans() const { return false; }
  /// How the input was read.
  [[nodiscard]] const SourceFacts& facts() const noexcept { return facts_; }
  /// Records how `key` was decided before every other fact (e.g. the format).
  void add_fact_front(const std::string& key, const std::string& how) {
    facts_.decided.insert(facts_.decided.begin(), {key, how});
  }

 protected:
  SourceFacts facts_;
};

/// Up to k readable scans among frames 0..n-1, read by `read(i, error)`.
template <typename Read>
std::vector<semlio::Scan> first_readable(std::size_t k, std::size_t n, Read read) {
  std::vector<semlio::Scan> out;
  std::string error;
  for (std::size_t i = 0; i < n && out.size() < k; ++i) {
    semlio::Scan s = read(i, error);
    if (error.empty() && !s.empty()) out.push_back(std::move(s));
  }
  return out;
}

/// Settings shared by every source.
struct SourceConfig {
  std::string labels = "labels";     ///< KITTI label folder ("" = none)
  std::string ground_truth_path;     ///< explicit ground truth ("" = discover)
  std::string calib_path;            ///< explicit calib.txt ("" = the input's)
  bool allow_missing_frames = true;  ///< a gap in the numbering costs one frame (else an error up front)
};

/// A KITTI odometry / SemanticKITTI sequence folder (and semlio_simulate's drives).
class KittiFolderSource final : public FrameSource {
 public:
  /// Opens `dir`; throws what KittiSequence throws.
  KittiFolderSource(const std::string& dir, const SourceConfig& config)
      : seq_(dir, sequence_config(config)), config_(config) {
    facts_.format = "kitti";
    facts_.path = dir;
    if (!config.calib_path.empty()) calib_ = semlio::io::read_kitti_calib(config.calib_path);
    else calib_ = seq_.calibration();
    simulated_ = std::filesystem::exists(std::filesystem::path(seq_.directory()) / "sim.json");
    facts_.decided.emplace_back("stamps", seq_.times().empty() ? "nominal 0.1 s period (no times.txt)" : "times.txt");
    if (seq_.missing_count() > 0) facts_.decided.emplace_back("missing_frames", std::to_string(seq_.missing_count()));
  }

  [[nodiscard]] std::size_t size() const override { return seq_.size(); }
  SourceFrame read(std::size_t i) override {
    SourceFrame f;
    f.missing = seq_.is_missing(i);
    f.scan = seq_.read_or_empty(i, f.error, &f.dropped);
    return f;
  }
  [[nodiscard]] bool has_labels() const override { return seq_.has_labels(); }
  [[nodiscard]] std::vector<semlio::Scan> first_scans(std::size_t k) override {
    return first_readable(k, size(), [this](std::size_t i, std::string& e) { return seq_.read_or_empty(i, e); });
  }
  [[nodiscard]] std::optional<double> stamp_hint(std::size_t i) const override { return seq_.stamp(i); }
  [[nodiscard]] std::optional<std::vector<semlio::SE3d>> ground_truth_lidar() const override {
    if (!seq_.has_ground_truth()) return std::nullopt;
    std::vector<semlio::SE3d> gt = seq_.ground_truth_camera();
    if (calib_ && calib_->T_cam0_velo) gt = semlio::io::camera_to_lidar(gt, *calib_->T_cam0_velo);
    return gt;
  }
  [[nodiscard]] std::string ground_truth_source() const override { return seq_.ground_truth_path(); }
  [[nodiscard]] std::optional<semlio::SE3d> T_cam0_lidar() const override {
    if (calib_ && calib_->T_cam0_velo) return *calib_->T_cam0_velo;
    return std::nullopt;
  }
  [[nodiscard]] ImuInput imu() const override {
    ImuInput in;
    const std::filesystem::path oxts_dir = std::filesystem::path(seq_.directory()) / "oxts";
    if (!std::filesystem::is_directory(oxts_dir)) return in;
    const std::vector<semlio::io::OxtsRecord> records = semlio::io::read_oxts(oxts_dir.string());
    in.samples = semlio::io::imu_samples(records);
    in.velocities = oxts_velocities(records);
    in.source = "oxts";
    if (calib_ && calib_->T_imu_velo) in.T_imu_lidar = *calib_->T_imu_velo;
    return in;
  }
  [[nodiscard]] bool simulated() const override { return simulated_; }
  [[nodiscard]] bool kitti_scans() const override { return !simulated_; }
  /// The sequence (stamps, directory).
  [[nodiscard]] const semlio::io::KittiSequence& sequence() const noexcept { return seq_; }
  /// True when calib.txt has no Tr (outputs and evaluation stay in the lidar frame).
  [[nodiscard]] bool has_camera_calibration() const noexcept { return calib_ && calib_->T_cam0_velo; }

 private:
  static semlio::io::KittiSequenceConfig sequence_config(const SourceConfig& c) {
    semlio::io::KittiSequenceConfig s;
    s.label_folder = c.labels;
    s.ground_truth_path = c.ground_truth_path;
    s.allow_gaps = c.allow_missing_frames;
    return s;
  }

  semlio::io::KittiSequence seq_;
  SourceConfig config_;
  std::optional<semlio::io::Calibration> calib_;
  bool simulated_ = false;
};

}  // namespace semlio_examples
