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
///              random walk and the front end's pose (degenerate directions
///              of the scan-to-map solve get no information) -> optimise.
///
/// Start-up: the first frames run lidar-only (constant velocity) until
/// `init.min_frames` tracked poses exist; initialize_inertial() then gives
/// gravity (in the map frame = the first lidar frame), the gyro bias and the
/// velocity, without requiring standstill; on failure it is retried on the
/// next frames over a sliding window of the latest poses.
///
/// Frames and time: the graph lives in the front end's map frame; states are
/// the IMU's (T_map_imu = T_map_lidar * T_imu_lidar^-1). Scan stamps are sweep
/// starts in the lidar clock; t_imu = t_lidar + imu_time_offset_s. Push IMU
/// samples up to the sweep END (stamp + sweep_period_s) before process() when
/// deskewing, up to the stamp otherwise.
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
/// front end is copyable, and otherwise keeps its first map. Scans without per-point times
/// get them from the azimuth (assign_times_from_azimuth, KITTI convention).
/// Not thread-safe: one instance per sensor stream.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

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
#include <semlio/imu/deskew.hpp>
#include <semlio/imu/imu_buffer.hpp>
#include <semlio/imu/imu_factor.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/imu/inertial_init.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/pipeline/odometry.hpp>

namespace semlio {

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
  double init_velocity_sigma_mps = 0.2;    ///< prior on the first state's velocity [m/s]
  double init_gyro_bias_sigma_radps = 1e-3;   ///< prior on the gyro bias after initialisation [rad/s]
  double init_accel_bias_sigma_mps2 = 0.1;    ///< prior on the accel bias after initialisation [m/s^2]
  double reanchor_velocity_sigma_mps = 1.0;   ///< velocity prior after an IMU fallback [m/s]
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
};

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

  // Re-runs a fresh front end on the first two sweeps deskewed with the
  // motion estimated between them (see the file comment).
  void restart_deskewed() {
    if (make_ && first_scans_.size() == 2) {
      const SE3d motion = T_prev_lidar_.inverse() * T_last_lidar_;
      odometry_.reset();
      odometry_.emplace(make_());
      make_ = nullptr;
      LidarInertialReport dummy;
      for (Scan& sc : first_scans_) {
        deskew_cv(sc, motion, dummy);
        odometry_->process(sc);
      }
    }
    first_scans_.clear();
  }

  void process_initializing(Scan& scan, LidarInertialReport& rep) {
    if (config_.deskew && frames_ < 2 && make_) first_scans_.push_back(scan);
    if (config_.deskew && frames_ == 2) restart_deskewed();
    deskew_cv(scan, cv_motion(scan.stamp_s), rep);
    rep.frame = odometry_->process(scan);
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
    anchor(scan.stamp_s + config_.imu_time_offset_s, r.states.back(), r.bias, sigma, rep);
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

  // Information of the front end's pose in the IMU tangent: diagonal sigmas,
  // nothing along the solve's degenerate directions (those were copied from
  // the prediction, i.e. from the IMU itself).
  [[nodiscard]] Eigen::Matrix<double, 6, 6> pose_information(const FrameReport& f) const {
    using Matrix6 = Eigen::Matrix<double, 6, 6>;
    Eigen::Matrix<double, 6, 1> d;
    d << Eigen::Vector3d::Constant(1.0 / (config_.lidar_position_sigma_m * config_.lidar_position_sigma_m)),
        Eigen::Vector3d::Constant(1.0 / (config_.lidar_rotation_sigma_rad * config_.lidar_rotation_sigma_rad));
    Matrix6 info = d.asDiagonal();
    if (f.solve.degenerate_directions > 0 && f.solve.eigenvectors.allFinite()) {
      Matrix6 P = Matrix6::Identity();
      for (int k = 0; k < std::min(f.solve.degenerate_directions, 6); ++k) {
        const Eigen::Matrix<double, 6, 1> v = f.solve.eigenvectors.col(k).normalized();
        P -= v * v.transpose();
      }
      info = P.transpose() * info * P;
    }
    // xi_imu = Ad(T_imu_lidar) xi_lidar: Omega_imu = A^-T Omega_lidar A^-1.
    const Matrix6 A_inv = T_lidar_imu_.adjoint();
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
        ensure_times(scan);
        try {
          ImuDeskew d({.target = DeskewTarget::kStart,
                       .frame_period_s = config_.frame_period_s,
                       .sweep_period_s = config_.sweep_period_s,
                       .T_imu_lidar = config_.T_imu_lidar,
                       .imu_time_offset_s = config_.imu_time_offset_s,
                       .max_gap_s = config_.imu.max_gap_s});
          d.set_imu(buffer_.samples());
          d.set_bias(last.bias);
          const Eigen::Matrix3d R_map_lidar = prior->rotation();
          const std::span<const ImuSample> s = buffer_.samples();
          Eigen::Vector3d w_imu = s.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(s.back().gyro_radps);
          for (const ImuSample& x : s) {  // rate at the sweep start
            if (x.stamp_s >= t_imu) {
              w_imu = x.gyro_radps;
              break;
            }
          }
          w_imu -= last.bias.gyro_radps;
          const Eigen::Vector3d v_lidar_map =
              predicted->v_world_mps +
              predicted->R_world_imu.matrix() * w_imu.cross(config_.T_imu_lidar.translation());
          d.set_motion(R_map_lidar.transpose() * v_lidar_map, R_map_lidar.transpose() * gravity_map_);
          d.deskew(scan, T_prev_current);
          rep.deskew = DeskewSource::kImu;
          done = true;
        } catch (const ValueError& e) {
          if (rep.imu_issue.empty()) rep.imu_issue = e.what();
        }
      }
      if (!done) deskew_cv(scan, T_prev_current, rep);
    }

    rep.frame = odometry_->process(scan, prior);
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
};

/// Deduction guide: a factory gives the front end's type.
template <typename Make>
  requires std::invocable<Make&>
LidarInertialOdometry(Make, const LidarInertialConfig&) -> LidarInertialOdometry<std::invoke_result_t<Make&>>;

}  // namespace semlio
