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
/// (Robust::set_min_scale_m). Measured (scripts/accuracy_sim.sh; test "Preset
/// robust corners: on by default ..."): the ATE of both
/// presets halves on simulated drives with and without traffic, and the real
/// KITTI raw snippet's forward/backward runs agree better.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/core/error.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/features/sensor_profiles.hpp>
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
  SemanticWeightConfig semantic_weights{};     ///< full residual weights (eq. 10-12; default chance-corrected)
  PoseThresholdConfig pose_threshold{};        ///< baseline keyframes
  SemanticAdaptiveConfig semantic_keyframes{}; ///< full keyframes (eq. 14-22)
  SweepDeskewConfig deskew{};                  ///< motion correction (off: KITTI odometry; on: KITTI raw, distorted drives)
};

/// How the sensor is carried: bounds on its motion between frames, which set
/// the odometry's correction gates and prediction (OdometryConfig, "motion
/// profile"), and whether a vehicle box is cropped.
struct MotionProfile {
  std::string name = "vehicle";           ///< "vehicle" or "hand_held" (the YAML's platform)
  double max_speed_mps = 0.0;             ///< OdometryConfig::max_speed_mps (0: fixed gates)
  double max_angular_rate_radps = 0.0;    ///< OdometryConfig::max_angular_rate_radps (0: fixed gates)
  double prediction_rotation_scale = 1.0; ///< OdometryConfig::prediction_rotation_scale
  bool crop_ego_box = true;               ///< PreprocessConfig::crop_ego_box
  int min_solver_iterations = 0;          ///< GaussNewtonConfig::max_iterations at least this
  bool coarse_solve_first = false;        ///< OdometryConfig::coarse_solve_first
};

/// A car (KITTI): the fixed gates of OdometryConfig (2 m, 0.3 rad per frame
/// exceed what a car's prediction misses by at 10 Hz: 0.3 rad is a 3 rad/s
/// change of yaw rate), constant velocity, the vehicle box cropped. These
/// are the settings every KITTI result of the project was measured with.
inline MotionProfile vehicle_motion() { return MotionProfile{}; }

/// A sensor carried by hand (or on a helmet, a backpack, a legged robot):
/// up to 2 m/s and 2 rad/s (a brisk walk and a quick turn of the body), so
/// at 2 Hz frames the rotation gate opens to 2 rad; half the last rotation
/// extrapolated (OdometryConfig::prediction_rotation_scale); no vehicle box;
/// at least 50 Gauss-Newton iterations, since corrections of tens of degrees
/// take more than 30 (BALM OS0: one keyframe stopped 11 cm / 2 deg off at 30);
/// and for the same corrections a coarse solve with the nearest candidates
/// before Algorithm 1's (OdometryConfig::coarse_solve_first: the full
/// preset's ATE on the BALM OS0 keyframes, scripts/balm_os0.sh, was 0.66 m
/// without it, three keyframes 17-22 deg off where the prediction missed by
/// about 20 deg).
inline MotionProfile hand_held_motion() {
  return MotionProfile{.name = "hand_held",
                       .max_speed_mps = 2.0,
                       .max_angular_rate_radps = 2.0,
                       .prediction_rotation_scale = 0.5,
                       .crop_ego_box = false,
                       .min_solver_iterations = 50,
                       .coarse_solve_first = true};
}

/// The motion profile named `name` ("vehicle", "hand_held"); throws
/// ConfigError listing both for any other name.
inline MotionProfile motion_profile(std::string_view name) {
  if (name == "vehicle") return vehicle_motion();
  if (name == "hand_held") return hand_held_motion();
  throw ConfigError("unknown platform '" + std::string(name) + "'; known: vehicle, hand_held");
}

/// Pipeline settings for a sensor and the way it is carried, on top of
/// `base` (default: the presets' defaults). What follows the sensor profile:
/// the beam table (ring inference: the scans' own ring field when valid,
/// else point order when it yields the table's beam count, else nearest beam
/// by elevation), the range crop (the
/// profile's limits, capped by base's: min_range_m at least base's 1 m --
/// returns nearer than that are the vehicle or the operator -- and
/// max_range_m at most base's 100 m), the deskew's sweep period, spin and
/// start azimuth. What follows the motion profile: correction gates,
/// prediction, vehicle box, iterations. What does NOT scale (measured to work
/// from 2 m indoor to 80 m street ranges, so left at base's values): feature
/// thresholds (eq. 2 is range-normalised), voxel leaves, association gates,
/// keyframe thresholds, the KITTI vertical correction (a property of KITTI's
/// calibration, not of the sensor: the caller decides). The ground
/// segmenter's height is the profile's mount_height_m (GeometricSegmenterConfig,
/// which PipelineSettings does not hold: the caller sets it). Throws
/// ConfigError for an invalid profile.
inline PipelineSettings settings_for_sensor(const SensorProfile& sensor, const MotionProfile& motion = vehicle_motion(),
                                            PipelineSettings base = {}) {
  sensor.validate();
  OdometryConfig& o = base.odometry;
  o.sensor = sensor.beams;
  o.rings.method = RingMethod::kAuto;
  o.rings.prefer_scan_rings = true;  // a driver's ring field, when the scans carry one
  o.preprocess.min_range_m = std::max(sensor.min_range_m, o.preprocess.min_range_m);
  o.preprocess.max_range_m = std::min(sensor.max_range_m, o.preprocess.max_range_m);
  if (!(o.preprocess.max_range_m > o.preprocess.min_range_m)) o.preprocess.max_range_m = sensor.max_range_m;
  o.preprocess.crop_ego_box = motion.crop_ego_box;
  o.max_speed_mps = motion.max_speed_mps;
  o.max_angular_rate_radps = motion.max_angular_rate_radps;
  o.prediction_rotation_scale = motion.prediction_rotation_scale;
  o.solver.max_iterations = std::max(o.solver.max_iterations, motion.min_solver_iterations);
  o.coarse_solve_first = motion.coarse_solve_first;
  base.deskew.sweep_period_s = sensor.sweep_period_s();
  base.deskew.start_azimuth_rad = sensor.sweep_start_azimuth_rad;
  base.deskew.clockwise = !sensor.counter_clockwise;
  return base;
}

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
                  LoamResiduals{SemanticWeighted<PresetCornerResidual>(preset_corner_residual(s), s.semantic_weights),
                                SemanticWeighted<PointToPlane>(PointToPlane(s.plane), s.semantic_weights)},
                  SemanticAdaptive(s.semantic_keyframes), s.odometry, SweepDeskew(s.deskew));
}

}  // namespace semlio
