#pragma once
/// \file
/// Slam<Odometry, Detector>: the paper's back end (§3 steps 4-5, METHOD.md
/// step 9, without IMU) around any odometry front end: per scan the front end
/// runs unchanged; on its keyframes the back end adds a pose-graph node with
/// an odometry between-factor, stores a compact LoopKeyframe, asks the loop
/// closer for a verified loop and, when one is found, adds it as a loop factor
/// and re-solves the graph (a warm-started full solve; graph/pose_graph.hpp).
///
/// Frames. The front end keeps working in its own drifting "odometry" frame
/// (its local map is never rewritten). The back end's "world" frame is the
/// graph's: node 0 (the first keyframe) is fixed at its odometry pose, so
/// both frames coincide until the first loop. The pose of a frame is the
/// optimised pose of its preceding keyframe composed with the odometry motion
/// since that keyframe: T_world_frame = T_world_kf * (T_odom_kf^-1 T_odom_frame).
/// trajectory() re-evaluates this for every frame with the latest graph, so it
/// is the optimised trajectory; without loops it equals the odometry.
///
/// Odometry information (why this scaling). The front end's Gauss-Newton
/// Hessian H = J^T W J of its sum of squared (semantically weighted, robustly
/// reweighted) point-to-line/plane residuals, at its final pose, is the
/// inverse covariance of the right perturbation of T_map_lidar for unit
/// residual variance ([rho; phi] order, as the graph). Near the optimum the
/// between error's Jacobian with respect to that perturbation of the new node
/// is the identity, so Omega = s * H with s = 1 / sigma_r^2 is the information
/// of the between factor (the registration measures the new keyframe relative
/// to the local map, which the previous keyframe anchors). The default s = 1
/// (sigma_r = 1 m) is deliberately conservative: the residuals are correlated
/// (neighbouring points share a plane), so H over-counts evidence; and it is
/// the same scale the loop verifier uses for loop factors
/// (LoopVerifierConfig::hessian_scale = 1), so odometry and loops are weighed
/// consistently. Eigenvalues are clamped to [min_information, max_information]:
/// a degenerate direction (tunnel, open field) then gets a weak but positive
/// information instead of a singular graph. When a frame since the previous
/// keyframe failed (too few features, solver failure, rejected jump) the
/// motion partly came from the constant-velocity prediction, and the factor
/// gets the weak default diag(1/sigma_t^2, 1/sigma_r^2) (1 m, 0.1 rad).
///
/// Memory (a configurable ceiling). Per keyframe the back end keeps a
/// LoopKeyframe: the LOAM features (corners and voxelised surfaces, 13 bytes
/// each: position + label; the per-point scan indices are dropped) when loops
/// are on, and the preprocessed scan voxel-downsampled at
/// keyframe_cloud_leaf_m (0.5 m default; 13 bytes per point): ~0.2-0.25 MB
/// per keyframe (keyframe_bytes() reports the whole store; semlio_kitti
/// writes it to report.json). Kept like that for every keyframe this would
/// grow linearly with the drive, so the store is bounded in three steps:
/// - the newest max_keyframe_clouds keyframes (default 100, ~10 s of a car's
///   drive at LIO-SAM's 1 m keyframe spacing) keep everything;
/// - an older keyframe is "retired": it stays a "place" (features and cloud
///   kept) only when no place lies within the place spacing (initially
///   place_spacing_m, default 2 m, LIO-SAM's surroundingKeyframeDensity) of
///   its current position estimate; otherwise its features and cloud are
///   freed (LoopKeyframe::archived) and only the stamp, the pose (graph node)
///   and the detector's descriptor remain (Scan Context caches its descriptor
///   before retirement: only keyframes the detector has seen are retired);
/// - the places' data has a ceiling, max_place_bytes (default 128 MiB, ~550
///   places of a 64-beam scanner): when a new place takes it over, the place
///   spacing grows by place_thinning_factor (1.5) and the places are thinned
///   to it (greedy, newest first: a place stays when no place already kept
///   lies within the new spacing; the others are archived), repeated until
///   the places fit. New places then also use the grown spacing. So the
///   explored area stays covered, ever more sparsely, and a revisit of any
///   old street still finds places within its loop search radius (loop
///   verification builds its submap from the kept keyframes around an
///   archived candidate, loop/loop_verifier.hpp detail::select_submap). A
///   ceiling below one place's data keeps no places (loops then only close
///   within the recent window). max_place_bytes = 0: no ceiling (the store
///   then grows with the distinct road driven, ~0.1 MB per new metre).
/// Places keep the keyframe frame and the graph pose, so later loop
/// closures still move them (a world-frame voxel archive would go stale at
/// every loop correction). The semantic map is built, as LIO-SAM's global
/// map, from the kept keyframes (places + recent) at their optimised poses,
/// so it is bounded by the same ceiling (SemanticMap: one point per occupied
/// voxel, the kept clouds overlap heavily). max_keyframe_clouds = 0 keeps
/// every keyframe in full (no retirement, no ceiling).
/// What still grows with the drive is bookkeeping: per keyframe the record
/// (~0.3 kB), a graph node and two factors (~1 kB); per frame an index and
/// two poses (~120 bytes): about 1.2 MB per km at 10 Hz and a keyframe per
/// metre and a quarter. The front end's LocalMap (map/local_map.hpp) has
/// its own ceiling, LocalMapConfig::max_keyframes (~0.1 MB per keyframe;
/// before it, the process's live heap grew ~65 MB per 1000 simulated frames
/// while this store stayed under its ceiling).
///
/// Cost per frame: the odometry plus, on keyframes, a voxel downsample, the
/// loop detector (linear in keyframes, microseconds), the retirement of one
/// keyframe (linear in places, microseconds; a thinning, quadratic in the
/// places, is rare: each one multiplies the spacing) and a window graph update
/// (PoseGraphConfig::window_size newest nodes and their factors, constant). A loop closure costs a verification and a full graph
/// solve; those frames are flagged in the report (loop_checked/loop_closed).
///
/// Lidar-inertial back end. With a front end that also reports inertial
/// states (InertialSlamFrontEnd, e.g. LidarInertialFrontEnd of
/// pipeline/lidar_inertial.hpp) the graph is a KeyframeInertialGraph
/// (graph/keyframe_inertial_graph.hpp): each keyframe node carries the IMU's
/// pose, velocity and bias (initial values from the front end's state,
/// rotated into the world frame), consecutive keyframes get the lidar between
/// factor (the same information as above) and a preintegrated IMU factor over
/// their interval (from the samples the front end consumed), and loops enter
/// as above. Where the front end has no inertial state (while it
/// initialises, on IMU fallback frames) or the IMU does not cover the
/// interval (gaps), the keyframe gets no IMU factor but a prior on its
/// velocity and bias (config.inertial_*_sigma), so the graph stays
/// well-posed; the first keyframe's prior also holds its pose (the gauge:
/// all 6 DoF until the first IMU factor, then position and yaw, see
/// Gravity). The lidar-only Slam is unchanged.
///
/// Gravity. Every IMU factor gets the map's gravity as the front end
/// estimated it (LidarInertialOdometry: at initialisation, never refined), a
/// constant of the graph's world frame. It is not rotated by the keyframe's
/// world-odometry correction as the velocity is: that would let the graph's
/// attitude errors tilt the gravity of later factors (600-frame drive, full
/// IMU weight, graph given the true gravity: median IMU chi2 at the ground
/// truth 7430 rotated, 8.4 constant = the true preintegration's;
/// tests/imu/test_lio_slam.cpp). The graph estimates the gravity DIRECTION
/// (inertial_gravity_gauge, default on): once the first IMU factor is in,
/// the first keyframe's prior holds only its position and its rotation about
/// gravity (gravity_gauge_information(), the standard 4-DoF inertial gauge),
/// so the IMU factors turn the whole trajectory about horizontal axes until
/// the map's gravity vector is the true gravity in it. The world frame is
/// then the map frame so corrected about the first keyframe (by the front
/// end's tilt error, mrad; odometry_trajectory() stays in the map frame).
/// Before the first IMU factor nothing observes roll and pitch, hence the
/// 6-DoF prior until then (relaxing it earlier makes the graph singular).
/// Window updates hold the older keyframes and cannot turn the trajectory,
/// so the direction is estimated by the full solves: over the first
/// window_size keyframes and after each loop. Test: given the true gravity
/// tilted by 5 mrad, at full IMU weight, the gravity the graph implies is
/// 0.29 mrad off with the gauge, 1.25 mrad without (the chain bends after
/// the held first keyframe instead; tests/imu/test_lio_slam.cpp).
///
/// IMU weighting (measured, not derived). The IMU factors are consistent
/// with the simulator at their white-noise information (chi2 ~ 9 at the
/// truth). What they are weighed against is the lidar between (and loop)
/// information, Omega = s * H with the conventional s = 1 (residual sigma
/// 1 m, see above): ~3 cm per 0.1 s keyframe interval, while the front end's
/// relative poses are good to ~1 mm (its residuals' noise is ~1-2 cm). So
/// at full weight against s = 1, IMU dead reckoning (white-noise drift
/// ~0.14 m over 30 s, plus bias) overrules a front end that drifts ~3 cm
/// there; the frozen gravity direction was not the main reason. All-frame
/// ATE [m] with loops, scripts/lio_loop_accuracy.sh with IMU_SCALE and
/// GRAVITY_GAUGE, on the simulated revisiting urban drives with distortion
/// of 600 frames, seed 1 (LIO alone 0.0185) and 1000 frames, heavy traffic,
/// seed 2 (LIO alone 0.1033):
///
///   imu_information_scale           1       1e-3    1e-4    1e-6
///   600 frames, 6-DoF prior         0.0429   -       -      0.0207
///   600 frames, gravity gauge       0.0379  0.0236  0.0225  0.0200
///   1000 heavy, 6-DoF prior         0.0705   -       -      0.0674
///   1000 heavy, gravity gauge       0.0795  0.0624  0.0633  0.0603
///
/// Full weight needs the lidar information at its real scale, odometry and
/// loops together: inertial_lidar_information_scale (default 1) multiplies
/// both, and their eigenvalue ceiling max_information, in this back end only
/// (the floor stays: a degenerate direction stays weak and the IMU carries
/// it; the lidar-only back end ignores the option, tests/pipeline/
/// test_slam.cpp).
///
/// The between measurement is the front end's scan-to-map motion
/// (LidarInertialFrontEnd::registered_pose), not the motion of the LIO's
/// fused poses: those already hold the IMU, which the IMU factors would add
/// a second time, while the between's information is the scan-to-map
/// Hessian alone. All-frame ATE [m] on three drives, gravity gauge (LIO
/// alone 0.0185 / 0.1033 / 0.1671):
///
///   drive (urban, revisit, distortion)   fused between      scan-to-map between
///                                        default  A    B    default    A
///   600 frames, seed 1, light            0.0200 0.0203 0.0206  0.0189  0.0197
///   1000 frames, seed 2, heavy           0.0603 0.0624 0.0578  0.0444  0.0416
///   800 frames, seed 3, light            0.1139 0.1171 0.1266  0.1103  0.1149*
///
/// A: IMU 1, lidar 1e4. B: the same with the loops clamped at 1e8.
/// Drives: semlio_simulate --world urban --revisit --distortion on with
/// those frames, seed and traffic. Default and A: scripts/lio_loop_accuracy.sh
/// (DRIVE=<drive> KEEP_SCANS=1) with IMU_SCALE=1e-6 LIDAR_SCALE=1 (= the
/// default) and with IMU_SCALE=1 LIDAR_SCALE=1e4; B: semlio_kitti --imu oxts
/// --deskew on --loop on with slam.imu_information_scale 1,
/// odometry_information_scale 1e4, max_information 1e12 and
/// loop_verify.hessian_scale 1e4 (the verifier then clamps the loops at its
/// max_eigenvalue 1e8; the 1e3 = 3 cm variant of it was worse: 0.0237 /
/// 0.0605 on the first two drives). *: a local build of the same
/// scan-to-map between before it was written here. Full weight is
/// worse or mixed in every variant, so the default stays: IMU at 1e-6,
/// lidar at s = 1. The IMU factors carry velocity, bias and the gravity
/// direction between keyframes and bridge lidar failures without
/// overruling the lidar. (Neither is the window the cause: solving every
/// keyframe in full at IMU scale 1 against s = 1, inertial_window_size
/// 100000, cuts the drift before the first loop from 2.4 m to 0.16 m but
/// not the final ATE, 0.0441 on the 600-frame drive with the fused between.)
///
/// Not thread-safe; one Slam per sensor stream.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/core/stopwatch.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/graph/keyframe_inertial_graph.hpp>
#include <semlio/graph/pose_graph.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/loop/loop_closer.hpp>
#include <semlio/loop/loop_keyframe.hpp>
#include <semlio/loop/radius_detector.hpp>
#include <semlio/map/semantic_map.hpp>
#include <semlio/pipeline/odometry.hpp>
#include <semlio/search/voxel_grid.hpp>

namespace semlio {

/// What Slam needs of a front end: Odometry's process() and features().
template <typename O>
concept SlamFrontEnd = requires(O o, Scan& scan, const std::optional<SE3d>& prior) {
  { o.process(scan, prior) } -> std::same_as<FrameReport>;
  { o.features() } -> std::convertible_to<const LoamFeatures&>;
};

/// A front end that also reports inertial states and preintegrates its IMU
/// over keyframe intervals (LidarInertialFrontEnd): Slam then runs a
/// KeyframeInertialGraph (file comment).
template <typename O>
concept InertialSlamFrontEnd =
    SlamFrontEnd<O> && requires(O o, const O& c, double t, const ImuBias& b, const Eigen::Vector3d& g) {
      { c.inertial_state() } -> std::same_as<std::optional<KeyframeInertialNode>>;
      { c.preintegrate(t, t, b, g) } -> std::same_as<std::optional<ImuPreintegration>>;
      { c.gravity_map_mps2() } -> std::convertible_to<Eigen::Vector3d>;
      { c.T_imu_lidar() } -> std::convertible_to<SE3d>;
      { c.imu_stamp_s(t) } -> std::convertible_to<double>;
      { c.registered_pose() } -> std::convertible_to<SE3d>;
      o.drop_imu_before(t);
    };

/// Settings of Slam (documented defaults; see the file comment for the why).
struct SlamConfig {
  bool loop_closure = true;                  ///< detect and add loops; off: the back end only mirrors the odometry
  LoopCloserConfig loop{};                   ///< verification thresholds (loop_closer.hpp / loop_verifier.hpp)
  PoseGraphConfig graph{};                   ///< solver; window_size newest keyframes per incremental update
  double loop_interval_s = 1.0;              ///< query the loop closer at most this often [s] (LIO-SAM: 1 Hz); 0 = every keyframe
  bool robust_loops = true;                  ///< Huber-weight loop factors (graph.huber_delta)
  double odometry_information_scale = 1.0;   ///< Omega = scale * H (residual sigma 1 m / sqrt(scale))
  double min_information = 1e-2;             ///< eigenvalue floor of an odometry factor's information
  double max_information = 1e8;              ///< eigenvalue ceiling of the same
  double weak_sigma_m = 1.0;                 ///< weak default (failed frames in between): translation sigma [m]
  double weak_sigma_rad = 0.1;               ///< weak default: rotation sigma [rad]
  double keyframe_cloud_leaf_m = 0.5;        ///< voxel leaf of the cloud kept per keyframe (Scan Context, map) [m]
  double keyframe_cloud_max_range_m = 80.0;  ///< drop farther points from the kept cloud [m]; 0 = keep all
  std::size_t max_keyframe_clouds = 100;     ///< newest keyframes kept in full; older ones retire (file comment); 0 = never retire (unbounded)
  double place_spacing_m = 2.0;              ///< a retiring keyframe keeps its data only when no place is within this distance [m] (grows when thinning)
  std::size_t max_place_bytes = std::size_t{128} << 20;  ///< ceiling on the places' data (features + clouds) [bytes]; 0 = no ceiling
  double place_thinning_factor = 1.5;        ///< over the ceiling: the place spacing grows by this factor and the places are thinned (> 1)
  /// Lidar-inertial front ends only: the keyframe graph's solver (its
  /// T_imu_sensor is taken from the front end). IMU information scaled by
  /// 1e-6 against the lidar's conventional s = 1, by measurement: full
  /// weight with the lidar at its real scale (next field 1e4) was worse on
  /// the three drives measured; see "IMU weighting" in the file comment.
  KeyframeInertialGraphConfig inertial_graph{.imu_information_scale = 1e-6};
  /// Lidar-inertial front ends only: multiplies the lidar information (the
  /// odometry between factors' odometry_information_scale * H and the
  /// verified loops' information) and its ceiling max_information, not its
  /// floor (a degenerate direction stays weak: the IMU carries it). 1e4 =
  /// residual sigma 1 cm, the front end's real accuracy, is the scale that
  /// lets inertial_graph.imu_information_scale = 1 not overrule the lidar
  /// (file comment, "IMU weighting"). The lidar-only back end ignores it.
  double inertial_lidar_information_scale = 1.0;
  double inertial_first_sigma_m = 1e-3;          ///< first keyframe's pose prior, translation (the gauge) [m]
  double inertial_first_sigma_rad = 1e-4;        ///< same, rotation (with the gravity gauge: about gravity only) [rad]
  /// Once the first IMU factor is in the graph, the first keyframe's prior
  /// holds position and yaw only (4-DoF gauge): the IMU factors then set the
  /// trajectory's roll and pitch, i.e. the graph estimates the gravity
  /// direction (file comment, "Gravity"). false: all 6 DoF, the map's gravity
  /// as the front end estimated it.
  bool inertial_gravity_gauge = true;
  double inertial_velocity_sigma_mps = 0.5;      ///< prior on the front end's velocity where no IMU factor links a keyframe [m/s]
  /// Same while the front end has no velocity yet [m/s]. No IMU factor
  /// touches such a velocity, so its value does not matter; a much weaker
  /// prior would only trip the singularity test next to the bias walk's
  /// information (pivot ratio 1e-14).
  double inertial_unknown_velocity_sigma_mps = 1.0;
  double inertial_gyro_bias_sigma_radps = 1e-3;  ///< prior on the gyro bias of an unlinked keyframe [rad/s]
  double inertial_accel_bias_sigma_mps2 = 0.1;   ///< prior on the accel bias of an unlinked keyframe [m/s^2]

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    const auto positive = [](double v, const char* name) {
      if (!(v > 0.0) || !std::isfinite(v)) {
        throw ConfigError(std::string("SlamConfig.") + name + " = " + std::to_string(v) + ", expected a finite value > 0");
      }
    };
    positive(odometry_information_scale, "odometry_information_scale");
    positive(inertial_lidar_information_scale, "inertial_lidar_information_scale");
    positive(min_information, "min_information");
    positive(max_information, "max_information");
    positive(weak_sigma_m, "weak_sigma_m");
    positive(weak_sigma_rad, "weak_sigma_rad");
    positive(keyframe_cloud_leaf_m, "keyframe_cloud_leaf_m");
    positive(place_spacing_m, "place_spacing_m");
    positive(inertial_first_sigma_m, "inertial_first_sigma_m");
    positive(inertial_first_sigma_rad, "inertial_first_sigma_rad");
    positive(inertial_velocity_sigma_mps, "inertial_velocity_sigma_mps");
    positive(inertial_unknown_velocity_sigma_mps, "inertial_unknown_velocity_sigma_mps");
    positive(inertial_gyro_bias_sigma_radps, "inertial_gyro_bias_sigma_radps");
    positive(inertial_accel_bias_sigma_mps2, "inertial_accel_bias_sigma_mps2");
    if (!(place_thinning_factor > 1.0) || !std::isfinite(place_thinning_factor)) {
      throw ConfigError("SlamConfig.place_thinning_factor = " + std::to_string(place_thinning_factor) +
                        ", expected a finite value > 1");
    }
    if (!(min_information <= max_information)) {
      throw ConfigError("SlamConfig.min_information = " + std::to_string(min_information) +
                        " exceeds max_information = " + std::to_string(max_information));
    }
    if (!std::isfinite(inertial_lidar_information_scale * max_information)) {
      throw ConfigError("SlamConfig.inertial_lidar_information_scale = " +
                        std::to_string(inertial_lidar_information_scale) + " times max_information = " +
                        std::to_string(max_information) + " overflows");
    }
    if (!(loop_interval_s >= 0.0) || !std::isfinite(loop_interval_s)) {
      throw ConfigError("SlamConfig.loop_interval_s = " + std::to_string(loop_interval_s) + ", expected >= 0");
    }
    if (!(keyframe_cloud_max_range_m >= 0.0)) {
      throw ConfigError("SlamConfig.keyframe_cloud_max_range_m = " + std::to_string(keyframe_cloud_max_range_m) +
                        ", expected >= 0");
    }
  }
};

/// One accepted loop closure as the back end used it.
struct SlamLoop {
  std::size_t from_keyframe = 0;   ///< older keyframe (graph node)
  std::size_t to_keyframe = 0;     ///< newer keyframe (graph node)
  std::size_t from_frame = 0;      ///< frame index of from_keyframe
  std::size_t to_frame = 0;        ///< frame index of to_keyframe
  double fitness_m = 0.0;          ///< verification RMS residual [m]
  double inlier_ratio = 0.0;       ///< verification matched fraction
  double correction_m = 0.0;       ///< distance between the query keyframe's estimate and the loop's measurement of it, before the solve [m]
  GraphSolveReport solve;          ///< the full graph solve it triggered
  double solve_ms = 0.0;           ///< wall time of that solve [ms]
};

/// What Slam::process reports about one frame.
struct SlamFrameReport {
  FrameReport odometry;               ///< the front end's report (pose in the odometry frame)
  SE3d T_world_lidar;                 ///< pose in the world (graph) frame at this time
  bool keyframe = false;              ///< a graph node was added
  bool loop_checked = false;          ///< the loop closer ran a verification this frame
  bool loop_closed = false;           ///< a loop was accepted and the graph re-solved
  std::optional<GraphSolveReport> graph;  ///< the graph update of this frame (keyframes with loops on)
  double backend_ms = 0.0;            ///< back-end wall time (downsample, loops, graph) [ms]
  double total_ms = 0.0;              ///< odometry + back end [ms]
};

namespace detail {

/// Symmetric eigenvalue clamp of a 6x6 information matrix; identity * lo when
/// the input is not finite.
inline Eigen::Matrix<double, 6, 6> clamp_information6(const Eigen::Matrix<double, 6, 6>& H, double lo, double hi) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  if (!H.allFinite()) return Matrix6::Identity() * lo;
  const Matrix6 S = 0.5 * (H + H.transpose());
  const Eigen::SelfAdjointEigenSolver<Matrix6> es(S);
  Eigen::Matrix<double, 6, 1> ev = es.eigenvalues();
  for (int k = 0; k < 6; ++k) ev[k] = std::isfinite(ev[k]) ? std::clamp(ev[k], lo, hi) : lo;
  Matrix6 out = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
  if (!out.allFinite()) return Matrix6::Identity() * lo;
  return 0.5 * (out + out.transpose());
}

/// True for statuses whose pose came from the prediction, not from data.
constexpr bool prediction_only(OdometryStatus s) noexcept {
  return s == OdometryStatus::kTooFewFeatures || s == OdometryStatus::kSolverFailed ||
         s == OdometryStatus::kRejectedJump;
}

/// Copy of a feature set without the scan indices (not needed by the back end).
inline FeatureSet compact_features(const FeatureSet& in) {
  FeatureSet out;
  out.points = in.points;
  out.labels = in.labels;
  return out;
}

}  // namespace detail

/// Front end + pose graph + loop closure + semantic map. Owns the odometry
/// and the detector by value (CTAD: `Slam slam(make_full_odometry(...),
/// RadiusLoopDetector{}, config);`).
template <SlamFrontEnd OdometryT, LoopDetector Detector = RadiusLoopDetector>
class Slam {
 public:
  using Config = SlamConfig;
  /// True with a lidar-inertial front end (file comment).
  static constexpr bool kInertial = InertialSlamFrontEnd<OdometryT>;
  /// The keyframe graph: poses only, or poses with velocity and IMU bias.
  using Graph = std::conditional_t<kInertial, KeyframeInertialGraph, PoseGraph<SE3d>>;

  /// Takes the configured front end and loop detector.
  explicit Slam(OdometryT odometry, Detector detector = Detector(), const Config& config = {})
      : config_((config.validate(), config)),
        odometry_(std::move(odometry)),
        closer_(std::move(detector), config.loop),
        graph_(make_graph(config, odometry_)),
        cloud_grid_(VoxelGridConfig{.leaf_size_m = config.keyframe_cloud_leaf_m}),
        place_spacing_m_(config.place_spacing_m) {}

  /// Processes one scan (sensor frame; consumed as the front end's working
  /// buffer). `T_world_lidar_prior`, when given, is a pose prior in the world
  /// (graph) frame; it is mapped into the odometry frame for the front end.
  SlamFrameReport process(Scan& scan, const std::optional<SE3d>& T_world_lidar_prior = std::nullopt) {
    SlamFrameReport out;
    std::optional<SE3d> prior_odom;
    if (T_world_lidar_prior && T_world_lidar_prior->matrix().allFinite()) {
      prior_odom = has_keyframe() ? T_odom_kf_.back() * graph_.pose(last_node()).inverse() * *T_world_lidar_prior
                                  : *T_world_lidar_prior;
    }
    out.odometry = odometry_.process(scan, prior_odom);
    const auto t0 = StageClock::now();
    SE3d T_odom = out.odometry.T_map_lidar;
    if (!T_odom.matrix().allFinite()) T_odom = odom_poses_.empty() ? SE3d() : odom_poses_.back();
    failed_since_keyframe_ = failed_since_keyframe_ || detail::prediction_only(out.odometry.status);

    if (out.odometry.keyframe) {
      out.keyframe = true;
      add_keyframe(scan, out, T_odom);
    }
    // Frame bookkeeping: preceding keyframe and the odometry motion since it.
    odom_poses_.push_back(T_odom);
    if (has_keyframe()) {
      frame_kf_.push_back(static_cast<std::uint32_t>(last_node()));
      frame_rel_.push_back(T_odom_kf_.back().inverse() * T_odom);
    } else {
      frame_kf_.push_back(kNoKeyframe);
      frame_rel_.push_back(T_odom);
    }
    out.T_world_lidar = world_pose(frames() - 1);
    out.backend_ms = ms_since(t0);
    out.total_ms = out.odometry.timings.total_ms + out.backend_ms;
    return out;
  }

  /// Feeds an IMU sample to a lidar-inertial front end (before the scans it
  /// covers); false when the front end rejects it.
  bool push_imu(const ImuSample& sample)
    requires requires(OdometryT& o, const ImuSample& s) { o.push_imu(s); }
  {
    return odometry_.push_imu(sample);
  }
  /// Feeds an INS velocity to a front end that takes one.
  bool push_velocity(double stamp_s, const Eigen::Vector3d& v_imu_mps)
    requires requires(OdometryT& o, double t, const Eigen::Vector3d& v) { o.push_velocity(t, v); }
  {
    return odometry_.push_velocity(stamp_s, v_imu_mps);
  }

  /// Number of processed frames.
  [[nodiscard]] std::size_t frames() const noexcept { return odom_poses_.size(); }
  /// Optimised pose of frame i in the world frame with the latest graph.
  [[nodiscard]] SE3d world_pose(std::size_t i) const {
    if (i >= frames()) throw ValueError("Slam::world_pose: frame " + std::to_string(i) + " of " + std::to_string(frames()));
    return frame_kf_[i] == kNoKeyframe ? frame_rel_[i] : graph_.pose(frame_kf_[i]) * frame_rel_[i];
  }
  /// Optimised trajectory, one pose per processed frame (world frame).
  [[nodiscard]] std::vector<SE3d> trajectory() const {
    std::vector<SE3d> out(frames());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = world_pose(i);
    return out;
  }
  /// Odometry-only trajectory, one pose per processed frame (odometry frame).
  [[nodiscard]] const std::vector<SE3d>& odometry_trajectory() const noexcept { return odom_poses_; }
  /// Frame index of every keyframe (graph node order).
  [[nodiscard]] const std::vector<std::size_t>& keyframe_frames() const noexcept { return keyframe_frame_; }
  /// The stored keyframes (poses = latest graph estimate).
  [[nodiscard]] const std::vector<LoopKeyframe>& keyframes() const noexcept { return keyframes_; }
  /// Accepted loops in order.
  [[nodiscard]] const std::vector<SlamLoop>& loops() const noexcept { return loops_; }
  /// The loop closer's counters (queries, candidates, verifications, rejections).
  [[nodiscard]] const LoopStats& loop_stats() const noexcept { return closer_.stats(); }
  /// The keyframe graph (node i = keyframe i; pose() = the lidar's pose).
  [[nodiscard]] const Graph& graph() const noexcept { return graph_; }
  /// IMU factors in the graph (0 for a lidar-only front end).
  [[nodiscard]] std::size_t imu_factors() const noexcept {
    if constexpr (kInertial) {
      return graph_.num_imu_factors();
    } else {
      return 0;
    }
  }
  /// Total wall time of graph updates so far [ms], and of the full solves among them.
  [[nodiscard]] double graph_ms() const noexcept { return graph_ms_; }
  /// Wall time of full graph solves (after loops) [ms].
  [[nodiscard]] double graph_full_ms() const noexcept { return graph_full_ms_; }
  /// The front end.
  [[nodiscard]] const OdometryT& odometry() const noexcept { return odometry_; }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

  /// Indices of the retired keyframes that kept their data (places), oldest first.
  [[nodiscard]] const std::vector<std::size_t>& places() const noexcept { return places_; }
  /// Number of retired keyframes whose data was dropped (LoopKeyframe::archived).
  [[nodiscard]] std::size_t archived_count() const noexcept { return archived_; }
  /// Number of keyframes retired so far (places + archived).
  [[nodiscard]] std::size_t retired_count() const noexcept { return next_retire_; }
  /// Data bytes (features, clouds, labels) of the places; at most
  /// config().max_place_bytes when that is > 0.
  [[nodiscard]] std::size_t place_bytes() const noexcept { return place_bytes_; }
  /// The current place spacing [m]: place_spacing_m, grown by each thinning.
  [[nodiscard]] double place_spacing_m() const noexcept { return place_spacing_m_; }
  /// Number of thinnings so far (each grew the spacing by place_thinning_factor).
  [[nodiscard]] std::size_t place_thinnings() const noexcept { return thinnings_; }

  /// Heap bytes of one keyframe's data (features, clouds, labels).
  [[nodiscard]] static std::size_t data_bytes(const LoopKeyframe& k) noexcept {
    const auto set_bytes = [](const FeatureSet& f) {
      return f.points.capacity() * sizeof(Eigen::Vector3f) + f.labels.capacity() * sizeof(Class) +
             f.indices.capacity() * sizeof(std::uint32_t);
    };
    return set_bytes(k.corners) + set_bytes(k.surfaces) + k.cloud.capacity() * sizeof(Eigen::Vector3f) +
           k.labels.capacity() * sizeof(Class);
  }

  /// Heap bytes of the stored keyframes: records plus data (features, clouds,
  /// labels) = recent keyframes + places + one record per keyframe.
  [[nodiscard]] std::size_t keyframe_bytes() const noexcept {
    std::size_t b = keyframes_.capacity() * sizeof(LoopKeyframe);
    for (const LoopKeyframe& k : keyframes_) b += data_bytes(k);
    return b;
  }

  /// Adds the kept keyframe clouds (places + the newest max_keyframe_clouds;
  /// archived keyframes have none) at their optimised poses to `map`.
  void build_semantic_map(SemanticMap& map) const {
    for (std::size_t k = 0; k < keyframes_.size(); ++k) {
      if (keyframes_[k].cloud.empty()) continue;
      map.insert(graph_.pose(static_cast<NodeId>(k)), keyframes_[k].cloud, keyframes_[k].labels);
    }
  }

  /// The global semantic map: build_semantic_map() into a SemanticMap
  /// (map/semantic_map.hpp), as a cloud in the world frame.
  [[nodiscard]] Scan semantic_map(const SemanticMapConfig& config = {}) const {
    SemanticMap map(config);
    build_semantic_map(map);
    return map.cloud();
  }

 private:
  static constexpr std::uint32_t kNoKeyframe = std::numeric_limits<std::uint32_t>::max();

  [[nodiscard]] bool has_keyframe() const noexcept { return !T_odom_kf_.empty(); }

  static Graph make_graph(const Config& config, const OdometryT& odometry) {
    if constexpr (kInertial) {
      KeyframeInertialGraphConfig c = config.inertial_graph;
      c.T_imu_sensor = odometry.T_imu_lidar();
      return Graph(c);
    } else {
      return Graph(config.graph);
    }
  }

  // Inertial keyframe node (see the file comment): the IMU state from the
  // front end moved into the world frame with the keyframe's world pose, a
  // between factor, and an IMU factor from the previous keyframe or a prior.
  void add_inertial_node(const SE3d& T_world_lidar, const SE3d& T_odom_lidar, const FrameReport& r) {
    if constexpr (kInertial) {
      const SE3d T_lidar_imu = odometry_.T_imu_lidar().inverse();
      const SE3d T_world_imu = T_world_lidar * T_lidar_imu;
      const SO3d R_world_odom = (T_world_imu * (T_odom_lidar * T_lidar_imu).inverse()).so3();
      const std::optional<KeyframeInertialNode> s = odometry_.inertial_state();
      NavState x;
      x.R_world_imu = T_world_imu.so3();
      x.p_world_m = T_world_imu.translation();
      x.v_world_mps = s ? Eigen::Vector3d(R_world_odom * s->state.v_world_mps) : Eigen::Vector3d::Zero();
      const ImuBias b = s ? s->bias : ImuBias{};
      const double t_imu = odometry_.imu_stamp_s(r.stamp_s);
      const SE3d T_registered = odometry_.registered_pose();
      const bool first = !has_keyframe();
      const NodeId node = graph_.add_node(t_imu, x, b);
      bool linked = false;
      if (!first) {
        const NodeId prev = last_node();
        // The between is the scan-to-map motion, not the LIO's fused poses:
        // those already hold the IMU, which the IMU factor below adds again
        // (file comment, "IMU weighting").
        graph_.add_between(prev, node, T_registered_kf_.back().inverse() * T_registered, odometry_information(r));
        if (s && prev_inertial_) {
          const KeyframeInertialNode& p = graph_.node(prev);
          // Gravity is a constant of the world frame, which is the front end's
          // map frame (the first keyframe's prior holds it there): the map's
          // gravity as it is. Rotating it by R_world_odom (the graph's
          // correction at this keyframe, as for the velocity) let the graph's
          // own attitude errors tilt the gravity of every later IMU factor.
          const Eigen::Vector3d g_world = odometry_.gravity_map_mps2();
          if (const std::optional<ImuPreintegration> pim = odometry_.preintegrate(p.stamp_s, t_imu, p.bias, g_world)) {
            graph_.add_imu(prev, node, *pim);
            linked = true;
          }
        }
      }
      if (first || !linked) {
        const auto inv2 = [](double sigma) { return 1.0 / (sigma * sigma); };
        Vector15d w = Vector15d::Zero();
        if (first) {
          w.head<3>().setConstant(inv2(config_.inertial_first_sigma_m));
          w.segment<3>(3).setConstant(inv2(config_.inertial_first_sigma_rad));
        }
        w.segment<3>(6).setConstant(
            inv2(s ? config_.inertial_velocity_sigma_mps : config_.inertial_unknown_velocity_sigma_mps));
        w.segment<3>(9).setConstant(inv2(config_.inertial_gyro_bias_sigma_radps));
        w.segment<3>(12).setConstant(inv2(config_.inertial_accel_bias_sigma_mps2));
        const std::size_t f = graph_.add_prior(node, x, b, w.asDiagonal().toDenseMatrix());
        if (first) {
          first_prior_ = f;
          first_prior_information_ = w.asDiagonal().toDenseMatrix();
          first_R_world_imu_ = x.R_world_imu;
        }
      }
      // The 4-DoF gauge (file comment, "Gravity"): relaxed once, when the
      // first IMU factor makes roll and pitch observable; before it a prior
      // on position and yaw alone would leave them free (singular).
      if (linked && config_.inertial_gravity_gauge && !gauge_relaxed_) {
        Matrix15d info = first_prior_information_;
        info.topLeftCorner<6, 6>() =
            gravity_gauge_information(first_R_world_imu_, odometry_.gravity_map_mps2(),
                                      config_.inertial_first_sigma_m, config_.inertial_first_sigma_rad);
        graph_.set_prior_information(first_prior_, info);
        gauge_relaxed_ = true;
      }
      prev_inertial_ = s.has_value();
      T_registered_kf_.push_back(T_registered);
      odometry_.drop_imu_before(t_imu);
    }
  }
  [[nodiscard]] NodeId last_node() const noexcept { return static_cast<NodeId>(T_odom_kf_.size() - 1); }

  Eigen::Matrix<double, 6, 6> odometry_information(const FrameReport& r) const {
    Eigen::Matrix<double, 6, 6> weak = Eigen::Matrix<double, 6, 6>::Zero();
    weak.diagonal() << Eigen::Vector3d::Constant(1.0 / (config_.weak_sigma_m * config_.weak_sigma_m)),
        Eigen::Vector3d::Constant(1.0 / (config_.weak_sigma_rad * config_.weak_sigma_rad));
    if (failed_since_keyframe_ || !r.solve.ok() || !r.solve.hessian.allFinite() || r.solve.hessian.isZero(0.0)) {
      return weak;
    }
    return lidar_information(config_.odometry_information_scale * r.solve.hessian);
  }

  // The lidar's information (odometry between or verified loop) as the graph
  // gets it, eigenvalues clamped. The inertial back end scales it and its
  // ceiling to the lidar's real accuracy (inertial_lidar_information_scale;
  // file comment, "IMU weighting"); the floor stays, so a degenerate
  // direction stays weak and the IMU carries it. Lidar-only: as it was.
  // (Scaling by 1.0 is exact, so lidar-only stays bit for bit.)
  Eigen::Matrix<double, 6, 6> lidar_information(const Eigen::Matrix<double, 6, 6>& Omega) const {
    const double s = kInertial ? config_.inertial_lidar_information_scale : 1.0;
    return detail::clamp_information6(s * Omega, config_.min_information, s * config_.max_information);
  }

  void add_keyframe(const Scan& scan, SlamFrameReport& out, const SE3d& T_odom) {
    // Graph node: optimised pose of the previous keyframe + odometry motion.
    const std::size_t frame = frames();
    SE3d T_world = T_odom;
    if constexpr (kInertial) {
      if (has_keyframe()) T_world = graph_.pose(last_node()) * (T_odom_kf_.back().inverse() * T_odom);
      add_inertial_node(T_world, T_odom, out.odometry);
    } else if (has_keyframe()) {
      const SE3d Z = T_odom_kf_.back().inverse() * T_odom;
      T_world = graph_.pose(last_node()) * Z;
      const NodeId prev = last_node();
      const NodeId node = graph_.add_node(T_world);
      graph_.add_between(prev, node, Z, odometry_information(out.odometry));
    } else {
      graph_.add_node(T_world);
    }
    failed_since_keyframe_ = false;
    T_odom_kf_.push_back(T_odom);
    keyframe_frame_.push_back(frame);

    // Compact keyframe: downsampled cloud (+ features when loops are on).
    LoopKeyframe kf;
    kf.stamp_s = out.odometry.stamp_s;
    kf.T_world_lidar = T_world;
    downsample_cloud(scan, kf);
    if (config_.loop_closure) {
      kf.corners = detail::compact_features(odometry_.features().corners);
      kf.surfaces = detail::compact_features(odometry_.features().surfaces);
    }
    keyframes_.push_back(std::move(kf));
    if (!config_.loop_closure) {
      retire_keyframes();
      return;
    }

    // Loop closure, rate-limited.
    std::optional<LoopConstraint> loop;
    if (keyframes_.size() >= 2 &&
        (!last_query_s_ || !(out.odometry.stamp_s - *last_query_s_ < config_.loop_interval_s))) {
      last_query_s_ = out.odometry.stamp_s;
      const std::size_t verified_before = closer_.stats().verified;
      loop = closer_.process(keyframes_);
      out.loop_checked = closer_.stats().verified > verified_before;
    }
    // Retire after the query: the detector has now seen (and cached) every
    // keyframe up to this one.
    retire_keyframes();
    SlamLoop record;
    if (loop && loop->from < loop->to && loop->to < keyframes_.size() && loop->information.allFinite() &&
        loop->T_from_to.matrix().allFinite()) {
      const SE3d before = graph_.pose(static_cast<NodeId>(loop->to));
      graph_.add_loop(static_cast<NodeId>(loop->from), static_cast<NodeId>(loop->to), loop->T_from_to,
                      lidar_information(loop->information),
                      config_.robust_loops);
      record.from_keyframe = loop->from;
      record.to_keyframe = loop->to;
      record.from_frame = keyframe_frame_[loop->from];
      record.to_frame = keyframe_frame_[loop->to];
      record.fitness_m = loop->fitness_m;
      record.inlier_ratio = loop->inlier_ratio;
      const SE3d measured_to = graph_.pose(static_cast<NodeId>(loop->from)) * loop->T_from_to;
      record.correction_m = (measured_to.translation() - before.translation()).norm();
      out.loop_closed = true;
    }

    // Graph update: window, or a warm-started full solve after a loop.
    const bool full = graph_.full_solve_pending();
    const auto t = StageClock::now();
    const GraphSolveReport report = graph_.update();
    const double ms = ms_since(t);
    graph_ms_ += ms;
    if (full) graph_full_ms_ += ms;
    out.graph = report;
    if (out.loop_closed) {
      record.solve = report;
      record.solve_ms = ms;
      loops_.push_back(record);
    }
    // Hand the new estimates to the keyframes (all after a full solve).
    const std::size_t n = keyframes_.size();
    const std::size_t from = full ? 0 : n - std::min(n, graph_.config().window_size);
    for (std::size_t k = from; k < n; ++k) keyframes_[k].T_world_lidar = graph_.pose(static_cast<NodeId>(k));
  }

  // Retires the keyframes beyond the newest max_keyframe_clouds that the loop
  // detector has already seen (its last query is at or after their stamp),
  // then holds the places to their ceiling.
  void retire_keyframes() {
    if (config_.max_keyframe_clouds == 0) return;
    while (keyframes_.size() - next_retire_ > config_.max_keyframe_clouds) {
      LoopKeyframe& kf = keyframes_[next_retire_];
      if (config_.loop_closure && (!last_query_s_ || kf.stamp_s > *last_query_s_)) break;
      const Eigen::Vector3d p = kf.T_world_lidar.translation();
      const double s2 = place_spacing_m_ * place_spacing_m_;
      bool covered = false;
      for (const std::size_t j : places_) {
        if ((keyframes_[j].T_world_lidar.translation() - p).squaredNorm() < s2) {
          covered = true;
          break;
        }
      }
      if (covered) {
        archive(kf);
      } else {
        places_.push_back(next_retire_);
        place_bytes_ += data_bytes(kf);
      }
      ++next_retire_;
    }
    enforce_place_ceiling();
  }

  // Frees a keyframe's data (it keeps stamp, pose and the detector's descriptor).
  void archive(LoopKeyframe& kf) {
    kf.corners = FeatureSet{};
    kf.surfaces = FeatureSet{};
    kf.cloud = std::vector<Eigen::Vector3f>{};
    kf.labels = std::vector<Class>{};
    kf.archived = true;
    ++archived_;
  }

  // While the places' data exceeds max_place_bytes: grow the spacing and thin
  // the places to it (greedy, newest first). Ends: at a large enough spacing
  // one place is left, and one place over the ceiling is archived too.
  void enforce_place_ceiling() {
    if (config_.max_place_bytes == 0) return;
    while (place_bytes_ > config_.max_place_bytes && !places_.empty()) {
      if (places_.size() == 1) {
        place_bytes_ -= data_bytes(keyframes_[places_.front()]);
        archive(keyframes_[places_.front()]);
        places_.clear();
        break;
      }
      place_spacing_m_ *= config_.place_thinning_factor;
      ++thinnings_;
      const double s2 = place_spacing_m_ * place_spacing_m_;
      kept_.clear();
      for (auto it = places_.rbegin(); it != places_.rend(); ++it) {
        LoopKeyframe& kf = keyframes_[*it];
        const Eigen::Vector3d p = kf.T_world_lidar.translation();
        bool covered = false;
        for (const std::size_t j : kept_) {
          if ((keyframes_[j].T_world_lidar.translation() - p).squaredNorm() < s2) {
            covered = true;
            break;
          }
        }
        if (covered) {
          place_bytes_ -= data_bytes(kf);
          archive(kf);
        } else {
          kept_.push_back(*it);
        }
      }
      std::reverse(kept_.begin(), kept_.end());
      places_.swap(kept_);
    }
  }

  void downsample_cloud(const Scan& scan, LoopKeyframe& kf) {
    const double r2 = config_.keyframe_cloud_max_range_m * config_.keyframe_cloud_max_range_m;
    subset_.clear();
    for (std::uint32_t i = 0; i < scan.points.size(); ++i) {
      if (r2 > 0.0 && static_cast<double>(scan.points[i].squaredNorm()) > r2) continue;
      subset_.push_back(i);
    }
    const std::vector<Class>& labels = scan.labels.size() == scan.points.size() ? scan.labels : no_labels_;
    cloud_grid_.downsample(scan.points, labels, subset_, cloud_pts_, cloud_labels_, first_idx_);
    kf.cloud.assign(cloud_pts_.begin(), cloud_pts_.end());
    kf.labels.assign(cloud_labels_.begin(), cloud_labels_.end());
  }

  Config config_;
  OdometryT odometry_;
  LoopCloser<Detector> closer_;
  Graph graph_;
  VoxelGrid cloud_grid_;
  std::vector<LoopKeyframe> keyframes_;
  std::vector<std::size_t> places_;        // retired keyframes that kept their data
  std::size_t next_retire_ = 0;            // keyframes [0, next_retire_) are retired
  std::size_t archived_ = 0;               // retired keyframes whose data was dropped
  double place_spacing_m_ = 2.0;           // current place spacing (grows with each thinning)
  std::size_t place_bytes_ = 0;            // data bytes of the places
  std::size_t thinnings_ = 0;
  std::vector<std::size_t> kept_;          // thinning buffer
  std::vector<SE3d> T_odom_kf_;            // odometry pose of each keyframe
  std::vector<SE3d> T_registered_kf_;      // inertial: the front end's scan-to-map pose of each keyframe
  std::vector<std::size_t> keyframe_frame_;
  std::vector<SlamLoop> loops_;
  std::vector<SE3d> odom_poses_;           // per frame
  std::vector<std::uint32_t> frame_kf_;    // per frame: preceding keyframe or kNoKeyframe
  std::vector<SE3d> frame_rel_;            // per frame: T_odom_kf^-1 T_odom_frame
  bool failed_since_keyframe_ = false;
  bool prev_inertial_ = false;             // the previous keyframe had an inertial state (inertial graph)
  std::size_t first_prior_ = 0;            // inertial graph: the first keyframe's prior (factor id) ...
  Matrix15d first_prior_information_ = Matrix15d::Zero();  // ... its 6-DoF information ...
  SO3d first_R_world_imu_;                 // ... and rotation (the 4-DoF gauge is built from them)
  bool gauge_relaxed_ = false;             // the first prior holds position and yaw only
  std::optional<double> last_query_s_;
  double graph_ms_ = 0.0;
  double graph_full_ms_ = 0.0;
  // Reused buffers.
  std::vector<std::uint32_t> subset_;
  std::vector<Eigen::Vector3f> cloud_pts_;
  std::vector<Class> cloud_labels_;
  std::vector<std::uint32_t> first_idx_;
  std::vector<Class> no_labels_;
};

/// Deduction guides: front end and detector by value.
template <typename O>
Slam(O) -> Slam<O, RadiusLoopDetector>;
template <typename O, typename D>
Slam(O, D) -> Slam<O, D>;
template <typename O, typename D>
Slam(O, D, const SlamConfig&) -> Slam<O, D>;

}  // namespace semlio
