#pragma once
// FrameSources over bags: ROS 1 bags, MCAP files and rosbag2 sqlite3 bags,
// read without ROS through semlio::io_bags. One PointCloud2 topic gives the
// frames (in log-time order), one Imu topic the IMU stream. With a single
// PointCloud2 topic and at most one Imu topic nothing needs naming; several
// are a ConfigError listing them.

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/mcap.hpp>
#include <semlio/io/bag/message.hpp>
#include <semlio/io/bag/rosbag1.hpp>
#include <semlio/io/bag/sqlite_bag.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/ros1_msgs.hpp>
#include <semlio/io/ros_msgs.hpp>
#include <semlio/io/trajectory.hpp>

#include "frame_source.hpp"

namespace semlio_examples {

namespace detail {

/// "/a (sensor_msgs/PointCloud2, 3 messages), /b (...)" for error messages.
inline std::string topic_list(const std::vector<semlio::io::BagTopic>& topics) {
  std::string s;
  for (const semlio::io::BagTopic& t : topics) {
    if (!s.empty()) s += ", ";
    s += t.name + " (" + t.type + ", " + std::to_string(t.message_count) + " messages)";
  }
  return s.empty() ? "none" : s;
}

/// The topic to read: `wanted` when given (it must exist with a matching
/// type), else the only topic of the type; nullopt when there is none and
/// `required` is false. `kind` names the type in messages.
template <typename IsType>
std::optional<std::size_t> choose_topic(const std::vector<semlio::io::BagTopic>& topics, const std::string& wanted,
                                        IsType is_type, const char* kind, const char* option, bool required,
                                        const std::string& path, std::string& why) {
  std::vector<std::size_t> of_type;
  for (std::size_t i = 0; i < topics.size(); ++i) {
    if (!wanted.empty() && topics[i].name == wanted) {
      if (!is_type(topics[i].type)) {
        throw semlio::ConfigError(path + ": " + option + " " + wanted + " is a " + topics[i].type + " topic, not " + kind);
      }
      why = std::string(option);
      return i;
    }
    if (is_type(topics[i].type)) of_type.push_back(i);
  }
  if (!wanted.empty()) {
    throw semlio::ConfigError(path + ": no topic " + wanted + " (" + option + "); topics: " + topic_list(topics));
  }
  if (of_type.size() == 1) {
    why = std::string("the only ") + kind + " topic";
    return of_type.front();
  }
  if (of_type.empty()) {
    if (!required) return std::nullopt;
    throw semlio::FormatError(path + ": no " + kind + " topic; topics: " + topic_list(topics));
  }
  std::string names;
  for (const std::size_t i : of_type) names += (names.empty() ? "" : ", ") + topics[i].name;
  throw semlio::ConfigError(path + ": " + std::to_string(of_type.size()) + " " + kind + " topics (" + names +
                            "); choose one with " + option);
}

}  // namespace detail

/// Frames from the PointCloud2 topic of a bag read by `Reader` (RosBag1Reader,
/// McapReader or SqliteBagReader); the IMU from its Imu topic.
template <typename Reader>
class BagSource final : public FrameSource {
 public:
  /// Opens the bag and chooses the topics (see the file comment); `gt`: an
  /// optional ground truth (KITTI 3x4 or TUM, one pose per cloud); `calib`:
  /// an optional KITTI calib.txt whose Tr puts that ground truth (and the
  /// outputs) in KITTI's camera-0 frame, as for a semlio_simulate drive.
  BagSource(const std::string& path, const std::string& format, const std::string& lidar_topic,
            const std::string& imu_topic, const std::string& gt, const std::string& calib)
      : path_(path), frames_(path), gt_path_(gt) {
    if (!calib.empty()) Tr_ = semlio::io::read_kitti_calib(calib).T_cam0_velo;
    facts_.format = format;
    facts_.path = path;
    const std::vector<semlio::io::BagTopic>& topics = frames_.topics();
    std::string why;
    lidar_ = *detail::choose_topic(topics, lidar_topic, semlio::io::is_pointcloud2_type, "sensor_msgs/PointCloud2",
                                   "--lidar-topic", true, path, why);
    facts_.decided.emplace_back("lidar_topic", topics[lidar_].name + " (" + why + ")");
    imu_ = detail::choose_topic(topics, imu_topic, semlio::io::is_imu_type, "sensor_msgs/Imu", "--imu-topic", false,
                                path, why);
    facts_.decided.emplace_back("imu_topic", imu_ ? topics[*imu_].name + " (" + why + ")" : "none");
    facts_.decided.emplace_back("encoding", topics[lidar_].encoding == semlio::io::MessageEncoding::kRos1 ? "ros1" : "cdr");
    frames_.select({topics[lidar_].name});
    describe_layout();
  }

  [[nodiscard]] std::size_t size() const override { return frames_.topics()[lidar_].message_count; }

  SourceFrame read(std::size_t /*i: frames come in order*/) override {
    SourceFrame f;
    if (!frames_.next(message_)) {
      f.error = "the bag ended before its index's message count";
      f.missing = true;
      return f;
    }
    try {
      decode_cloud(message_, cloud_);
      semlio::io::pointcloud2_to_scan(cloud_, f.scan, cloud_config_, nullptr, &f.dropped);
      if (!f.scan.has_times()) f.scan.stamp_s -= header_after_start_s_;
    } catch (const semlio::Error& e) {
      f.error = e.what();
      f.scan = semlio::Scan();
      f.scan.stamp_s = static_cast<double>(message_.log_time_ns) / 1e9;
    }
    return f;
  }

  void set_header_stamp(semlio::StampMeaning meaning, double sweep_period_s) override {
    const double f = meaning == semlio::StampMeaning::kSweepEnd      ? 1.0
                     : meaning == semlio::StampMeaning::kSweepMiddle ? 0.5
                                                                      : 0.0;
    header_after_start_s_ = f * sweep_period_s;
    if (first_scan_.has_times()) {
      facts_.decided.emplace_back("stamps", "per-point time field: a sweep starts at its earliest point");
    } else {
      facts_.decided.emplace_back("stamps", std::string("header stamp = sweep ") + semlio::to_string(meaning) +
                                                ": sweep start = header stamp - " +
                                                std::to_string(header_after_start_s_) + " s");
    }
  }

  [[nodiscard]] std::optional<std::vector<semlio::SE3d>> ground_truth_lidar() const override {
    if (gt_path_.empty()) return std::nullopt;
    std::vector<semlio::SE3d> gt = read_poses(gt_path_);
    if (Tr_) gt = semlio::io::camera_to_lidar(gt, *Tr_);
    return gt;
  }
  [[nodiscard]] std::optional<semlio::SE3d> T_cam0_lidar() const override { return Tr_; }
  [[nodiscard]] std::string ground_truth_source() const override { return gt_path_; }

  [[nodiscard]] ImuInput imu() const override {
    ImuInput in;
    if (!imu_) return in;
    Reader reader(path_);
    const semlio::io::BagTopic& topic = reader.topics()[*imu_];
    reader.select({topic.name});
    semlio::io::BagMessage m;
    semlio::io::ImuMsg msg;
    while (reader.next(m)) {
      if (topic.encoding == semlio::io::MessageEncoding::kRos1) {
        semlio::io::parse_ros1_imu(m.data.data(), m.data.size(), msg);
      } else {
        semlio::io::parse_cdr_imu(m.data.data(), m.data.size(), msg);
      }
      in.samples.push_back({msg.stamp_s, msg.angular_velocity_radps, msg.linear_acceleration_mps2});
    }
    in.source = topic.name;
    return in;
  }

  [[nodiscard]] std::vector<semlio::Scan> first_scans(std::size_t k) override {
    std::vector<semlio::Scan> out;
    Reader reader(path_);
    reader.select({reader.topics()[lidar_].name});
    semlio::io::BagMessage m;
    semlio::io::PointCloud2Msg cloud;
    while (out.size() < k && reader.next(m)) {
      try {
        decode_cloud(m, cloud);
        semlio::Scan scan;
        semlio::io::pointcloud2_to_scan(cloud, scan, cloud_config_);
        if (!scan.empty()) out.push_back(std::move(scan));
      } catch (const semlio::Error&) {
        // an unreadable cloud is skipped here; read() reports it
      }
    }
    return out;
  }

  /// The first cloud's field layout, for the sensor decision (ring field present?).
  [[nodiscard]] const semlio::io::PointCloud2Layout& layout() const noexcept { return layout_; }

 private:
  void decode_cloud(const semlio::io::BagMessage& m, semlio::io::PointCloud2Msg& out) const {
    if (frames_.topics()[lidar_].encoding == semlio::io::MessageEncoding::kRos1) {
      semlio::io::parse_ros1_pointcloud2(m.data.data(), m.data.size(), out);
    } else {
      semlio::io::parse_cdr_pointcloud2(m.data.data(), m.data.size(), out);
    }
  }

  // Decodes the first cloud with a reader of its own (frames_ stays at the
  // start) and records its fields.
  void describe_layout() {
    Reader reader(path_);
    reader.select({reader.topics()[lidar_].name});
    semlio::io::BagMessage m;
    if (!reader.next(m)) return;
    semlio::io::PointCloud2Msg cloud;
    decode_cloud(m, cloud);
    semlio::Scan scan;
    semlio::io::pointcloud2_to_scan(cloud, scan, cloud_config_, &layout_, nullptr);
    std::string fields;
    for (const semlio::io::PointField& f : cloud.fields) fields += (fields.empty() ? "" : " ") + f.name;
    facts_.decided.emplace_back("fields", fields);
    facts_.decided.emplace_back("ring_field", scan.has_rings() ? "yes" : "no (rings inferred)");
    facts_.decided.emplace_back("time_field", scan.has_times() ? "yes" : "no (times from azimuth when deskewing)");
    first_scan_ = std::move(scan);
  }

  static std::vector<semlio::SE3d> read_poses(const std::string& path) {
    // KITTI 3x4 (12 numbers a line) or TUM (8: stamp x y z qx qy qz qw).
    std::ifstream f(path);
    std::string line;
    while (std::getline(f, line) && line.find_first_not_of(" \t\r") == std::string::npos) {
    }
    std::size_t columns = 0;
    {
      std::istringstream ss(line);
      std::string tok;
      while (ss >> tok) ++columns;
    }
    if (columns == 8) {
      std::vector<semlio::SE3d> out;
      for (const semlio::io::StampedPose& p : semlio::io::read_tum_trajectory(path)) out.push_back(p.pose);
      return out;
    }
    return semlio::io::read_kitti_poses(path);
  }

 public:
  /// The first cloud as a scan (empty when the topic has no message).
  [[nodiscard]] const semlio::Scan& first_scan() const noexcept { return first_scan_; }

 private:
  std::string path_;
  Reader frames_;
  std::string gt_path_;
  std::optional<semlio::SE3d> Tr_;
  std::size_t lidar_ = 0;
  std::optional<std::size_t> imu_;
  semlio::io::BagMessage message_;
  semlio::io::PointCloud2Msg cloud_;
  semlio::io::PointCloud2Layout layout_;
  semlio::io::PointCloud2Config cloud_config_;
  semlio::Scan first_scan_;
  double header_after_start_s_ = 0.0;  // header stamp minus sweep start [s] (set_header_stamp)
};

/// The bag source for `format` (bag, mcap, db3).
inline std::unique_ptr<FrameSource> open_bag_source(const std::string& path, const std::string& format,
                                                    const std::string& lidar_topic, const std::string& imu_topic,
                                                    const std::string& gt, const std::string& calib) {
  if (format == "bag") {
    return std::make_unique<BagSource<semlio::io::RosBag1Reader>>(path, format, lidar_topic, imu_topic, gt, calib);
  }
  if (format == "mcap") {
    return std::make_unique<BagSource<semlio::io::McapReader>>(path, format, lidar_topic, imu_topic, gt, calib);
  }
  if (format == "db3") {
    return std::make_unique<BagSource<semlio::io::SqliteBagReader>>(path, format, lidar_topic, imu_topic, gt, calib);
  }
  throw semlio::ConfigError(path + ": unknown bag format " + format);
}

}  // namespace semlio_examples
