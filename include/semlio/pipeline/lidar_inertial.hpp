#pragma once
/// \file
/// LidarInertialOdometry<OdometryT>: the lidar front end (Odometry, e.g. from
/// pipeline/presets.hpp) driven by an IMU (METHOD.md steps 1, 2 and the IMU
/// part of 9):
///
///   per scan:  preintegrate the IMU from the last optimised state to the
///              scan's stamp (Forster) -> predicted pose = the front end's
///              initial guess (Odometry::process's prior) -> optional IMU
///              deskew of the sweep -> scan-to-map odometry -> new state in a
///              sliding-window inertial graph with the IMU factor, the bias
///              random walk and the front end's pose -> optimise. The
///              pose's information follows the scan-to-map Hessian
///              (lidar_pose_information(): weakly constrained directions,
///              e.g. along a straight road, get little and flagged
///              degenerate ones none), so the IMU carries those directions.
///
/// Start-up: the first frames run lidar-only (constant velocity) until
/// `init.min_frames` tracked poses exist; initialize_inertial() then gives
/// gravity (in the map frame = the first lidar frame), the gyro bias and the
/// velocity, without requiring standstill; on failure it is retried on the
/// next frames over a sliding window of the latest poses.
///
/// Frames and time: the graph lives in the front end's map frame; states are
/// the IMU's (T_map_imu = T_map_lidar * T_imu_lidar^-1). Scan stamps are sweep
/// starts in the lidar clock; t_imu = t_lidar + imu_time_offset_s. Before
/// process(), push the IMU samples up to the sweep END (stamp +
/// sweep_period_s) when deskewing, up to the stamp otherwise, AND the first
/// sample after that time: prediction and deskew interpolate between
/// samples, so a sweep is covered only by samples on both sides of it (a
/// 10 Hz IMU such as KITTI raw's OXTS has its next one up to 0.1 s later;
/// semlio_run and semlio_lio wait for it, as an online system would).
///
/// IMU trouble is never a crash. push_imu() rejects non-finite samples and
/// samples not after the previous one (counted, last reason kept). When the
/// samples do not cover the frame, go backwards or have a gap above max_gap_s,
/// that frame falls back to the front end's constant-velocity prediction (and
/// constant-velocity deskew) and the report says so (`imu_fallback`, reason in
/// `imu_issue`); the inertial chain is then re-anchored at that frame (pose
/// from the lidar, velocity from the lidar displacement, bias kept).
///
/// Deskew: with `deskew` on, the LIO corrects each sweep to its start before
/// the front end sees it (ImuDeskew with the state's velocity and gravity, so
/// the accelerometer is integrated too; constant-velocity deskew while
/// initialising or on IMU trouble). The front end itself must then not deskew
/// again (the presets build it with NoDeskew). The first two sweeps have no
/// motion estimate yet and enter the front end's map distorted, which would
/// bias every later (deskewed) sweep against that map; so at the third frame
/// the LIO restarts a fresh front end on the first two sweeps deskewed with
/// the motion estimated between them. That needs a way to build a fresh front
/// end: construct the LIO from a factory (a callable returning the front end,
/// e.g. `[&] { return make_baseline_odometry(ScanLabels{}, settings); }`);
/// constructed from a front end object, the LIO restarts only when that
/// front end is copyable, and otherwise keeps its first map. Scans without
/// per-point times get them from the azimuth with config.point_times
/// (assign_times_from_azimuth; default KITTI raw: clockwise from the front;
/// the simulator's sweeps start facing backwards: start_azimuth_rad = pi --
/// a wrong start misplaces half of each sweep by half a sweep's motion).
///
/// Weak directions (a straight road's along-track axis). Build the front end
/// with solver.reset_weak_directions on (GaussNewtonConfig): the directions
/// the solver's relative test flags then stay at the prediction -- the IMU's,
/// or the velocity hint's while initialising -- and, with the default
/// DegenerateInformation::kNone, the graph takes no lidar information there.
/// Left to the lidar, the along-road solution on the simulated highway comes
/// out ~5 % short per frame (ring patterns on flat ground pull it back);
/// initialised from those poses, gravity was tilted 4.1 deg along the road
/// (0.05 deg with the reset). What stays unobservable: with no lidar
/// information along the road and no velocity measurement, a tilt of the
/// front end's map (its pitch drifts ~0.4 deg over 500 m there) is
/// indistinguishable from an along-road acceleration (g * tilt), so the
/// along-road error still grows with time squared; velocity_factors (INS
/// velocity on every state) removes that, at the price of no longer being
/// lidar-inertial alone. The reset applies per frame (Odometry::process's
/// WeakDirectionReset): to frames with an IMU or INS prior, and to sweeps
/// deskewed with the constant-velocity motion; not to the constant-velocity
/// start-up frames of scans that need no deskew (30-frame urban drive,
/// undistorted: 0.14 m worst position error, 1.91 m with the reset there).
///
/// Not thread-safe: one instance per sensor stream.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>

#include <cmath>
#include <concepts>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/graph/inertial_graph.hpp>
#include <semlio/graph/keyframe_inertial_graph.hpp>
#include <semlio/imu/deskew.hpp>
#include <semlio/imu/imu_buffer.hpp>
#include <semlio/imu/imu_factor.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/imu/inertial_init.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>
#include <semlio/pipeline/odometry.hpp>
#include <semlio/solve/gauss_newton.hpp>

namespace semlio {

/// How the front end's pose enters the inertial graph.
enum class LidarInformation {
  /// Diagonal sigmas (lidar_position_sigma_m, lidar_rotation_sigma_rad), with
  /// nothing along the directions the solve flagged degenerate.
  kDiagonal,
  /// The scan-to-map Hessian scaled by 1 / lidar_residual_sigma_m^2 and capped
  /// by the diagonal sigmas, per direction (lidar_pose_information()): weakly
  /// constrained directions (a straight road's along-track axis, flagged
  /// degenerate or not) get little information, so the IMU carries them.
  kHessian,
};

/// What the front end's pose tells the inertial graph along the directions
/// its solve flagged degenerate (SolveReport::degenerate_directions).
enum class DegenerateInformation {
  /// None along every flagged direction (the absolute and the relative test).
  kNone,
  /// None only along the directions the solver froze at the prediction (its
  /// step remapping, eigenvalue below GaussNewtonConfig::degeneracy_threshold:
  /// the solution there is the IMU's own prediction and would count twice);
  /// directions flagged only by the relative test (degeneracy_ratio, a report
  /// that does not change the solution) keep the Hessian's information.
  kRemappedOnly,
};

/// Settings of LidarInertialOdometry. Defaults: the simulator's IMU, KITTI's
/// 10 Hz lidar.
struct LidarInertialConfig {
  SE3d T_imu_lidar = SE3d();         ///< lidar -> IMU extrinsic (calib.txt Tr_imu_velo)
  double imu_time_offset_s = 0.0;    ///< t_imu = t_lidar + offset [s]
  /// Noise densities, max gap and |g| (the norm of gravity_world_mps2; its
  /// direction in the map frame comes from the initialisation).
  PreintegrationConfig imu{};
  InertialInitConfig init{};         ///< initialisation while moving
  InertialGraphConfig graph{};       ///< sliding window (10 states by default)
  double lidar_position_sigma_m = 0.05;    ///< front-end pose noise, translation (1 sigma) [m]
  double lidar_rotation_sigma_rad = 0.005; ///< front-end pose noise, rotation (1 sigma) [rad]
  /// Shape of the front end's pose information (see LidarInformation).
  LidarInformation lidar_information = LidarInformation::kHessian;
  /// Information along the directions the front end flagged degenerate.
  DegenerateInformation degenerate_information = DegenerateInformation::kNone;
  /// Residual noise that turns the front end's Hessian J^T W J into an
  /// information (kHessian): H / sigma^2, then capped by the diagonal sigmas
  /// above. Larger than a single point's noise because the residuals are
  /// correlated (shared map planes) [m].
  double lidar_residual_sigma_m = 0.5;
  double init_velocity_sigma_mps = 0.2;    ///< prior on the first state's velocity [m/s]
  double init_gyro_bias_sigma_radps = 1e-3;   ///< prior on the gyro bias after initialisation [rad/s]
  double init_accel_bias_sigma_mps2 = 0.1;    ///< prior on the accel bias after initialisation [m/s^2]
  double reanchor_velocity_sigma_mps = 1.0;   ///< velocity prior after an IMU fallback [m/s]
  /// Pushed velocities (push_velocity) also become velocity factors on every
  /// state after initialisation: INS-aided, no longer lidar-inertial alone
  /// (off: they only guide the start-up).
  bool velocity_factors = false;
  double velocity_factor_sigma_mps = 0.1;  ///< noise of such a velocity, per axis (1 sigma) [m/s]
  bool deskew = false;               ///< deskew sweeps (raw data, --distortion on); not for KITTI odometry scans
  double sweep_period_s = 0.1;       ///< one sweep [s]
  double frame_period_s = 0.1;       ///< nominal time between scans (constant-velocity deskew) [s]
  PointTimeConfig point_times{};     ///< per-point times for scans without them (deskew only)
};

/// Where a frame's initial guess came from.
enum class PredictionSource {
  kConstantVelocity,  ///< the front end's constant-velocity model (initialising, or IMU fallback)
  kImu,               ///< IMU preintegration from the last optimised state
};

/// How a sweep was deskewed.
enum class DeskewSource { kNone, kConstantVelocity, kImu };

/// Name of a prediction source, for reports.
constexpr const char* to_string(PredictionSource s) noexcept {
  return s == PredictionSource::kImu ? "imu" : "constant_velocity";
}
/// Name of a deskew source, for reports.
constexpr const char* to_string(DeskewSource s) noexcept {
  switch (s) {
    case DeskewSource::kNone: return "none";
    case DeskewSource::kConstantVelocity: return "constant_velocity";
    case DeskewSource::kImu: return "imu";
  }
  return "unknown";
}

/// Everything LidarInertialOdometry::process reports about one frame.
struct LidarInertialReport {
  FrameReport frame;            ///< the front end's report (its pose is the scan-to-map result)
  std::optional<SE3d> T_map_lidar_prior;  ///< initial guess given to the front end (IMU or velocity hint), if any
  SE3d T_map_lidar;             ///< lidar pose after the inertial optimisation (= frame's while initialising)
  bool initialized = false;     ///< inertial state available (after this frame)
  PredictionSource prediction = PredictionSource::kConstantVelocity;  ///< source of the initial guess
  DeskewSource deskew = DeskewSource::kNone;                          ///< how the sweep was deskewed
  bool imu_fallback = false;    ///< IMU unusable for this frame (after initialisation): lidar-only prediction
  std::string imu_issue;        ///< why (find_imu_range's message), empty otherwise
  std::optional<InertialInitStatus> init_status;  ///< set on frames where initialisation was attempted
  std::optional<InertialSolveStatus> solve_status;  ///< set on frames where the graph was optimised
  NavState state;               ///< IMU state in the map frame (valid when initialized)
  ImuBias bias;                 ///< IMU bias (valid when initialized)
  Eigen::Vector3d gravity_map_mps2 = Eigen::Vector3d::Zero();  ///< gravity in the map frame (when initialized)
  std::size_t imu_rejected = 0; ///< push_imu rejections so far
  bool velocity_factor = false; ///< a pushed velocity entered the graph for this frame (config.velocity_factors)
};

/// Information (6x6, lidar tangent [rho; phi], right perturbation) of a
/// scan-to-map pose for the inertial graph. Directions the solve flagged
/// degenerate get none in either mode: the remapped solve copied the
/// prediction (the IMU's own) there. kDiagonal: the configured sigmas.
/// kHessian: with D = diag(1/sigma_p, 1/sigma_r), the whitened Hessian
/// M = D^-1 (H / sigma_res^2) D^-1 = U diag(mu) U^T gives
/// Omega = D U diag(mu / (1 + mu)) U^T D: the diagonal sigmas where the scan
/// constrains the pose well (mu >> 1), the scan's own (small) information
/// where it does not. A non-finite Hessian falls back to kDiagonal. With
/// c.degenerate_information == kRemappedOnly only the flagged directions whose
/// eigenvalue is below `remapped_below` (the solver's absolute threshold) get
/// none.
inline Eigen::Matrix<double, 6, 6> lidar_pose_information(const SolveReport& solve, const LidarInertialConfig& c,
                                                          double remapped_below = 100.0) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  Vector6 d;  // sqrt of the diagonal information
  d << Eigen::Vector3d::Constant(1.0 / c.lidar_position_sigma_m), Eigen::Vector3d::Constant(1.0 / c.lidar_rotation_sigma_rad);
  Matrix6 info = d.cwiseAbs2().asDiagonal();
  if (c.lidar_information == LidarInformation::kHessian && solve.hessian.allFinite() &&
      solve.hessian.diagonal().maxCoeff() > 0.0) {
    const Vector6 d_inv = d.cwiseInverse();
    const Matrix6 M = d_inv.asDiagonal() * (solve.hessian / (c.lidar_residual_sigma_m * c.lidar_residual_sigma_m)) *
                      d_inv.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Matrix6> es(0.5 * (M + M.transpose()));
    Vector6 mu = es.eigenvalues().cwiseMax(0.0);
    for (int k = 0; k < 6; ++k) mu[k] = mu[k] / (1.0 + mu[k]);
    info = d.asDiagonal() * es.eigenvectors() * mu.asDiagonal() * es.eigenvectors().transpose() * d.asDiagonal();
  }
  if (solve.degenerate_directions > 0 && solve.eigenvectors.allFinite()) {
    Matrix6 P = Matrix6::Identity();
    for (int k = 0; k < std::min(solve.degenerate_directions, 6); ++k) {
      if (c.degenerate_information == DegenerateInformation::kRemappedOnly && !(solve.eigenvalues[k] < remapped_below)) {
        continue;
      }
      const Vector6 v = solve.eigenvectors.col(k).normalized();
      P -= v * v.transpose();
    }
    info = P.transpose() * info * P;
  }
  return info;
}

/// Deskews a sweep in place to its start (the lidar frame at scan.stamp_s)
/// from a lidar-inertial state: `x_start` is the IMU state at the sweep start
/// (t_imu = stamp + c.imu_time_offset_s) in the map frame, `gravity_map_mps2`
/// gravity there; the gyro gives the rotation, the accelerometer (bias removed,
/// lever arm included) the translation from the lidar's velocity at the start
/// (ImuDeskew::set_motion). Per-point times: the scan's, else from the azimuth
/// (c.point_times). ValueError when the samples do not cover the sweep, go
/// backwards or have a gap above c.imu.max_gap_s.
inline void deskew_sweep_imu(Scan& scan, std::span<const ImuSample> imu, const NavState& x_start, const ImuBias& bias,
                             const Eigen::Vector3d& gravity_map_mps2, const LidarInertialConfig& c) {
  if (scan.empty()) return;
  if (!scan.has_times()) assign_times_from_azimuth(scan, c.point_times);
  ImuDeskew d({.target = DeskewTarget::kStart,
               .frame_period_s = c.frame_period_s,
               .sweep_period_s = c.sweep_period_s,
               .T_imu_lidar = c.T_imu_lidar,
               .imu_time_offset_s = c.imu_time_offset_s,
               .max_gap_s = c.imu.max_gap_s});
  d.set_imu(imu);
  d.set_bias(bias);
  const double t_imu = scan.stamp_s + c.imu_time_offset_s;
  // Angular rate at the sweep start (linear between samples), bias removed.
  Eigen::Vector3d w_imu = imu.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(imu.back().gyro_radps);
  for (std::size_t k = 0; k < imu.size(); ++k) {
    if (imu[k].stamp_s >= t_imu) {
      w_imu = k > 0 ? Eigen::Vector3d(interpolate_imu(imu[k - 1], imu[k], t_imu).gyro_radps)
                    : Eigen::Vector3d(imu[k].gyro_radps);
      break;
    }
  }
  w_imu -= bias.gyro_radps;
  // Lidar velocity: v_L = v_I + R_world_imu (w x r), r = lidar origin in the IMU frame.
  const Eigen::Vector3d v_lidar_map =
      x_start.v_world_mps + x_start.R_world_imu.matrix() * w_imu.cross(c.T_imu_lidar.translation());
  const Eigen::Matrix3d R_map_lidar = (x_start.pose() * c.T_imu_lidar).rotation();
  d.set_motion(R_map_lidar.transpose() * v_lidar_map, R_map_lidar.transpose() * gravity_map_mps2);
  d.deskew(scan, SE3d());
}

/// Lidar-inertial odometry around a lidar front end (see the file comment).
template <typename OdometryT>
class LidarInertialOdometry {
 public:
  using Config = LidarInertialConfig;

  /// Takes the front end by value; validates the settings (ConfigError).
  LidarInertialOdometry(OdometryT odometry, const Config& config) : config_(config), graph_(config.graph) {
    if constexpr (std::is_copy_constructible_v<OdometryT>) {
      if (config_.deskew) make_ = [fresh = odometry]() { return fresh; };  // before any scan: nothing to dangle
    }
    odometry_.emplace(std::move(odometry));
    validate();
  }

  /// Builds the front end with `make` (called again for the deskew restart).
  template <typename Make>
    requires std::is_invocable_r_v<OdometryT, Make&>
  LidarInertialOdometry(Make make, const Config& config) : config_(config), graph_(config.graph) {
    odometry_.emplace(make());
    if (config_.deskew) make_ = std::move(make);
    validate();
  }

 private:
  void validate() {
    config_.imu.validate();
    if (!std::isfinite(config_.imu_time_offset_s)) {
      throw ConfigError("LidarInertialConfig.imu_time_offset_s is not finite");
    }
    const auto positive = [](double v, const char* field) {
      if (!(v > 0.0) || !std::isfinite(v)) {
        throw ConfigError(std::string("LidarInertialConfig.") + field + " must be > 0, got " + std::to_string(v));
      }
    };
    positive(config_.lidar_position_sigma_m, "lidar_position_sigma_m");
    positive(config_.lidar_rotation_sigma_rad, "lidar_rotation_sigma_rad");
    positive(config_.init_velocity_sigma_mps, "init_velocity_sigma_mps");
    positive(config_.init_gyro_bias_sigma_radps, "init_gyro_bias_sigma_radps");
    positive(config_.init_accel_bias_sigma_mps2, "init_accel_bias_sigma_mps2");
    positive(config_.reanchor_velocity_sigma_mps, "reanchor_velocity_sigma_mps");
    positive(config_.velocity_factor_sigma_mps, "velocity_factor_sigma_mps");
    positive(config_.lidar_residual_sigma_m, "lidar_residual_sigma_m");
    positive(config_.sweep_period_s, "sweep_period_s");
    positive(config_.frame_period_s, "frame_period_s");
    if (!(config_.imu.gravity_world_mps2.norm() > 0.0)) {
      throw ConfigError("LidarInertialConfig.imu.gravity_world_mps2 must be nonzero");
    }
    T_lidar_imu_ = config_.T_imu_lidar.inverse();
  }

 public:

  /// Adds one IMU sample (IMU frame and clock). Returns false and counts it
  /// when it is rejected: not finite, or not after the previous sample.
  bool push_imu(const ImuSample& sample) {
    try {
      buffer_.push(sample);
      return true;
    } catch (const ValueError& e) {
      ++imu_rejected_;
      last_push_issue_ = e.what();
      return false;
    }
  }

  /// Adds a velocity measurement of the IMU, in the IMU frame at IMU time
  /// stamp_s (KITTI raw OXTS: vf, vl, vu rotated by roll and pitch; see
  /// oxts_velocities in examples/common/imu_oxts.hpp). Used only while
  /// initialising: the front end's initial guess is then this velocity with
  /// the gyro's rotation instead of its constant-velocity model, and the
  /// initial state takes it as its velocity. On a road that does not
  /// constrain the along-track motion (a straight highway entered at cruise
  /// speed) it is the only source of that motion -- neither the lidar nor the
  /// IMU (no acceleration) observes it. With config.velocity_factors also a
  /// velocity factor on the state nearest to it (within half a frame period)
  /// after initialisation. Returns false for a non-finite one or one not
  /// after the previous.
  bool push_velocity(double stamp_s, const Eigen::Vector3d& v_imu_mps) {
    if (!std::isfinite(stamp_s) || !v_imu_mps.allFinite()) return false;
    if (!velocities_.empty() && !(stamp_s > velocities_.back().first)) return false;
    velocities_.emplace_back(stamp_s, v_imu_mps);
    return true;
  }

  /// Processes one scan (see the file comment). The scan is consumed as the
  /// front end's working buffer.
  LidarInertialReport process(Scan& scan) {
    LidarInertialReport rep;
    const double t_imu = scan.stamp_s + config_.imu_time_offset_s;
    if (!initialized_) {
      process_initializing(scan, rep);
    } else {
      process_inertial(scan, t_imu, rep);
    }
    rep.initialized = initialized_;
    rep.imu_rejected = imu_rejected_;
    if (initialized_ && !graph_.empty()) {
      const InertialNode& x = graph_.node(graph_.last_id());
      rep.state = x.state;
      rep.bias = x.bias;
      rep.gravity_map_mps2 = gravity_map_;
    }
    if (rep.frame.status != OdometryStatus::kTimeWentBackwards) {
      T_last_lidar_ = rep.T_map_lidar;
      prev_stamp_s_ = last_stamp_s_;
      last_stamp_s_ = scan.stamp_s;
      ++frames_;
    }
    trim_buffer();
    return rep;
  }

  /// True once gravity, bias and velocity are initialised.
  [[nodiscard]] bool initialized() const noexcept { return initialized_; }
  /// The front end.
  [[nodiscard]] const OdometryT& odometry() const noexcept { return *odometry_; }
  /// The inertial graph (states in the map frame).
  [[nodiscard]] const InertialGraph& graph() const noexcept { return graph_; }
  /// Gravity in the map frame (zero before initialisation).
  [[nodiscard]] const Eigen::Vector3d& gravity_map_mps2() const noexcept { return gravity_map_; }
  /// Rejected IMU samples so far and the last reason.
  [[nodiscard]] std::size_t imu_rejected() const noexcept { return imu_rejected_; }
  /// Why the last IMU sample was rejected (empty when none was).
  [[nodiscard]] const std::string& last_imu_rejection() const noexcept { return last_push_issue_; }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  static bool tracked(OdometryStatus s) {
    return s == OdometryStatus::kInitialized || s == OdometryStatus::kTracked || s == OdometryStatus::kDegenerate;
  }

  // Constant-velocity guess of T_prev_current from the last two LIO poses.
  [[nodiscard]] SE3d cv_motion(double stamp_s) const {
    if (frames_ < 2 || !(last_stamp_s_ - prev_stamp_s_ > 1e-6)) return SE3d();
    const double scale = std::min((stamp_s - last_stamp_s_) / (last_stamp_s_ - prev_stamp_s_), 3.0);
    return SE3d::exp(std::max(scale, 0.0) * (T_prev_lidar_.inverse() * T_last_lidar_).log());
  }

  void ensure_times(Scan& scan) const {
    if (!scan.has_times() && !scan.empty()) assign_times_from_azimuth(scan, config_.point_times);
  }

  void deskew_cv(Scan& scan, const SE3d& T_prev_current, LidarInertialReport& rep) const {
    if (!config_.deskew || scan.empty()) return;
    ensure_times(scan);
    const ConstantVelocityDeskew d({.target = DeskewTarget::kStart,
                                    .frame_period_s = config_.frame_period_s,
                                    .sweep_period_s = config_.sweep_period_s});
    d.deskew(scan, T_prev_current);
    rep.deskew = DeskewSource::kConstantVelocity;
  }

  // The front end on one (deskewed) sweep. The weak-direction reset (when
  // the front end has it on) applies to frames with a prior and to sweeps
  // deskewed with the constant-velocity motion (see Odometry::process).
  FrameReport process_front_end(Scan& scan, const std::optional<SE3d>& prior, const LidarInertialReport& rep) {
    if constexpr (requires(OdometryT& o) { o.process(scan, prior, WeakDirectionReset::kAlways); }) {
      const WeakDirectionReset reset = rep.deskew == DeskewSource::kConstantVelocity ? WeakDirectionReset::kAlways
                                                                                     : WeakDirectionReset::kWithPrior;
      return odometry_->process(scan, prior, reset);
    } else {
      return odometry_->process(scan, prior);
    }
  }

  // Re-runs a fresh front end on the first two sweeps deskewed with the
  // motion estimated between them (see the file comment).
  void restart_deskewed() {
    if (make_ && first_scans_.size() == 2) {
      const SE3d motion = T_prev_lidar_.inverse() * T_last_lidar_;
      odometry_.reset();
      odometry_.emplace(make_());
      make_ = nullptr;
      LidarInertialReport dummy;
      for (std::size_t k = 0; k < first_scans_.size(); ++k) {
        Scan& sc = first_scans_[k];
        deskew_cv(sc, motion, dummy);
        // The second sweep starts from where it was tracked (a velocity hint may have placed it).
        process_front_end(sc, k == 1 ? std::optional<SE3d>(T_last_lidar_) : std::nullopt, dummy);
      }
    }
    first_scans_.clear();
  }

  // The pushed velocity (IMU frame) nearest to IMU time t, within max_dt_s.
  [[nodiscard]] std::optional<Eigen::Vector3d> velocity_near(double t_imu, double max_dt_s = 0.2) const {
    if (velocities_.empty()) return std::nullopt;
    const auto* best = &velocities_.front();
    for (const auto& v : velocities_) {
      if (std::abs(v.first - t_imu) < std::abs(best->first - t_imu)) best = &v;
    }
    if (std::abs(best->first - t_imu) > max_dt_s) return std::nullopt;
    return best->second;
  }

  // Lidar motion T_prev_current from the velocity measurement nearest to the
  // previous scan (within 0.2 s) and the gyro's rotation since then; nullopt
  // without one. At the first scan: the motion over one frame period ahead.
  [[nodiscard]] std::optional<SE3d> velocity_motion(double stamp_s) const {
    if (velocities_.empty()) return std::nullopt;
    const double t1 = stamp_s + config_.imu_time_offset_s;
    const double t0 = frames_ > 0 && stamp_s - last_stamp_s_ > 1e-6 ? last_stamp_s_ + config_.imu_time_offset_s
                                                                    : t1 - config_.frame_period_s;
    const std::optional<Eigen::Vector3d> v_imu = velocity_near(t0);
    if (!v_imu) return std::nullopt;
    // Rotation: gyro (no bias known yet) over [t0, t1], rectangle rule per sample interval.
    SO3d R;
    const std::span<const ImuSample> s = buffer_.samples();
    for (std::size_t k = 0; k + 1 < s.size(); ++k) {
      const double a = std::max(s[k].stamp_s, t0);
      const double b = std::min(s[k + 1].stamp_s, t1);
      if (b > a) R = R * SO3d::exp(0.5 * (s[k].gyro_radps + s[k + 1].gyro_radps) * (b - a));
    }
    const SE3d T_imu_prev_cur(R, *v_imu * (t1 - t0));
    return T_lidar_imu_ * T_imu_prev_cur * config_.T_imu_lidar;
  }

  void process_initializing(Scan& scan, LidarInertialReport& rep) {
    if (config_.deskew && frames_ < 2 && make_) first_scans_.push_back(scan);
    if (config_.deskew && frames_ == 2) restart_deskewed();
    const std::optional<SE3d> hint = velocity_motion(scan.stamp_s);
    deskew_cv(scan, hint ? *hint : cv_motion(scan.stamp_s), rep);
    if (hint && frames_ > 0) rep.T_map_lidar_prior = T_last_lidar_ * *hint;
    rep.frame = process_front_end(scan, rep.T_map_lidar_prior, rep);
    rep.T_map_lidar = rep.frame.T_map_lidar;
    if (rep.frame.status == OdometryStatus::kTimeWentBackwards) return;
    T_prev_lidar_ = T_last_lidar_;
    if (!tracked(rep.frame.status)) {
      window_stamps_.clear();
      window_poses_.clear();
      return;
    }
    window_stamps_.push_back(scan.stamp_s);
    window_poses_.push_back(rep.frame.T_map_lidar);
    const std::size_t need = std::max<std::size_t>(3, config_.init.min_frames);
    while (window_stamps_.size() > need) {
      window_stamps_.erase(window_stamps_.begin());
      window_poses_.erase(window_poses_.begin());
    }
    if (window_stamps_.size() < need) return;
    const InertialInitResult r = initialize_inertial(window_stamps_, window_poses_, buffer_.samples(),
                                                     config_.T_imu_lidar, config_.imu_time_offset_s, config_.imu,
                                                     config_.init);
    rep.init_status = r.status;
    if (!r.ok()) {
      rep.imu_issue = r.message;
      return;
    }
    gravity_map_ = r.gravity_map_mps2;
    PreintegrationConfig pc = config_.imu;
    pc.gravity_world_mps2 = gravity_map_;
    pim_ = ImuPreintegration(pc);
    Vector15d sigma;
    sigma << Eigen::Vector3d::Constant(config_.lidar_position_sigma_m),
        Eigen::Vector3d::Constant(config_.lidar_rotation_sigma_rad), Eigen::Vector3d::Constant(config_.init_velocity_sigma_mps),
        Eigen::Vector3d::Constant(config_.init_gyro_bias_sigma_radps),
        Eigen::Vector3d::Constant(config_.init_accel_bias_sigma_mps2);
    NavState x0 = r.states.back();
    // A velocity measurement at this scan (push_velocity) replaces the
    // estimate from the lidar poses, which is biased where the lidar does
    // not observe the along-track motion.
    if (const auto v = velocity_near(scan.stamp_s + config_.imu_time_offset_s)) {
      x0.v_world_mps = x0.R_world_imu.matrix() * *v;
    }
    anchor(scan.stamp_s + config_.imu_time_offset_s, x0, r.bias, sigma, rep);
    initialized_ = true;
  }

  // Starts a new graph at one state with a prior (sigmas in tangent order).
  void anchor(double t_imu, const NavState& x, const ImuBias& b, const Vector15d& sigma, LidarInertialReport& rep) {
    graph_ = InertialGraph(config_.graph);
    const InertialGraph::Id id = graph_.add_state(t_imu, x, b);
    const Matrix15d info = sigma.cwiseInverse().cwiseAbs2().asDiagonal();
    graph_.add_prior(id, x, b, info);
    rep.solve_status = graph_.optimize().status;
    rep.T_map_lidar = graph_.node(id).state.pose() * config_.T_imu_lidar;
  }

  // Information of the front end's pose in the IMU tangent.
  [[nodiscard]] Eigen::Matrix<double, 6, 6> pose_information(const FrameReport& f) const {
    double remapped_below = 100.0;
    if constexpr (requires(const OdometryT& o) { o.config().solver.degeneracy_threshold; }) {
      remapped_below = odometry_->config().solver.degeneracy_threshold;
    }
    const Eigen::Matrix<double, 6, 6> info = lidar_pose_information(f.solve, config_, remapped_below);
    // xi_imu = Ad(T_imu_lidar) xi_lidar: Omega_imu = A^-T Omega_lidar A^-1.
    const Eigen::Matrix<double, 6, 6> A_inv = T_lidar_imu_.adjoint();
    return A_inv.transpose() * info * A_inv;
  }

  void process_inertial(Scan& scan, double t_imu, LidarInertialReport& rep) {
    const InertialGraph::Id last_id = graph_.last_id();
    const InertialNode last = graph_.node(last_id);
    std::optional<NavState> predicted;
    try {
      pim_.integrate(buffer_.samples(), last.stamp_s, t_imu, last.bias);
      predicted = pim_.predict(last.state, last.bias);
      rep.prediction = PredictionSource::kImu;
    } catch (const ValueError& e) {
      rep.imu_fallback = true;
      rep.imu_issue = e.what();
    }
    std::optional<SE3d> prior;
    if (predicted) prior = predicted->pose() * config_.T_imu_lidar;

    // Deskew: IMU (accelerometer integrated from the predicted state), else constant velocity.
    if (config_.deskew && !scan.empty()) {
      const SE3d T_prev_current = prior ? T_last_lidar_.inverse() * *prior : cv_motion(scan.stamp_s);
      bool done = false;
      if (predicted) {
        try {
          deskew_sweep_imu(scan, buffer_.samples(), *predicted, last.bias, gravity_map_, config_);
          rep.deskew = DeskewSource::kImu;
          done = true;
        } catch (const ValueError& e) {
          if (rep.imu_issue.empty()) rep.imu_issue = e.what();
        }
      }
      if (!done) deskew_cv(scan, T_prev_current, rep);
    }

    rep.T_map_lidar_prior = prior;
    rep.frame = process_front_end(scan, prior, rep);
    rep.T_map_lidar = rep.frame.T_map_lidar;
    if (rep.frame.status == OdometryStatus::kTimeWentBackwards) return;
    T_prev_lidar_ = T_last_lidar_;

    if (!predicted) {
      // Re-anchor at this frame: lidar pose, velocity from the lidar displacement.
      const SE3d T_map_imu = rep.frame.T_map_lidar * T_lidar_imu_;
      NavState x;
      x.R_world_imu = T_map_imu.so3();
      x.p_world_m = T_map_imu.translation();
      const double dt = t_imu - last.stamp_s;
      x.v_world_mps = dt > 1e-3 ? Eigen::Vector3d((x.p_world_m - last.state.p_world_m) / dt) : last.state.v_world_mps;
      if (!x.v_world_mps.allFinite()) x.v_world_mps = last.state.v_world_mps;
      Vector15d sigma;
      sigma << Eigen::Vector3d::Constant(config_.lidar_position_sigma_m),
          Eigen::Vector3d::Constant(config_.lidar_rotation_sigma_rad),
          Eigen::Vector3d::Constant(config_.reanchor_velocity_sigma_mps),
          Eigen::Vector3d::Constant(config_.init_gyro_bias_sigma_radps),
          Eigen::Vector3d::Constant(config_.init_accel_bias_sigma_mps2);
      anchor(t_imu, x, last.bias, sigma, rep);
      return;
    }
    const InertialGraph::Id j = graph_.add_state(t_imu, *predicted, last.bias);
    graph_.add_imu(last_id, j, pim_);
    if (tracked(rep.frame.status)) {
      graph_.add_pose(j, rep.frame.T_map_lidar * T_lidar_imu_, pose_information(rep.frame));
    }
    if (config_.velocity_factors) {
      // INS velocity (IMU frame) rotated into the map with the predicted
      // attitude (held fixed: a prior on the velocity block only).
      if (const auto v = velocity_near(t_imu, 0.5 * config_.frame_period_s)) {
        NavState z = *predicted;
        z.v_world_mps = predicted->R_world_imu.matrix() * *v;
        Matrix15d info = Matrix15d::Zero();
        info.block<3, 3>(6, 6) = Eigen::Matrix3d::Identity() /
                                 (config_.velocity_factor_sigma_mps * config_.velocity_factor_sigma_mps);
        graph_.add_prior(j, z, last.bias, info);
        rep.velocity_factor = true;
      }
    }
    rep.solve_status = graph_.optimize().status;
    rep.T_map_lidar = graph_.node(j).state.pose() * config_.T_imu_lidar;
  }

  // Keeps the samples still needed: those covering the initialisation window
  // or the last state onwards.
  void trim_buffer() {
    double keep_from = 0.0;
    if (initialized_ && !graph_.empty()) {
      keep_from = graph_.node(graph_.last_id()).stamp_s;
    } else if (!window_stamps_.empty()) {
      keep_from = window_stamps_.front() + config_.imu_time_offset_s;
    } else {
      keep_from = last_stamp_s_ + config_.imu_time_offset_s;
    }
    buffer_.drop_before(keep_from - 0.5);
    while (!velocities_.empty() && velocities_.front().first < keep_from - 0.5) velocities_.erase(velocities_.begin());
  }

  Config config_;
  std::optional<OdometryT> odometry_;  // always engaged; optional so that it can be rebuilt
  InertialGraph graph_;
  ImuBuffer buffer_;
  ImuPreintegration pim_;
  SE3d T_lidar_imu_;
  Eigen::Vector3d gravity_map_ = Eigen::Vector3d::Zero();
  bool initialized_ = false;
  std::vector<double> window_stamps_;
  std::vector<SE3d> window_poses_;
  SE3d T_last_lidar_;
  SE3d T_prev_lidar_;
  double last_stamp_s_ = 0.0;
  double prev_stamp_s_ = 0.0;
  std::size_t frames_ = 0;
  std::size_t imu_rejected_ = 0;
  std::string last_push_issue_;
  std::function<OdometryT()> make_;  // builds a fresh front end for the deskew restart
  std::vector<Scan> first_scans_;   // the first two sweeps, kept for the restart
  std::vector<std::pair<double, Eigen::Vector3d>> velocities_;  // push_velocity: (IMU time, IMU-frame velocity)
};

/// Deduction guide: a factory gives the front end's type.
template <typename Make>
  requires std::invocable<Make&>
LidarInertialOdometry(Make, const LidarInertialConfig&) -> LidarInertialOdometry<std::invoke_result_t<Make&>>;

/// LidarInertialOdometry as the front end of the keyframe back end (Slam with
/// a KeyframeInertialGraph, pipeline/slam.hpp): process() returns the front
/// end's report with the LIO's optimised pose, and the back end reads the
/// inertial state of the last frame (inertial_state()) and preintegrates the
/// IMU over a keyframe interval (preintegrate()) from a copy of the samples
/// the LIO accepted, kept from the last keyframe on (drop_imu_before(); the
/// copy holds the samples since the oldest undropped time, ~1.5 kB per
/// 10 samples). Not thread-safe.
template <typename OdometryT>
class LidarInertialFrontEnd {
 public:
  /// The LIO from a front-end factory (or front end) and its settings.
  template <typename Make>
  LidarInertialFrontEnd(Make make, const LidarInertialConfig& config) : lio_(std::move(make), config) {}

  /// Feeds the LIO; an accepted sample is also kept for the back end's IMU factors.
  bool push_imu(const ImuSample& sample) {
    if (!lio_.push_imu(sample)) return false;
    try {
      buffer_.push(sample);  // the LIO accepted it: finite and after its previous one
    } catch (const ValueError&) {
      // Behind this copy's last sample (the LIO had dropped its own): skipped here only.
    }
    return true;
  }
  /// Feeds the LIO an INS velocity (LidarInertialOdometry::push_velocity).
  bool push_velocity(double stamp_s, const Eigen::Vector3d& v_imu_mps) { return lio_.push_velocity(stamp_s, v_imu_mps); }

  /// Runs the LIO on one scan; the prior is not used (the IMU predicts). The
  /// report's pose is the LIO's optimised one.
  FrameReport process(Scan& scan, const std::optional<SE3d>& /*T_map_lidar_prior*/ = std::nullopt) {
    last_ = lio_.process(scan);
    FrameReport f = last_.frame;
    f.T_map_lidar = last_.T_map_lidar;
    return f;
  }

  /// The front end's scan-to-map pose of the last frame, before the inertial
  /// fusion (Slam's between factors: the fused pose already holds the IMU).
  [[nodiscard]] const SE3d& registered_pose() const noexcept { return last_.frame.T_map_lidar; }
  /// Features of the last frame (the front end's).
  [[nodiscard]] const LoamFeatures& features() const { return lio_.odometry().features(); }
  /// Association-rank histogram of the front end.
  [[nodiscard]] const RankHistogram& rank_histogram() const { return lio_.odometry().rank_histogram(); }
  /// The LIO's report of the last frame.
  [[nodiscard]] const LidarInertialReport& last_report() const noexcept { return last_; }
  /// The LIO.
  [[nodiscard]] const LidarInertialOdometry<OdometryT>& lio() const noexcept { return lio_; }
  /// Lidar -> IMU extrinsic.
  [[nodiscard]] const SE3d& T_imu_lidar() const noexcept { return lio_.config().T_imu_lidar; }
  /// IMU time of a lidar stamp.
  [[nodiscard]] double imu_stamp_s(double lidar_stamp_s) const noexcept {
    return lidar_stamp_s + lio_.config().imu_time_offset_s;
  }
  /// Gravity in the LIO's map frame (zero before initialisation).
  [[nodiscard]] const Eigen::Vector3d& gravity_map_mps2() const noexcept { return lio_.gravity_map_mps2(); }

  /// IMU state of the last frame in the LIO's map frame, when the LIO is
  /// initialised and used the IMU for it (none while initialising or on an
  /// IMU fallback frame).
  [[nodiscard]] std::optional<KeyframeInertialNode> inertial_state() const {
    if (!last_.initialized || last_.imu_fallback || last_.frame.status == OdometryStatus::kTimeWentBackwards) {
      return std::nullopt;
    }
    return KeyframeInertialNode{imu_stamp_s(last_.frame.stamp_s), last_.state, last_.bias};
  }

  /// Preintegration over [t0_imu_s, t1_imu_s] at bias `bias` with gravity
  /// `gravity_mps2` (the graph's frame); none when the kept samples do not
  /// cover the interval, go backwards or have a gap (the back end then adds
  /// no IMU factor there).
  [[nodiscard]] std::optional<ImuPreintegration> preintegrate(double t0_imu_s, double t1_imu_s, const ImuBias& bias,
                                                              const Eigen::Vector3d& gravity_mps2) const {
    PreintegrationConfig c = lio_.config().imu;
    c.gravity_world_mps2 = gravity_mps2;
    ImuPreintegration pim(c);
    try {
      pim.integrate(buffer_.samples(), t0_imu_s, t1_imu_s, bias);
    } catch (const ValueError&) {
      return std::nullopt;
    }
    return pim;
  }

  /// Forgets the kept samples before IMU time t (minus 0.5 s of margin).
  void drop_imu_before(double t_imu_s) { buffer_.drop_before(t_imu_s - 0.5); }

 private:
  LidarInertialOdometry<OdometryT> lio_;
  ImuBuffer buffer_;
  LidarInertialReport last_;
};

/// Deduction guide: a factory gives the front end's type.
template <typename Make>
  requires std::invocable<Make&>
LidarInertialFrontEnd(Make, const LidarInertialConfig&) -> LidarInertialFrontEnd<std::invoke_result_t<Make&>>;

}  // namespace semlio
