#pragma once
// Test helpers of the loop tests: LoopKeyframes from scans (LOAM features,
// a voxel-downsampled cloud for Scan Context) and yaw/translation helpers.

#include <Eigen/Core>

#include <cmath>
#include <vector>

#include <semlio/core/scan.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/loop/loop_keyframe.hpp>
#include <semlio/map/local_map.hpp>

namespace loop_test {

/// Rotation about z by yaw [rad] with translation t.
inline semlio::SE3d yaw_pose(double yaw, const Eigen::Vector3d& t = Eigen::Vector3d::Zero()) {
  return semlio::SE3d(semlio::SO3d::exp(Eigen::Vector3d(0.0, 0.0, yaw)), t);
}

/// A keyframe from a scan with rings (lidar frame) at pose T_world_lidar:
/// LOAM features and a 0.5 m voxel cloud.
inline semlio::LoopKeyframe make_keyframe(const semlio::Scan& scan, const semlio::SE3d& T_world_lidar, double stamp_s) {
  semlio::LoopKeyframe kf;
  kf.stamp_s = stamp_s;
  kf.T_world_lidar = T_world_lidar;
  semlio::LoamFeatureExtractor extractor;
  semlio::LoamFeatures f;
  extractor.extract(scan, f);
  kf.corners = std::move(f.corners);
  kf.surfaces = std::move(f.surfaces);
  semlio::detail::downsample_labelled(scan.points, scan.labels, 0.5, kf.cloud, kf.labels);
  return kf;
}

/// Translation distance and rotation angle between two poses.
inline std::pair<double, double> pose_error(const semlio::SE3d& a, const semlio::SE3d& b) {
  const semlio::SE3d d = a.inverse() * b;
  return {d.translation().norm(), d.so3().log().norm()};
}

}  // namespace loop_test
