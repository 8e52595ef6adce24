#pragma once
/// \file
/// The two front ends semlio_kitti offers, with every setting in one struct:
/// `baseline` = LIO-SAM-like (nearest 5, unweighted residuals, pose
/// thresholds); `full` = the paper (normal consistency, semantic weights,
/// semantic keyframes). Both carry a SweepDeskew (imu/deskew.hpp), off
/// unless PipelineSettings::deskew switches it on.

#include <utility>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/imu/deskew.hpp>
#include <semlio/keyframe/pose_threshold.hpp>
#include <semlio/keyframe/semantic_adaptive.hpp>
#include <semlio/pipeline/odometry.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/semantic_weighted.hpp>

namespace semlio {

/// Every setting of both presets (unused parts are ignored by a preset).
struct PipelineSettings {
  OdometryConfig odometry{};                   ///< shared pipeline settings
  NearestKConfig nearest{};                    ///< baseline association
  NormalConsistencyConfig normal{};            ///< full association (Algorithm 1)
  PointToLineConfig line{};                    ///< corner residual
  PointToPlaneConfig plane{};                  ///< surface residual
  PoseThresholdConfig pose_threshold{};        ///< baseline keyframes
  SemanticAdaptiveConfig semantic_keyframes{}; ///< full keyframes (eq. 14-22)
  SweepDeskewConfig deskew{};                  ///< motion correction (off: KITTI odometry; on: KITTI raw, distorted drives)
};

/// LIO-SAM-like odometry with the given segmenter (labels are carried along
/// but not used by the baseline's policies).
template <Segmenter S>
auto make_baseline_odometry(S segmenter, const PipelineSettings& s) {
  return Odometry(std::move(segmenter), NearestK(s.nearest),
                  LoamResiduals{PointToLine(s.line), PointToPlane(s.plane)}, PoseThreshold(s.pose_threshold),
                  s.odometry, SweepDeskew(s.deskew));
}

/// The paper's odometry: Algorithm 1, eq. 10-12 weights, eq. 14-22 keyframes.
template <Segmenter S>
auto make_full_odometry(S segmenter, const PipelineSettings& s) {
  return Odometry(std::move(segmenter), NormalConsistency(s.normal),
                  LoamResiduals{SemanticWeighted<PointToLine>(PointToLine(s.line)),
                                SemanticWeighted<PointToPlane>(PointToPlane(s.plane))},
                  SemanticAdaptive(s.semantic_keyframes), s.odometry, SweepDeskew(s.deskew));
}

}  // namespace semlio
