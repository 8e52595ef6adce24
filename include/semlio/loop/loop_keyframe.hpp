#pragma once
/// \file
/// What loop closure sees of the back end: one LoopKeyframe per keyframe
/// (lidar-frame features and cloud, current pose estimate) and what it hands
/// back: a verified LoopConstraint, a relative-pose measurement between two
/// keyframes that the pose graph turns into a between-factor.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include <semlio/core/labels.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// A keyframe as the back end stores it for loop closure (lidar-frame data; the
/// pose is the back end's current estimate, updated after each graph solve).
struct LoopKeyframe {
  double stamp_s = 0.0;                  ///< scan stamp [s]
  SE3d T_world_lidar;                    ///< current estimate of the keyframe pose
  FeatureSet corners;                    ///< corner features, lidar frame (features/loam_features.hpp)
  FeatureSet surfaces;                   ///< surface features, lidar frame
  std::vector<Eigen::Vector3f> cloud;    ///< the preprocessed scan, voxel-downsampled, lidar frame (Scan Context input)
  std::vector<Class> labels;             ///< labels of `cloud` (empty = unlabeled)
  /// True when a bounded store (Slam's, pipeline/slam.hpp) dropped this
  /// keyframe's features and cloud because a kept keyframe (a place) lies
  /// within the store's place spacing, or a thinning under the store's
  /// ceiling dropped it; stamp and pose remain (the radius detector still
  /// proposes it; Scan Context frees its descriptor). Verification then
  /// builds its submap from the kept keyframes around it.
  bool archived = false;
};

/// A verified loop closure: a relative-pose measurement between two keyframes.
struct LoopConstraint {
  std::size_t from = 0;                  ///< index of the older keyframe (the match)
  std::size_t to = 0;                    ///< index of the new keyframe (the query)
  SE3d T_from_to;                        ///< measured pose of `to` in the frame of `from`
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity(); ///< [rho; phi] order
  double fitness_m = 0.0;                ///< RMS point-to-plane/line residual of the inliers [m]
  double inlier_ratio = 0.0;             ///< matched features / features
};

}  // namespace semlio
