#pragma once
/// \file
/// The two front ends semlio_kitti offers, with every setting in one struct:
/// `baseline` = LIO-SAM-like (nearest 5, unweighted residuals, pose
/// thresholds); `full` = the paper (normal consistency, semantic weights,
/// semantic keyframes). Both carry a SweepDeskew (imu/deskew.hpp), off
/// unless PipelineSettings::deskew switches it on.
///
/// Robust corners (default; PipelineSettings::corner_cauchy_m = 0.1 m, 0
/// turns them off). The corner residual of both presets is Robust<Cauchy,
/// PointToLine>; at scale 0 the Cauchy weight is exactly 1 and the terms are
/// the plain least-squares point-to-line bit for bit (LIO-SAM itself is not
/// plain: it scales corner terms by 1 - 0.9 |d| and drops those below 0.1,
/// a cruder kernel of the same kind). Why on: a few corner matches
/// pair a feature with a line it does not lie on (horizontal ground lines
/// near the car, edges on adjacent rings matched to one near-horizontal map
/// line) and keep 0.3-0.9 m residuals at the right pose; squared, they pull
/// the motion short (real KITTI pair: 3.1 cm short of a plane ICP's 0.69 m;
/// 0.55 cm with a 0.1 m kernel). Down-weighted corners can push the forward
/// eigenvalue under LIO-SAM's absolute degeneracy threshold, and frozen there
/// the full preset lost track, so the presets damp degenerate directions
/// instead of freezing them (GaussNewtonConfig::damp_degenerate on; frames
/// reset to a measured prediction, the LIO's, stay frozen: GaussNewtonConfig). A robust
/// kernel wants a start near the answer: the first frame after the start has
/// no motion estimate, and in heavy traffic the full preset then ended 1 m
/// short for good; Odometry therefore solves that frame plain
/// (Robust::set_min_scale_m). Measured (README, Status): the ATE of both
/// presets halves on simulated drives with and without traffic, and the real
/// KITTI raw snippet's forward/backward runs agree better.

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/core/error.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/imu/deskew.hpp>
#include <semlio/keyframe/pose_threshold.hpp>
#include <semlio/keyframe/semantic_adaptive.hpp>
#include <semlio/pipeline/odometry.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/robust.hpp>
#include <semlio/residual/semantic_weighted.hpp>

namespace semlio {

/// The presets' pipeline settings: OdometryConfig's defaults, with
/// degenerate directions damped rather than frozen (file comment).
inline OdometryConfig preset_odometry_config() {
  OdometryConfig c;
  c.solver.damp_degenerate = true;
  return c;
}

/// Every setting of both presets (unused parts are ignored by a preset).
struct PipelineSettings {
  OdometryConfig odometry = preset_odometry_config(); ///< shared pipeline settings (degenerate directions damped)
  NearestKConfig nearest{};                    ///< baseline association
  NormalConsistencyConfig normal{};            ///< full association (Algorithm 1)
  PointToLineConfig line{};                    ///< corner residual
  double corner_cauchy_m = 0.1;                ///< Cauchy kernel scale on corner terms [m]; 0 = off, plain least squares (file comment)
  PointToPlaneConfig plane{};                  ///< surface residual
  PoseThresholdConfig pose_threshold{};        ///< baseline keyframes
  SemanticAdaptiveConfig semantic_keyframes{}; ///< full keyframes (eq. 14-22)
  SweepDeskewConfig deskew{};                  ///< motion correction (off: KITTI odometry; on: KITTI raw, distorted drives)
};

/// The corner residual of both presets: point-to-line under a Cauchy kernel
/// (weight exactly 1 while PipelineSettings::corner_cauchy_m is 0).
using PresetCornerResidual = Robust<Cauchy, PointToLine>;

/// The presets' corner residual from the settings; throws ConfigError on a
/// negative or non-finite corner_cauchy_m.
inline PresetCornerResidual preset_corner_residual(const PipelineSettings& s) {
  if (!(s.corner_cauchy_m >= 0.0) || !std::isfinite(s.corner_cauchy_m)) {
    throw ConfigError("PipelineSettings.corner_cauchy_m = " + std::to_string(s.corner_cauchy_m) +
                      ", expected a finite value >= 0 (0 = off)");
  }
  // An infinite scale makes the Cauchy weight 1 / (1 + s / inf) = 1 exactly.
  const double c = s.corner_cauchy_m > 0.0 ? s.corner_cauchy_m : std::numeric_limits<double>::infinity();
  return PresetCornerResidual(Cauchy{c}, PointToLine(s.line));
}

/// LIO-SAM-like odometry with the given segmenter (labels are carried along
/// but not used by the baseline's policies).
template <Segmenter S>
auto make_baseline_odometry(S segmenter, const PipelineSettings& s) {
  return Odometry(std::move(segmenter), NearestK(s.nearest),
                  LoamResiduals{preset_corner_residual(s), PointToPlane(s.plane)}, PoseThreshold(s.pose_threshold),
                  s.odometry, SweepDeskew(s.deskew));
}

/// The paper's odometry: Algorithm 1, eq. 10-12 weights, eq. 14-22 keyframes.
template <Segmenter S>
auto make_full_odometry(S segmenter, const PipelineSettings& s) {
  return Odometry(std::move(segmenter), NormalConsistency(s.normal),
                  LoamResiduals{SemanticWeighted<PresetCornerResidual>(preset_corner_residual(s)),
                                SemanticWeighted<PointToPlane>(PointToPlane(s.plane))},
                  SemanticAdaptive(s.semantic_keyframes), s.odometry, SweepDeskew(s.deskew));
}

}  // namespace semlio
