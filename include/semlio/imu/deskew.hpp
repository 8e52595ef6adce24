#pragma once
/// \file
/// Per-point motion correction ("deskew") of a spinning-lidar sweep (METHOD.md
/// step 2): each point, measured in the lidar frame at its own firing time
/// stamp_s + times_s[i], is re-expressed in the lidar frame at the start (or
/// end) of the sweep: p_target = T_target_ti * p_i.
///
/// Three policies with NoDeskew's signature (pipeline/odometry.hpp), so the
/// odometry's deskew slot takes any:
/// - SweepDeskew: the presets' slot, configured at run time (off, or constant
///   velocity with per-point times from the scan or from the azimuth; KITTI
///   raw's time convention is documented in features/rings.hpp);
/// - ConstantVelocityDeskew: constant body twist; the motion over one sweep is
///   the predicted frame-to-frame motion scaled by sweep_period / frame_period
///   (both 0.1 s by default: a 10 Hz lidar whose sweeps follow back to back).
/// - ImuDeskew: rotation from the integrated gyro, translation from a constant
///   body-frame velocity (given, or the predicted motion's).
///
/// In the odometry (the deskewer is held by value, so feed ImuDeskew through
/// an ImuBuffer it references):
///   ImuBuffer imu;
///   Odometry odo(segmenter, associator, residuals, keyframes, config,
///                ImuDeskew(imu, {.T_imu_lidar = T_imu_velo}));
///   per sweep: imu.push(...) every sample up to the sweep end, odo.process(scan).
///
/// ConstantVelocityDeskew's and ImuDeskew's default target is the sweep
/// START: semlio stamps a scan with its sweep start (Scan::stamp_s) and the
/// simulator's ground truth is the pose there. SweepDeskew defaults to the
/// MIDDLE, which keeps the odometry's velocity feedback stable (see
/// SweepDeskewConfig); kEnd maps to the lidar frame at stamp_s + sweep_period_s.
///
/// ConstantVelocityDeskew and ImuDeskew need per-point times (Scan::times_s,
/// seconds since stamp_s, >= 0; features/rings.hpp fills them from the
/// azimuth for KITTI's .bin scans, SweepDeskew does so itself); deskewing a
/// scan without them, or with a negative or non-finite time, throws ValueError. IMU trouble (not covering the sweep, time going
/// backwards, gaps) is a ValueError too (imu_buffer.hpp), never a crash.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/imu/imu_buffer.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

namespace semlio {

/// A deskew policy: corrects a scan in place given the predicted motion
/// T_prev_current (lidar frame of the previous scan <- current scan).
template <typename D>
concept ScanDeskewer = requires(const D& d, Scan& scan, const SE3d& T) {
  { d.deskew(scan, T) } -> std::same_as<void>;
};

/// The time a sweep is corrected to.
enum class DeskewTarget {
  kStart,  ///< lidar frame at stamp_s (default; matches semlio's frame poses)
  kEnd,    ///< lidar frame at stamp_s + sweep_period_s
  kMiddle, ///< lidar frame at stamp_s + sweep_period_s / 2 (insensitive to velocity errors, see SweepDeskew)
};

namespace detail {

/// Time of the target as a fraction of the sweep (0 start, 0.5 middle, 1 end).
constexpr double target_fraction(DeskewTarget target) noexcept {
  switch (target) {
    case DeskewTarget::kStart: return 0.0;
    case DeskewTarget::kMiddle: return 0.5;
    case DeskewTarget::kEnd: return 1.0;
  }
  return 0.0;
}

}  // namespace detail

namespace detail {

/// Throws ValueError unless the scan has finite per-point times.
inline float max_point_time(const Scan& scan, const char* who) {
  scan.validate();
  if (!scan.empty() && !scan.has_times()) {
    throw ValueError(std::string(who) + ": the scan has no per-point times (Scan::times_s); cannot deskew");
  }
  float t_max = 0.0F;
  for (std::size_t i = 0; i < scan.times_s.size(); ++i) {
    const float t = scan.times_s[i];
    if (!std::isfinite(t) || t < 0.0F) {
      throw ValueError(std::string(who) + ": Scan::times_s[" + std::to_string(i) + "] = " + std::to_string(t) +
                       " is not a finite time since the sweep start (>= 0)");
    }
    t_max = std::max(t_max, t);
  }
  return t_max;
}

inline void check_periods(double frame_period_s, double sweep_period_s, const char* who) {
  const auto check = [who](double v, const char* field) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw ConfigError(std::string(who) + "." + field + " must be > 0, got " + std::to_string(v));
    }
  };
  check(frame_period_s, "frame_period_s");
  check(sweep_period_s, "sweep_period_s");
}

}  // namespace detail

/// Deskews `scan` under a constant body twist whose motion over one sweep of
/// sweep_period_s is T_start_end (lidar at sweep start <- lidar at sweep end):
/// T_start_t = exp(t / sweep_period_s * log(T_start_end)). ValueError when the
/// scan has no finite per-point times; ConfigError when sweep_period_s <= 0.
inline void deskew_constant_velocity(Scan& scan, const SE3d& T_start_end, double sweep_period_s,
                                     DeskewTarget target = DeskewTarget::kStart) {
  detail::check_periods(sweep_period_s, sweep_period_s, "deskew_constant_velocity");
  detail::max_point_time(scan, "deskew_constant_velocity");
  const SE3d::Vector6 xi = T_start_end.log();
  const double offset = -detail::target_fraction(target);  // e.g. T_end_t = exp((s - 1) xi)
  float last_t = -1.0F;
  SE3d T_target_t;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const float t = scan.times_s[i];
    if (t != last_t) {  // points of one firing share a time: one exp per firing
      T_target_t = SE3d::exp((static_cast<double>(t) / sweep_period_s + offset) * xi);
      last_t = t;
    }
    scan.points[i] = (T_target_t * scan.points[i].cast<double>()).cast<float>();
  }
}

/// Settings of ConstantVelocityDeskew.
struct ConstantVelocityDeskewConfig {
  DeskewTarget target = DeskewTarget::kStart;  ///< correct to sweep start or end
  double frame_period_s = 0.1;  ///< time between consecutive scans, the span of T_prev_current [s]
  double sweep_period_s = 0.1;  ///< duration of one sweep [s] (= frame period for a back-to-back spinning lidar)
};

/// Constant-velocity deskew: the predicted frame-to-frame motion, taken as a
/// constant body twist, gives each point's sensor pose. Stateless, const,
/// thread-safe.
class ConstantVelocityDeskew {
 public:
  using Config = ConstantVelocityDeskewConfig;

  /// Default settings (implicit, so `D deskewer = {}` in the odometry works).
  ConstantVelocityDeskew() : ConstantVelocityDeskew(Config{}) {}
  /// Validates the periods (ConfigError names the field).
  explicit ConstantVelocityDeskew(const Config& config) : config_(config) {
    detail::check_periods(config_.frame_period_s, config_.sweep_period_s, "ConstantVelocityDeskewConfig");
  }

  /// Corrects the scan in place; T_prev_current_predicted spans frame_period_s.
  void deskew(Scan& scan, const SE3d& T_prev_current_predicted) const {
    const SE3d T_start_end =
        SE3d::exp((config_.sweep_period_s / config_.frame_period_s) * T_prev_current_predicted.log());
    deskew_constant_velocity(scan, T_start_end, config_.sweep_period_s, config_.target);
  }

  /// The configuration.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
};
static_assert(ScanDeskewer<ConstantVelocityDeskew>);

/// What SweepDeskew does with a scan.
enum class DeskewMode : std::uint8_t {
  kNone,              ///< leaves the scan untouched (KITTI odometry scans, undistorted simulated drives)
  kConstantVelocity,  ///< constant-velocity deskew with the predicted motion (KITTI raw, distorted drives)
};

/// Where SweepDeskew takes the per-point times from.
enum class PointTimeSource : std::uint8_t {
  kAuto,     ///< the scan's times_s when it has them, else from the azimuth
  kScan,     ///< the scan's times_s; a scan without them is a ValueError
  kAzimuth,  ///< always from the azimuth (replaces times_s)
};

/// Settings of SweepDeskew. Off by default; switched on, the other defaults
/// are KITTI raw's HDL-64E as measured (features/rings.hpp): 10 Hz, clockwise
/// seen from above, each sweep starting and ending facing forward; corrected
/// to the middle of the sweep. The simulator's sweeps start facing backwards:
/// start_azimuth_rad = pi (or point_times kScan: its scans carry times).
///
/// Why the middle: the predicted velocity is the last frame's estimate, and a
/// velocity error e shifts a sweep deskewed to its start by about e/2, which
/// the next velocity estimate inherits with the opposite sign -- on the real
/// KITTI raw snippet the start target makes the odometry oscillate frame to
/// frame (0.47/0.91/0.61/0.94 m steps, roll growing to 9 deg). Deskewed to the
/// middle, a velocity error only bends the sweep symmetrically and the pose
/// does not feed it back. The frame pose is then the lidar's at stamp_s +
/// sweep_period_s / 2; poses_at_sweep_start() re-times a trajectory.
struct SweepDeskewConfig {
  DeskewMode mode = DeskewMode::kNone;                   ///< none | constant velocity
  PointTimeSource point_times = PointTimeSource::kAuto;  ///< scan times or azimuth
  double sweep_period_s = 0.1;                           ///< duration of one sweep [s]
  double start_azimuth_rad = kKittiSweepStartAzimuthRad;  ///< azimuth atan2(y, x) at t = 0 (azimuth times) [rad]
  bool clockwise = true;                                 ///< spin seen from above (azimuth times)
  /// Time-reversed playback (a recording run backwards): t -> sweep_period_s -
  /// t, i.e. each sweep spins the other way. The predicted motion is then the
  /// reversed motion and the two signs cancel; without it a backward run
  /// doubles the distortion instead of removing it.
  bool reverse_time = false;
  DeskewTarget target = DeskewTarget::kMiddle;  ///< time the sweep is corrected to (= the frame pose's time)
  /// Span of the predicted motion when the stamps cannot give it (first
  /// frame, repeated or decreasing stamp) [s]; otherwise the span is the
  /// stamp difference to the previous deskewed scan.
  double frame_period_s = 0.1;

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    detail::check_periods(frame_period_s, sweep_period_s, "SweepDeskewConfig");
    if (!std::isfinite(start_azimuth_rad)) {
      throw ConfigError("SweepDeskewConfig.start_azimuth_rad must be finite, got " + std::to_string(start_azimuth_rad));
    }
  }
  /// The azimuth-to-time settings these fields describe.
  [[nodiscard]] PointTimeConfig point_time_config() const {
    return {.sweep_period_s = sweep_period_s, .start_azimuth_rad = start_azimuth_rad, .counter_clockwise = !clockwise};
  }
};

/// The pipeline's runtime-configurable deskew slot (the presets use it):
/// mode kNone returns at once, so results are those of NoDeskew; mode
/// kConstantVelocity fills per-point times when asked to (or when the scan
/// has none: KITTI .bin and PCD scans) and corrects each point with the
/// predicted motion taken as a constant twist, scaled from the stamp
/// difference to the previous deskewed scan to one sweep. Points are moved
/// with poses tabulated at kTableIntervals + 1 times across the sweep and
/// linearly interpolated (error far below a micrometre at car speeds; no
/// exp() per point). No heap allocation per scan (the table is allocated at
/// construction). Not thread-safe: it remembers the previous stamp.
class SweepDeskew {
 public:
  using Config = SweepDeskewConfig;
  /// Intervals of the pose table across the sweep.
  static constexpr std::size_t kTableIntervals = 256;

  /// Mode kNone (implicit, so `D deskewer = {}` in the odometry works).
  SweepDeskew() : SweepDeskew(Config{}) {}
  /// Validates the settings (ConfigError names the field).
  explicit SweepDeskew(const Config& config)
      : config_(config), R_(kTableIntervals + 1), t_(kTableIntervals + 1) {
    config_.validate();
  }

  /// Corrects the scan in place (mode kConstantVelocity): T_prev_current_predicted
  /// is the predicted motion since the previous scan (lidar frame there <- here).
  /// ValueError when times come from the scan and it has none, or a time is
  /// negative or not finite.
  void deskew(Scan& scan, const SE3d& T_prev_current_predicted) const {
    if (config_.mode == DeskewMode::kNone) return;
    const double dt = scan.stamp_s - last_stamp_s_;
    const double span_s = have_stamp_ && dt > 1e-6 && std::isfinite(dt) ? dt : config_.frame_period_s;
    last_stamp_s_ = scan.stamp_s;
    have_stamp_ = true;
    if (scan.empty()) return;
    if (config_.point_times == PointTimeSource::kAzimuth ||
        (config_.point_times == PointTimeSource::kAuto && !scan.has_times())) {
      assign_times_from_azimuth(scan, config_.point_time_config());
    }
    const double sweep = config_.sweep_period_s;
    const auto max_t = static_cast<double>(detail::max_point_time(scan, "SweepDeskew"));
    if (config_.reverse_time) {
      for (float& t : scan.times_s) t = std::max(0.0F, static_cast<float>(sweep - static_cast<double>(t)));
    }
    const double table_span = config_.reverse_time ? sweep : std::max(max_t, sweep);
    // T_target_t = exp((t / sweep - offset) * xi), xi the motion over one sweep.
    const SE3d::Vector6 xi = (sweep / span_s) * T_prev_current_predicted.log();
    const double offset = detail::target_fraction(config_.target);
    constexpr auto kN = static_cast<double>(kTableIntervals);
    for (std::size_t k = 0; k <= kTableIntervals; ++k) {
      const SE3d T = SE3d::exp((table_span * static_cast<double>(k) / kN / sweep - offset) * xi);
      R_[k] = T.rotation();
      t_[k] = T.translation();
    }
    const double per_s = kN / table_span;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double u = std::clamp(static_cast<double>(scan.times_s[i]) * per_s, 0.0, kN);
      const auto k = std::min(static_cast<std::size_t>(u), kTableIntervals - 1);
      const double f = u - static_cast<double>(k);
      const Eigen::Vector3d p = scan.points[i].cast<double>();
      const Eigen::Vector3d a = R_[k] * p + t_[k];
      const Eigen::Vector3d b = R_[k + 1] * p + t_[k + 1];
      scan.points[i] = (a + f * (b - a)).cast<float>();
    }
  }

  /// True unless the mode is kNone (an odometry may re-anchor its map once
  /// the first frames, deskewed without a velocity yet, are behind it).
  [[nodiscard]] bool active() const noexcept { return config_.mode != DeskewMode::kNone; }
  /// The configuration.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
  mutable std::vector<Eigen::Matrix3d> R_;  // pose table, allocated once
  mutable std::vector<Eigen::Vector3d> t_;
  mutable double last_stamp_s_ = 0.0;
  mutable bool have_stamp_ = false;
};
static_assert(ScanDeskewer<SweepDeskew>);

/// Re-times a trajectory of frames deskewed to `target` (one pose and stamp
/// per frame, T_map_lidar at stamp + f * sweep_period_s, f = 0 / 0.5 / 1) to
/// the sweep starts under constant velocity: T_start_i = T_i * exp(-f *
/// sweep_period_s / dt * log(T_{i-1}^-1 T_i)), dt the stamp difference; frame
/// 0 uses the motion to frame 1. A frame whose stamp difference is not
/// positive keeps its pose. For comparing with ground truth taken at the sweep
/// start (the simulator's). ValueError when the sizes differ.
inline std::vector<SE3d> poses_at_sweep_start(const std::vector<SE3d>& T_map_lidar, const std::vector<double>& stamps_s,
                                              DeskewTarget target, double sweep_period_s) {
  if (T_map_lidar.size() != stamps_s.size()) {
    throw ValueError("poses_at_sweep_start: " + std::to_string(T_map_lidar.size()) + " poses but " +
                     std::to_string(stamps_s.size()) + " stamps");
  }
  const double f = detail::target_fraction(target);
  std::vector<SE3d> out = T_map_lidar;
  if (f == 0.0 || out.size() < 2) return out;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1;
    const std::size_t b = i == 0 ? 1 : i;
    const double dt = stamps_s[b] - stamps_s[a];
    if (!(dt > 0.0) || !std::isfinite(dt)) continue;
    const SE3d::Vector6 xi = (T_map_lidar[a].inverse() * T_map_lidar[b]).log();
    out[i] = T_map_lidar[i] * SE3d::exp((-f * sweep_period_s / dt) * xi);
  }
  return out;
}

/// Settings of ImuDeskew.
struct ImuDeskewConfig {
  DeskewTarget target = DeskewTarget::kStart;  ///< correct to sweep start or end
  double frame_period_s = 0.1;  ///< span of T_prev_current (for the velocity fallback) [s]
  double sweep_period_s = 0.1;  ///< duration of one sweep; the kEnd target time [s]
  /// Lidar-to-IMU extrinsic (KITTI Tr_imu_velo): its rotation maps the gyro
  /// into the lidar frame; its translation (lidar origin in the IMU frame) is
  /// the lever arm of the accelerometer, used only after set_motion().
  SE3d T_imu_lidar = SE3d();
  double imu_time_offset_s = 0.0;  ///< t_imu = t_lidar + offset [s]
  double max_gap_s = 0.15;         ///< largest allowed IMU sample spacing [s]
};

/// IMU deskew: rotation from the gyro integrated over the sweep (bias
/// removed, signals linear between samples). Translation, by what is known:
/// - default: a velocity constant in the lidar's body frame,
///   log(T_prev_current).rho / frame_period (a constant twist's body velocity);
/// - set_velocity(v): that body-frame velocity instead;
/// - set_motion(v, g): the lidar's velocity and gravity in the lidar frame at
///   the sweep start (from a lidar-inertial state): the accelerometer is
///   integrated too (lever arm included), so braking and accelerating sweeps
///   are corrected as well.
/// IMU samples come either from an ImuBuffer attached at construction
/// (non-owning: the buffer must outlive the deskewer and its copies; push the
/// sweep's samples before the odometry processes the scan — the way to feed it
/// inside Odometry's deskew slot), or from a copy given with set_imu() before
/// each deskew(). Not thread-safe (one scratch buffer per instance).
class ImuDeskew {
 public:
  using Config = ImuDeskewConfig;

  /// Default settings, samples from set_imu().
  ImuDeskew() : ImuDeskew(Config{}) {}
  /// Validates the periods and gap limit (ConfigError names the field);
  /// samples from set_imu().
  explicit ImuDeskew(const Config& config) : config_(config) {
    detail::check_periods(config_.frame_period_s, config_.sweep_period_s, "ImuDeskewConfig");
    if (!(config_.max_gap_s > 0.0)) {
      throw ConfigError("ImuDeskewConfig.max_gap_s must be > 0, got " + std::to_string(config_.max_gap_s));
    }
    if (!std::isfinite(config_.imu_time_offset_s)) throw ConfigError("ImuDeskewConfig.imu_time_offset_s is not finite");
  }
  /// Reads samples from `buffer` at each deskew() (non-owning, see class comment).
  ImuDeskew(const ImuBuffer& buffer, const Config& config) : ImuDeskew(config) { buffer_ = &buffer; }

  /// Copies the IMU samples (IMU frame and clock) for the next deskew calls
  /// and detaches any buffer. They are validated against each sweep in deskew().
  void set_imu(std::span<const ImuSample> samples) {
    samples_.assign(samples.begin(), samples.end());
    buffer_ = nullptr;
  }
  /// Biases subtracted from the samples (default zero; the accel bias matters
  /// only after set_motion()).
  void set_bias(const ImuBias& bias) { bias_ = bias; }
  /// Uses this lidar velocity, constant in the lidar's body frame [m/s].
  void set_velocity(const Eigen::Vector3d& v_lidar_mps) {
    v_lidar_mps_ = v_lidar_mps;
    gravity_lidar_mps2_.reset();
  }
  /// Integrates the accelerometer from the lidar's velocity v_lidar_mps and
  /// gravity gravity_lidar_mps2, both in the lidar frame at the sweep start.
  void set_motion(const Eigen::Vector3d& v_lidar_mps, const Eigen::Vector3d& gravity_lidar_mps2) {
    v_lidar_mps_ = v_lidar_mps;
    gravity_lidar_mps2_ = gravity_lidar_mps2;
  }
  /// Returns to the velocity of the predicted motion.
  void clear_velocity() {
    v_lidar_mps_.reset();
    gravity_lidar_mps2_.reset();
  }

  /// Corrects the scan in place. ValueError when the scan lacks per-point
  /// times or when the IMU samples do not cover the sweep (in IMU time),
  /// go backwards in time or have a gap above max_gap_s (find_imu_range).
  void deskew(Scan& scan, const SE3d& T_prev_current_predicted) const {
    const float t_max = detail::max_point_time(scan, "ImuDeskew");
    if (scan.empty()) return;
    const double t0 = scan.stamp_s + config_.imu_time_offset_s;
    const double span = std::max(static_cast<double>(t_max),
                                 detail::target_fraction(config_.target) * config_.sweep_period_s);
    const std::span<const ImuSample> samples =
        buffer_ != nullptr ? buffer_->samples() : std::span<const ImuSample>(samples_);
    const ImuRange r = find_imu_range(samples, t0, t0 + span, config_.max_gap_s, "ImuDeskew");
    v_ = v_lidar_mps_.value_or(T_prev_current_predicted.log().head<3>() / config_.frame_period_s);
    accel_mode_ = gravity_lidar_mps2_.has_value();
    build_knots(samples, r, t0, t0 + span);

    const SE3d T_target_start =
        config_.target != DeskewTarget::kStart
            ? pose_at(detail::target_fraction(config_.target) * config_.sweep_period_s).inverse()
            : SE3d();
    std::size_t k = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double t = static_cast<double>(scan.times_s[i]);
      // Points come in firing order within a ring: continue from the last knot.
      if (t < knots_[k].t_s) k = 0;
      while (k + 2 < knots_.size() && knots_[k + 1].t_s <= t) ++k;
      const SE3d T_start_t = pose_in(k, t);
      scan.points[i] = (T_target_start * (T_start_t * scan.points[i].cast<double>())).cast<float>();
    }
  }

  /// The configuration.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  // Lidar state at a knot (start of a piece) and the piece's constant rates.
  struct Knot {
    double t_s;                     // time since sweep start
    SO3d R_start_t;                 // lidar rotation: start <- t
    Eigen::Vector3d p_start_t_m;    // lidar position in the start frame
    Eigen::Vector3d v_start_mps;    // lidar velocity in the start frame (accel mode)
    Eigen::Vector3d w_lidar_radps;  // angular rate over the piece (lidar frame)
    Eigen::Vector3d a_start_mps2;   // acceleration over the piece, start frame (accel mode)
  };

  // Lidar pose at time t in piece k: constant rate; position from the
  // constant acceleration (accel mode) or the body velocity rotated by the
  // piece's midpoint rotation.
  [[nodiscard]] SE3d pose_in(std::size_t k, double t_s) const {
    const Knot& n = knots_[k];
    const double dt = t_s - n.t_s;
    const SO3d R = n.R_start_t * SO3d::exp(n.w_lidar_radps * dt);
    const Eigen::Vector3d p = accel_mode_
        ? Eigen::Vector3d(n.p_start_t_m + n.v_start_mps * dt + (0.5 * dt * dt) * n.a_start_mps2)
        : Eigen::Vector3d(n.p_start_t_m + (n.R_start_t * SO3d::exp(n.w_lidar_radps * (0.5 * dt))) * (v_ * dt));
    return SE3d(R, p);
  }
  [[nodiscard]] SE3d pose_at(double t_s) const {
    std::size_t k = 0;
    while (k + 2 < knots_.size() && knots_[k + 1].t_s <= t_s) ++k;
    return pose_in(k, t_s);
  }

  // Knots at the sweep start, each sample inside the sweep, and the sweep end
  // (times relative to t0). Gyro and specific force are moved to the lidar:
  // w_L = R_LI w, f_L = R_LI (f + dw/dt x r + w x (w x r)), r = lidar in IMU frame.
  void build_knots(std::span<const ImuSample> samples, const ImuRange& r, double t0, double t1) const {
    const SO3d R_lidar_imu = config_.T_imu_lidar.so3().inverse();
    const Eigen::Vector3d lever_m = config_.T_imu_lidar.translation();
    const Eigen::Vector3d g = gravity_lidar_mps2_.value_or(Eigen::Vector3d::Zero());
    knots_.clear();
    ImuSample prev =
        r.first < r.last ? interpolate_imu(samples[r.first], samples[r.first + 1], t0) : samples[r.first];
    prev.stamp_s = t0;
    knots_.push_back(Knot{0.0, SO3d(), Eigen::Vector3d::Zero(), v_, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
    for (std::size_t j = r.first + 1; j <= r.last; ++j) {
      const bool last = samples[j].stamp_s >= t1;
      const ImuSample next = last ? interpolate_imu(samples[j - 1], samples[j], t1) : samples[j];
      const double dt = next.stamp_s - prev.stamp_s;
      if (dt > 0.0) {
        Knot& cur = knots_.back();
        const Eigen::Vector3d w = 0.5 * (prev.gyro_radps + next.gyro_radps) - bias_.gyro_radps;
        cur.w_lidar_radps = R_lidar_imu * w;
        if (accel_mode_) {
          const Eigen::Vector3d w_dot = (next.gyro_radps - prev.gyro_radps) / dt;
          const Eigen::Vector3d f = 0.5 * (prev.accel_mps2 + next.accel_mps2) - bias_.accel_mps2 +
                                    w_dot.cross(lever_m) + w.cross(w.cross(lever_m));
          const SO3d R_mid = cur.R_start_t * SO3d::exp(cur.w_lidar_radps * (0.5 * dt));
          cur.a_start_mps2 = R_mid * (R_lidar_imu * f) + g;
        }
        const SE3d T_next = pose_in(knots_.size() - 1, cur.t_s + dt);
        const Knot n{cur.t_s + dt, T_next.so3(), T_next.translation(), cur.v_start_mps + cur.a_start_mps2 * dt,
                     cur.w_lidar_radps, cur.a_start_mps2};  // extrapolates past the last sample
        knots_.push_back(n);
      }
      prev = next;
      if (last) break;
    }
  }

  Config config_;
  std::vector<ImuSample> samples_;
  const ImuBuffer* buffer_ = nullptr;  // non-owning; see class comment
  ImuBias bias_;
  std::optional<Eigen::Vector3d> v_lidar_mps_;
  std::optional<Eigen::Vector3d> gravity_lidar_mps2_;
  mutable std::vector<Knot> knots_;  // scratch, reused between sweeps
  mutable Eigen::Vector3d v_ = Eigen::Vector3d::Zero();
  mutable bool accel_mode_ = false;
};
static_assert(ScanDeskewer<ImuDeskew>);

}  // namespace semlio
