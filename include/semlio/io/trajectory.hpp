#pragma once
/// \file
/// Trajectory files: KITTI odometry poses (3x4 row-major, one line per frame)
/// and TUM (`timestamp tx ty tz qx qy qz qw`), plus the camera <-> lidar frame
/// conversion of KITTI ground truth.
///
/// Frames: a KITTI pose P_i maps camera-0 coordinates of frame i into camera-0
/// coordinates of frame 0. With Tr = T_cam0_velo from calib.txt, the lidar pose
/// is T_i = Tr^-1 * P_i * Tr (lidar of frame i into lidar of frame 0), and
/// P_i = Tr * T_i * Tr^-1 goes back. TUM files written by semlio hold lidar
/// poses T_i.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/detail/pose_text.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::io {

/// Parses KITTI-format poses from text already in memory (`path` names it in
/// error messages): 12 numbers per line (row-major 3x4 [R|t]). Throws
/// FormatError (empty file, wrong field count,
/// non-numeric field, blank line between poses) and ValueError (NaN/Inf,
/// rotation off orthonormal by more than kRotationTolerance, reflection), all
/// naming path and line. Trailing blank lines are allowed.
inline std::vector<SE3d> parse_kitti_poses(std::string_view text, const std::string& path) {
  std::vector<SE3d> poses;
  detail::for_each_record(text, path, "poses", [&](long line, std::string_view, const auto& tok) {
    if (tok.size() != 12) {
      throw FormatError(
          detail::where(path, line, "pose line has " + std::to_string(tok.size()) + " fields, expected 12"));
    }
    double v[12];
    for (std::size_t i = 0; i < 12; ++i) v[i] = detail::parse_double(tok[i], path, line, i + 1, "pose");
    poses.push_back(detail::pose_from_3x4(v, path, line, "pose"));
  });
  if (poses.empty()) throw FormatError(detail::where(path, 0, "empty pose file (no poses)"));
  return poses;
}

/// Reads KITTI-format poses; see parse_kitti_poses for the rules and errors,
/// plus IoError when the file is missing or unreadable.
inline std::vector<SE3d> read_kitti_poses(const std::string& path) {
  return parse_kitti_poses(detail::read_file(path), path);
}

/// The text of KITTI-format poses: one 3x4 row-major line per pose, numbers as
/// the shortest text that reads back exactly.
inline std::string format_kitti_poses(const std::vector<SE3d>& poses) {
  std::string out;
  out.reserve(poses.size() * 200);
  for (const SE3d& T : poses) {
    detail::append_3x4(out, T);
    out.push_back('\n');
  }
  return out;
}

/// Writes KITTI-format poses (format_kitti_poses). Throws IoError.
inline void write_kitti_poses(const std::string& path, const std::vector<SE3d>& poses) {
  detail::write_file(path, format_kitti_poses(poses));
}

/// A pose with its timestamp.
struct StampedPose {
  double stamp_s = 0.0;  ///< time [s]
  SE3d pose;             ///< the pose (TUM files written by semlio: T_lidar0_lidar)
};

/// Largest accepted | |q| - 1 | of a TUM quaternion before normalising it.
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// Parses a TUM trajectory from text already in memory (`path` names it in
/// error messages): `timestamp tx ty tz qx qy qz qw` per line; lines
/// starting with '#' and blank lines are skipped. The quaternion is normalised
/// after checking | |q| - 1 | <= kQuaternionNormTolerance. Throws
/// FormatError (empty, wrong field count, non-numeric) and ValueError (NaN/Inf,
/// bad quaternion norm, timestamps going backwards), naming path and line.
inline std::vector<StampedPose> parse_tum_trajectory(std::string_view text, const std::string& path) {
  std::vector<StampedPose> out;
  std::vector<std::string_view> tok;
  detail::for_each_line(text, [&](long line, std::string_view s) {
    const std::string_view t = detail::trim(s);
    if (t.empty() || t.front() == '#') return;
    detail::split_ws(t, tok);
    if (tok.size() != 8) {
      throw FormatError(
          detail::where(path, line, "TUM line has " + std::to_string(tok.size()) + " fields, expected 8"));
    }
    double v[8];
    for (std::size_t i = 0; i < 8; ++i) {
      v[i] = detail::parse_double(tok[i], path, line, i + 1, "TUM");
      if (!std::isfinite(v[i])) {
        throw ValueError(detail::where(
            path, line, "TUM field " + std::to_string(i + 1) + " ('" + std::string(tok[i]) + "') is not finite"));
      }
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) <= kQuaternionNormTolerance)) {
      throw ValueError(detail::where(path, line,
                                     "TUM quaternion norm " + std::to_string(norm) + " is not 1 (tolerance " +
                                         std::to_string(kQuaternionNormTolerance) + ")"));
    }
    if (!out.empty() && v[0] < out.back().stamp_s) {
      throw ValueError(detail::where(path, line,
                                     "timestamp " + std::string(tok[0]) + " goes backwards (previous " +
                                         std::to_string(out.back().stamp_s) + ")"));
    }
    out.push_back({v[0], SE3d(q.normalized(), Eigen::Vector3d(v[1], v[2], v[3]))});
  });
  if (out.empty()) throw FormatError(detail::where(path, 0, "empty TUM trajectory (no poses)"));
  return out;
}

/// Reads a TUM trajectory; see parse_tum_trajectory for the rules and errors,
/// plus IoError when the file is missing or unreadable.
inline std::vector<StampedPose> read_tum_trajectory(const std::string& path) {
  return parse_tum_trajectory(detail::read_file(path), path);
}

/// The text of a TUM trajectory (`timestamp tx ty tz qx qy qz qw`, qw >= 0),
/// numbers as the shortest text that reads back exactly.
inline std::string format_tum_trajectory(const std::vector<StampedPose>& poses) {
  std::string out;
  out.reserve(poses.size() * 160);
  for (const StampedPose& p : poses) {
    Eigen::Quaterniond q = p.pose.so3().quaternion();
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // one canonical sign
    const Eigen::Vector3d t = p.pose.translation();
    const double v[8] = {p.stamp_s, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
    for (std::size_t i = 0; i < 8; ++i) {
      if (i != 0) out.push_back(' ');
      detail::append_double(out, v[i]);
    }
    out.push_back('\n');
  }
  return out;
}

/// Writes a TUM trajectory (format_tum_trajectory). Throws IoError.
inline void write_tum_trajectory(const std::string& path, const std::vector<StampedPose>& poses) {
  detail::write_file(path, format_tum_trajectory(poses));
}

/// True when the first non-blank, non-comment line of `text` has 8 fields
/// (TUM); false for 12 (KITTI) or anything else.
inline bool looks_like_tum_text(std::string_view text) {
  bool decided = false;
  bool tum = false;
  detail::for_each_line(text, [&](long, std::string_view s) {
    if (decided) return;
    const std::string_view t = detail::trim(s);
    if (t.empty() || t.front() == '#') return;
    decided = true;
    tum = detail::split_ws(t).size() == 8;
  });
  return tum;
}

/// looks_like_tum_text() of the file at `path`. Throws IoError when the file is missing.
inline bool looks_like_tum(const std::string& path) { return looks_like_tum_text(detail::read_file(path)); }

/// KITTI camera-0 poses P_i into lidar poses T_i = Tr^-1 * P_i * Tr, with
/// Tr = T_cam0_velo (calib.txt `Tr`).
inline std::vector<SE3d> camera_to_lidar(const std::vector<SE3d>& P_cam, const SE3d& Tr) {
  const SE3d Tr_inv = Tr.inverse();
  std::vector<SE3d> out;
  out.reserve(P_cam.size());
  for (const SE3d& P : P_cam) out.push_back(Tr_inv * P * Tr);
  return out;
}

/// Lidar poses T_i into KITTI camera-0 poses P_i = Tr * T_i * Tr^-1, with
/// Tr = T_cam0_velo; the result can be scored by the official devkit.
inline std::vector<SE3d> lidar_to_camera(const std::vector<SE3d>& T_lidar, const SE3d& Tr) {
  const SE3d Tr_inv = Tr.inverse();
  std::vector<SE3d> out;
  out.reserve(T_lidar.size());
  for (const SE3d& T : T_lidar) out.push_back(Tr * T * Tr_inv);
  return out;
}

}  // namespace semlio::io
