#pragma once
// One fuzz harness body per reader: int fuzz_<reader>(const uint8_t*, size_t).
// Each feeds the bytes to the reader; a semlio::Error is the expected outcome
// of bad input (return 0), anything else escaping is a finding (libFuzzer
// reports the uncaught exception; the replay test fails). After a successful
// read the documented invariants are checked -- finite values, orthonormal
// rotations, consistent sizes, non-decreasing times -- and a violation traps.
// Where a writer exists, the result is written and read back and must match.
//
// The YAML settings harness lives in harness_settings_yaml.hpp (it needs
// yaml-cpp, a dependency of the examples only); the scan-folder and KITTI raw
// drive logic harnesses in harnesses_folders.hpp.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/g2o_graph.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/kitti_raw.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/ros1_msgs.hpp>
#include <semlio/io/trajectory.hpp>

#include "fuzz_support.hpp"
#include "harnesses_folders.hpp"

namespace semlio_fuzz {

/// Rotation of a pose read from a file: orthonormal within 1e-6, det +1.
inline void check_rotation(const Eigen::Matrix3d& R) {
  check(R.allFinite());
  check((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6);
  check(R.determinant() > 0.0);
}

/// A pose read from a file: finite translation and a proper rotation.
inline void check_pose(const semlio::SE3d& T) {
  check(T.translation().allFinite());
  check_rotation(T.so3().matrix());
}

/// Every documented property of a scan a reader returns.
inline void check_scan(const semlio::Scan& s) {
  try {
    s.validate();
  } catch (const semlio::Error&) {
    check(false);  // the reader returned fields of different lengths
  }
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto& p = s.points[i];
    check(std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()));
    check(!(p.x() == 0.0F && p.y() == 0.0F && p.z() == 0.0F));  // (0,0,0) is dropped
    if (s.has_intensity()) check(std::isfinite(s.intensity[i]));
    if (s.has_times()) check(std::isfinite(s.times_s[i]));
  }
}

/// Two scans equal field by field, bit for bit.
inline bool same_scan(const semlio::Scan& a, const semlio::Scan& b) {
  if (a.size() != b.size() || a.intensity.size() != b.intensity.size() || a.labels.size() != b.labels.size() ||
      a.instances.size() != b.instances.size() || a.rings.size() != b.rings.size() ||
      a.times_s.size() != b.times_s.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::memcmp(a.points[i].data(), b.points[i].data(), 3 * sizeof(float)) != 0) return false;
  }
  const auto bytes_equal = [](const auto& x, const auto& y) {
    return x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  return bytes_equal(a.intensity, b.intensity) && a.labels == b.labels && a.instances == b.instances &&
         a.rings == b.rings && bytes_equal(a.times_s, b.times_s);
}

/// Writes with `write`, reads back with `read`: must give the same scan.
template <typename Write, typename Read>
void check_round_trip(const semlio::Scan& s, Write write, Read read) {
  try {
    check(same_scan(s, read(write(s))));
  } catch (const semlio::Error&) {
    check(false);  // what the reader returned, the writer must accept and the reader re-read
  }
}

/// KITTI velodyne `.bin`: parse_kitti_bin, then .bin round trip in memory.
inline int fuzz_kitti_bin(const std::uint8_t* data, std::size_t size) {
  semlio::Scan s;
  semlio::io::ReadStats stats;
  try {
    s = semlio::io::parse_kitti_bin(as_text(data, size), "in.bin", &stats);
  } catch (const semlio::Error&) {
    return 0;
  }
  check_scan(s);
  check(s.has_intensity() || s.empty());
  check(s.size() + stats.dropped_nonfinite + stats.dropped_zero == size / 16);
  if (!s.empty()) {
    check_round_trip(s, [](const semlio::Scan& x) { return semlio::io::format_kitti_bin(x); },
                     [](const std::string& bytes) { return semlio::io::parse_kitti_bin(bytes, "rt.bin"); });
  }
  return 0;
}

/// KITTI `.label` with a `.bin` of as many points: parse_kitti_scan keeps the
/// labels aligned with the kept points; the label bytes round-trip.
inline int fuzz_kitti_label(const std::uint8_t* data, std::size_t size) {
  const std::string_view label = as_text(data, size);
  std::vector<std::uint32_t> raw;
  try {
    raw = semlio::io::parse_label_file(label, "in.label", size / 4);
  } catch (const semlio::Error&) {
    return 0;
  }
  check(raw.size() == size / 4 && size % 4 == 0);
  // A wrong expected count is always a ValueError.
  try {
    (void)semlio::io::parse_label_file(label, "in.label", raw.size() + 1);
    check(false);
  } catch (const semlio::ValueError&) {
  }
  const std::size_t n = raw.size();
  check(semlio::io::format_label_file(raw) == label);
  if (n == 0) return 0;
  // A .bin of as many points, every third point at (0,0,0) so that some
  // labels are dropped.
  std::string bin(n * 16, '\0');
  for (std::size_t i = 0; i < n; ++i) {
    const float c = i % 3 == 0 ? 0.0F : 1.0F;
    const float v[4] = {c * (1.0F + static_cast<float>(i)), 2.0F * c, 3.0F * c, 0.5F};
    std::memcpy(bin.data() + 16 * i, v, sizeof(v));
  }
  semlio::Scan s;
  try {
    s = semlio::io::parse_kitti_scan(bin, "in_label.bin", label, "in.label");
  } catch (const semlio::Error&) {
    check(false);  // a well-formed pair must read
  }
  check_scan(s);
  check(s.labels.size() == s.size() && s.instances.size() == s.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 3 == 0) continue;  // dropped with its label
    check(s.labels[k] == semlio::learning_class(raw[i]));
    check(s.instances[k] == static_cast<std::uint16_t>(raw[i] >> 16));
    ++k;
  }
  check(k == s.size());
  return 0;
}

/// KITTI calib.txt: transforms proper, entries finite; formatted and re-parsed
/// with the same entries.
inline int fuzz_kitti_calib(const std::uint8_t* data, std::size_t size) {
  semlio::io::Calibration c;
  try {
    c = semlio::io::parse_kitti_calib(as_text(data, size), "calib.txt");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(!c.entries.empty());
  for (const auto& [name, values] : c.entries) {
    check(!name.empty() && !values.empty());
    for (const double v : values) check(std::isfinite(v));
  }
  if (c.T_cam0_velo) check_pose(*c.T_cam0_velo);
  if (c.T_imu_velo) check_pose(*c.T_imu_velo);
  check(c.T_cam0_velo.has_value() == (c.entries.count("Tr") == 1));
  try {
    const semlio::io::Calibration back =
        semlio::io::parse_kitti_calib(semlio::io::format_kitti_calib(c), "rt_calib.txt");
    check(back.entries.size() == c.entries.size());
    for (const auto& [name, values] : c.entries) {
      const auto it = back.entries.find(name);
      check(it != back.entries.end());
      // Tr / Tr_imu_velo are rewritten from the (re-orthonormalised) transform.
      if (name != "Tr" && name != "Tr_imu_velo") check(it->second == values);
    }
  } catch (const semlio::Error&) {
    check(false);
  }
  return 0;
}

/// KITTI times.txt: finite, non-decreasing; exact round trip.
inline int fuzz_kitti_times(const std::uint8_t* data, std::size_t size) {
  std::vector<double> t;
  try {
    t = semlio::io::parse_kitti_times(as_text(data, size), "times.txt");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(!t.empty());
  for (std::size_t i = 0; i < t.size(); ++i) {
    check(std::isfinite(t[i]));
    if (i > 0) check(t[i] >= t[i - 1]);
  }
  try {
    check(semlio::io::parse_kitti_times(semlio::io::format_kitti_times(t), "rt_times.txt") == t);
  } catch (const semlio::Error&) {
    check(false);
  }
  return 0;
}

/// KITTI poses: proper rotations, finite translations; round trip keeps the
/// count and the translations exactly.
inline int fuzz_kitti_poses(const std::uint8_t* data, std::size_t size) {
  std::vector<semlio::SE3d> poses;
  try {
    poses = semlio::io::parse_kitti_poses(as_text(data, size), "poses.txt");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(!poses.empty());
  for (const auto& T : poses) check_pose(T);
  try {
    const std::vector<semlio::SE3d> back =
        semlio::io::parse_kitti_poses(semlio::io::format_kitti_poses(poses), "rt_poses.txt");
    check(back.size() == poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) check(back[i].translation() == poses[i].translation());
  } catch (const semlio::Error&) {
    check(false);
  }
  return 0;
}

/// TUM trajectory: finite, unit quaternions, non-decreasing stamps; round
/// trip keeps stamps and translations exactly.
inline int fuzz_tum(const std::uint8_t* data, std::size_t size) {
  std::vector<semlio::io::StampedPose> poses;
  try {
    poses = semlio::io::parse_tum_trajectory(as_text(data, size), "traj.tum");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(!poses.empty());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    check(std::isfinite(poses[i].stamp_s));
    if (i > 0) check(poses[i].stamp_s >= poses[i - 1].stamp_s);
    check_pose(poses[i].pose);
  }
  try {
    const auto back = semlio::io::parse_tum_trajectory(semlio::io::format_tum_trajectory(poses), "rt.tum");
    check(back.size() == poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) {
      check(back[i].stamp_s == poses[i].stamp_s);
      check(back[i].pose.translation() == poses[i].pose.translation());
    }
  } catch (const semlio::Error&) {
    check(false);
  }
  return 0;
}

/// PCD (ascii or binary): scan invariants; binary and ascii round trips.
inline int fuzz_pcd(const std::uint8_t* data, std::size_t size) {
  semlio::Scan s;
  try {
    s = semlio::io::parse_pcd(as_text(data, size), "in.pcd");
  } catch (const semlio::Error&) {
    return 0;
  }
  check_scan(s);
  for (const auto enc : {semlio::io::PcdEncoding::kBinary, semlio::io::PcdEncoding::kAscii}) {
    check_round_trip(s, [&](const semlio::Scan& x) { return semlio::io::format_pcd(x, enc); },
                     [](const std::string& bytes) { return semlio::io::parse_pcd(bytes, "rt.pcd"); });
  }
  return 0;
}

/// PLY (ascii or binary, either byte order): scan invariants; round trips
/// (labels travel as raw ids, so they compare as learning classes).
inline int fuzz_ply(const std::uint8_t* data, std::size_t size) {
  semlio::Scan s;
  try {
    s = semlio::io::parse_ply(as_text(data, size), "in.ply");
  } catch (const semlio::Error&) {
    return 0;
  }
  check_scan(s);
  for (const auto enc : {semlio::io::PlyEncoding::kBinaryLittleEndian, semlio::io::PlyEncoding::kBinaryBigEndian,
                         semlio::io::PlyEncoding::kAscii}) {
    check_round_trip(s, [&](const semlio::Scan& x) { return semlio::io::format_ply(x, enc); },
                     [](const std::string& bytes) { return semlio::io::parse_ply(bytes, "rt.ply"); });
  }
  return 0;
}

/// KITTI raw OXTS directory, in memory. The input is split at '|' bytes: the
/// first part is timestamps.txt, each further part one data/NNNNNNNNNN.txt.
/// Invariants: finite fields, non-decreasing stamps; the formatted directory
/// (stamps inside the 1970-9999 range the writer allows) parses back with
/// the same fields and stamps within the 1 ns text resolution.
inline int fuzz_oxts(const std::uint8_t* data, std::size_t size) {
  const std::string_view text = as_text(data, size);
  std::string_view stamps;
  std::vector<std::string_view> files;
  std::size_t start = 0;
  for (std::size_t part = 0;; ++part) {
    const std::size_t bar = text.find('|', start);
    const std::string_view piece = text.substr(start, bar == std::string_view::npos ? std::string_view::npos : bar - start);
    (part == 0 ? stamps : files.emplace_back()) = piece;
    if (bar == std::string_view::npos) break;
    start = bar + 1;
  }
  std::vector<semlio::io::OxtsRecord> recs;
  try {
    recs = semlio::io::parse_oxts(stamps, files, "oxts");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(!recs.empty() && recs.size() == files.size());
  bool writable = true;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const auto& r = recs[i];
    check(std::isfinite(r.stamp_s));
    if (i > 0) check(r.stamp_s >= recs[i - 1].stamp_s);
    check(std::isfinite(r.lat_deg) && std::isfinite(r.lon_deg) && std::isfinite(r.alt_m));
    check(r.velocity_flu_mps.allFinite() && r.accel_body_mps2.allFinite() && r.gyro_body_radps.allFinite());
    writable = writable && r.stamp_s >= 0.0 && r.stamp_s < 253402300800.0;
  }
  (void)semlio::io::imu_samples(recs);
  if (!writable) return 0;
  try {
    const std::string out_stamps = semlio::io::format_oxts_timestamps(recs);
    std::vector<std::string> lines(recs.size());
    for (std::size_t i = 0; i < recs.size(); ++i) semlio::io::append_oxts_line(lines[i], recs[i]);
    const std::vector<std::string_view> views(lines.begin(), lines.end());
    const auto back = semlio::io::parse_oxts(out_stamps, views, "oxts_rt");
    check(back.size() == recs.size());
    for (std::size_t i = 0; i < recs.size(); ++i) {
      check(std::abs(back[i].stamp_s - recs[i].stamp_s) <= 1e-9 + 1e-15 * std::abs(recs[i].stamp_s));
      check(back[i].lat_deg == recs[i].lat_deg && back[i].yaw_rad == recs[i].yaw_rad);
      check(back[i].gyro_body_radps == recs[i].gyro_body_radps && back[i].orimode == recs[i].orimode);
    }
  } catch (const semlio::Error&) {
    check(false);
  }
  return 0;
}

/// KITTI raw calibration (calib_velo_to_cam.txt, calib_imu_to_velo.txt): a
/// proper rigid transform.
inline int fuzz_kitti_raw_calib(const std::uint8_t* data, std::size_t size) {
  semlio::SE3d T;
  try {
    T = semlio::io::parse_kitti_raw_calib(as_text(data, size), "calib_velo_to_cam.txt");
  } catch (const semlio::Error&) {
    return 0;
  }
  check_pose(T);
  return 0;
}

/// KITTI raw timestamps file (velodyne_points/timestamps*.txt): one entry
/// per line, the present stamps finite and non-decreasing; the median
/// period of consecutive stamps (what KittiRawDrive derives) finite, >= 0.
inline int fuzz_kitti_raw_stamps(const std::uint8_t* data, std::size_t size) {
  std::vector<std::optional<double>> lines;
  try {
    lines = semlio::io::detail::parse_raw_stamp_lines(as_text(data, size), "timestamps.txt");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(!lines.empty());
  std::optional<double> last;
  for (const auto& t : lines) {
    if (!t) continue;
    check(std::isfinite(*t));
    if (last) check(*t >= *last);
    last = t;
  }
  if (const auto p = semlio::io::detail::median_period(lines)) check(std::isfinite(*p) && *p >= 0.0);
  return 0;
}

/// Information matrix after the reader: finite, symmetric, PSD.
template <int N>
void check_information(const Eigen::Matrix<double, N, N>& M) {
  check(M.allFinite());
  check((M - M.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * std::max(1.0, M.cwiseAbs().maxCoeff()));
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(0.5 * (M + M.transpose()));
  check(es.eigenvalues().minCoeff() >= -1e-9 * std::max(1.0, es.eigenvalues().cwiseAbs().maxCoeff()));
}

/// g2o pose graph: finite poses, unit rotations, PSD information, edges to
/// known vertices (a pose graph builds from it); round trip keeps the counts.
inline int fuzz_g2o(const std::uint8_t* data, std::size_t size) {
  semlio::io::G2oGraph g;
  try {
    g = semlio::io::parse_g2o(as_text(data, size), "in.g2o");
  } catch (const semlio::Error&) {
    return 0;
  }
  check(g.dimension == 0 || g.dimension == 2 || g.dimension == 3);
  for (const auto& v : g.vertices3) check_pose(v.pose);
  for (const auto& e : g.edges3) {
    check_pose(e.measured);
    check_information<6>(e.information);
  }
  for (const auto& v : g.vertices2) {
    check(v.pose.translation().allFinite() && std::isfinite(v.pose.theta()));
  }
  for (const auto& e : g.edges2) {
    check(e.measured.translation().allFinite() && std::isfinite(e.measured.theta()));
    check_information<3>(e.information);
  }
  try {
    if (g.dimension == 3) (void)semlio::io::make_pose_graph3(g);
    if (g.dimension == 2) (void)semlio::io::make_pose_graph2(g);
  } catch (const semlio::Error&) {
    // A self-loop edge or similar: refused with a typed error is fine.
  }
  try {
    const semlio::io::G2oGraph back = semlio::io::parse_g2o(semlio::io::format_g2o(g), "rt.g2o");
    check(back.vertices3.size() == g.vertices3.size() && back.edges3.size() == g.edges3.size());
    check(back.vertices2.size() == g.vertices2.size() && back.edges2.size() == g.edges2.size());
    check(back.fixed == g.fixed);
  } catch (const semlio::Error&) {
    check(false);
  }
  return 0;
}

/// A decoded PointCloud2: scan invariants, the layout's counts agree with the
/// scan and the stats, per-point times relative to the earliest (>= 0).
inline void check_cloud(const semlio::Scan& s, const semlio::io::PointCloud2Layout& layout,
                        const semlio::io::ReadStats& stats) {
  check_scan(s);
  check(layout.points_out == s.size());
  check(layout.points_in == s.size() + stats.dropped());
  check(std::isfinite(s.stamp_s));
  for (const float t : s.times_s) check(t >= 0.0F);
  check(s.has_times() == !layout.time_field.empty() || s.empty());
}

/// Decodes a deserialised PointCloud2 (any bad layout is a FormatError).
inline void fuzz_decode_cloud(const semlio::io::PointCloud2Msg& msg) {
  semlio::Scan s;
  semlio::io::PointCloud2Layout layout;
  semlio::io::ReadStats stats;
  try {
    semlio::io::pointcloud2_to_scan(msg, s, {}, &layout, &stats);
  } catch (const semlio::Error&) {
    return;
  }
  check_cloud(s, layout, stats);
}

/// sensor_msgs/PointCloud2 in ROS 1 serialisation: deserialise, decode; the
/// one-step ros1_pointcloud2_to_scan gives the same scan (or also throws).
inline int fuzz_ros1_pointcloud2(const std::uint8_t* data, std::size_t size) {
  semlio::io::PointCloud2Msg msg;
  try {
    semlio::io::parse_ros1_pointcloud2(data, size, msg);
  } catch (const semlio::Error&) {
    return 0;
  }
  check(msg.data.size() <= size);
  semlio::Scan a;
  semlio::io::PointCloud2Layout layout;
  semlio::io::ReadStats stats;
  bool two_steps_ok = true;
  try {
    semlio::io::pointcloud2_to_scan(msg, a, {}, &layout, &stats);
  } catch (const semlio::Error&) {
    two_steps_ok = false;
  }
  semlio::Scan b;
  bool one_step_ok = true;
  try {
    semlio::io::ros1_pointcloud2_to_scan(data, size, b);
  } catch (const semlio::Error&) {
    one_step_ok = false;
  }
  check(one_step_ok == two_steps_ok);
  if (!two_steps_ok) return 0;
  check_cloud(a, layout, stats);
  check(same_scan(a, b) && a.stamp_s == b.stamp_s);
  return 0;
}

/// sensor_msgs/PointCloud2 in CDR (ROS 2, with the encapsulation header):
/// deserialise, decode.
inline int fuzz_cdr_pointcloud2(const std::uint8_t* data, std::size_t size) {
  semlio::io::PointCloud2Msg msg;
  try {
    semlio::io::parse_cdr_pointcloud2(data, size, msg);
  } catch (const semlio::Error&) {
    return 0;
  }
  check(msg.data.size() <= size);
  fuzz_decode_cloud(msg);
  return 0;
}

/// sensor_msgs/Imu in ROS 1 serialisation: deserialise (typed error or a
/// message with a finite stamp).
inline int fuzz_ros1_imu(const std::uint8_t* data, std::size_t size) {
  semlio::io::ImuMsg msg;
  try {
    semlio::io::parse_ros1_imu(data, size, msg);
  } catch (const semlio::Error&) {
    return 0;
  }
  check(std::isfinite(msg.stamp_s));
  check(msg.frame_id.size() <= size);
  return 0;
}

/// sensor_msgs/Imu in CDR: deserialise (typed error or a finite stamp).
inline int fuzz_cdr_imu(const std::uint8_t* data, std::size_t size) {
  semlio::io::ImuMsg msg;
  try {
    semlio::io::parse_cdr_imu(data, size, msg);
  } catch (const semlio::Error&) {
    return 0;
  }
  check(std::isfinite(msg.stamp_s));
  check(msg.frame_id.size() <= size);
  return 0;
}

/// A harness: its name (the corpus folder) and body.
struct Harness {
  const char* name;
  int (*body)(const std::uint8_t*, std::size_t);
};

/// Every harness of this header (the YAML one is added where yaml-cpp is linked).
inline constexpr Harness kHarnesses[] = {
    {"kitti_bin", fuzz_kitti_bin}, {"kitti_label", fuzz_kitti_label}, {"kitti_calib", fuzz_kitti_calib},
    {"kitti_times", fuzz_kitti_times}, {"kitti_poses", fuzz_kitti_poses}, {"tum", fuzz_tum},
    {"pcd", fuzz_pcd}, {"ply", fuzz_ply}, {"oxts", fuzz_oxts}, {"g2o", fuzz_g2o},
    {"ros1_pointcloud2", fuzz_ros1_pointcloud2}, {"cdr_pointcloud2", fuzz_cdr_pointcloud2},
    {"ros1_imu", fuzz_ros1_imu}, {"cdr_imu", fuzz_cdr_imu},
    {"kitti_raw_calib", fuzz_kitti_raw_calib}, {"kitti_raw_stamps", fuzz_kitti_raw_stamps},
    {"scan_folder", fuzz_scan_folder}, {"kitti_raw_drive", fuzz_kitti_raw_drive},
};

}  // namespace semlio_fuzz
