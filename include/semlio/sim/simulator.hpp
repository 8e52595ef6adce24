#pragma once
/// \file
/// In-memory frame generation: `Simulator sim(config); Frame f = sim.frame(i);`
/// gives one lidar sweep with exact labels and instances, its ground-truth
/// pose, per-point ring/time/column, without touching the disk.
///
/// Time and frames (documented once here, used by the writer):
/// - Frame i's sweep starts at stamp_s = i / rate_hz (Scan::stamp_s, and the
///   value written to times.txt); per-point times_s run from 0 to the period.
/// - The ground-truth pose of frame i is T_world_lidar at stamp_s (sweep
///   start); poses.txt holds these relative to frame 0 in KITTI's camera-0
///   convention.
/// - distortion off (KITTI odometry, de-skewed): every ray is cast from the
///   lidar pose at stamp_s, so all points are exact in the sweep-start frame.
/// - distortion on (KITTI raw): each ray is cast from the lidar pose at its
///   own firing time t_i = stamp_s + times_s[i], and the point is reported in
///   the lidar frame at t_i, as a spinning lidar measures it. De-skewing it
///   to the sweep-start frame is p_start = T_world_lidar(stamp)^-1 *
///   T_world_lidar(t_i) * p_i.
/// - Moving actors are posed per azimuth chunk (at the chunk's mid time) in
///   both modes, since real de-skewed scans still smear moving objects.
/// - Point order follows KITTI's .bin files: rings from the top beam down,
///   each ring by increasing azimuth starting straight ahead.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/sim/bvh.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/lidar.hpp>
#include <semlio/sim/random.hpp>
#include <semlio/sim/revisit.hpp>
#include <semlio/sim/traffic.hpp>
#include <semlio/sim/trajectory.hpp>
#include <semlio/sim/world.hpp>

namespace semlio::sim {

/// Lidar -> IMU extrinsic (KITTI's Tr_imu_velo lever arm): the lidar sits
/// 0.81 m ahead of, 0.32 m right of and 0.80 m above the IMU, no rotation.
inline SE3d default_T_imu_lidar() { return SE3d(SO3d(), Eigen::Vector3d(0.81, -0.32, 0.80)); }

/// Everything that defines a simulated drive. Same config -> same frames.
struct SimulatorConfig {
  WorldKind world = WorldKind::kUrban;         ///< world family
  TrafficLevel traffic = TrafficLevel::kLight; ///< amount of traffic
  std::size_t frames = 1000;                   ///< number of sweeps
  std::uint64_t seed = 1;                      ///< seed of the world, traffic and noise
  /// Revisit: the route is a closed lap sized so that the last frame is taken
  /// at the first frame's pose (urban: a block loop, or an out-and-back drive
  /// with U-turns when no block loop is short enough; rural and highway:
  /// out-and-back; see revisit.hpp). Needs frames >= ~100 (a 10 s drive).
  bool revisit = false;
  bool distortion = false;                     ///< false: de-skewed (KITTI odometry); true: raw
  double imu_rate_hz = 100.0;                  ///< IMU sample rate (used by the writer) [Hz]
  double label_quality = 0.5;                  ///< target mIoU of predicted labels (used by the writer)
  LidarConfig lidar;                           ///< sensor model
  int threads = 1;                             ///< ray-casting threads; output is identical for any count
  int chunks = 36;                             ///< azimuth chunks per sweep (actor poses per chunk)
};

/// One simulated sweep.
struct Frame {
  std::size_t index = 0;                      ///< frame number
  Scan scan;                                  ///< points (lidar frame), intensity, labels, instances, rings, times_s, stamp_s
  std::vector<std::uint32_t> raw_labels;      ///< raw SemanticKITTI id | instance << 16, per point
  std::vector<std::uint16_t> columns;         ///< azimuth column per point (range-image column; 0 = facing backwards)
  SE3d T_world_lidar;                         ///< ground truth at scan.stamp_s (sweep start)
};

/// Generates the frames of one drive. Construction builds the world, the ego
/// trajectory and the traffic; `frame(i)` is const and may be called in any
/// order and from several threads.
class Simulator {
 public:
  using Config = SimulatorConfig;

  /// Validates `config` (ConfigError names the field) and builds the drive.
  explicit Simulator(const SimulatorConfig& config) : config_(config), lidar_(config.lidar) {
    if (config_.frames == 0) throw ConfigError("SimulatorConfig.frames must be > 0, got 0");
    if (config_.threads < 1) throw ConfigError("SimulatorConfig.threads must be >= 1, got " + std::to_string(config_.threads));
    if (config_.chunks < 1 || config_.chunks > lidar_.columns()) {
      throw ConfigError("SimulatorConfig.chunks must be in [1, azimuth_steps], got " + std::to_string(config_.chunks));
    }
    if (!(config_.imu_rate_hz > 0.0)) {
      throw ConfigError("SimulatorConfig.imu_rate_hz must be > 0, got " + std::to_string(config_.imu_rate_hz));
    }
    if (!(config_.label_quality > 0.0 && config_.label_quality <= 1.0)) {
      throw ConfigError("SimulatorConfig.label_quality must be in (0, 1], got " + std::to_string(config_.label_quality));
    }
    const double duration = static_cast<double>(config_.frames) * lidar_.period_s();
    world_ = std::make_shared<const World>(make_world(world_config(config_)));
    ego_ = ego_trajectory(world_->ego_route, world_->ego_motion, world_->ego_stop_points);
    traffic_ = std::make_shared<const Traffic>(*world_, config_.traffic, config_.seed, duration + 1.0);
    T_body_lidar_ = SE3d(SO3d(), Eigen::Vector3d(0.0, 0.0, config_.lidar.mount_height_m));
  }

  /// The world a drive uses: its kind, seed and revisit flag, a route long
  /// enough for the drive, and (revisit) the return time: the last frame's
  /// sweep starts at the first frame's pose. Lets tests build the world and
  /// ego route without ray casting or traffic.
  static WorldConfig world_config(const SimulatorConfig& config) {
    const double period_s = 1.0 / config.lidar.rate_hz;
    WorldConfig wc;
    wc.kind = config.world;
    wc.seed = config.seed;
    wc.revisit = config.revisit;
    wc.drive_length_m = std::max(100.0, static_cast<double>(config.frames) * period_s * cruise_speed(config.world));
    wc.return_time_s = static_cast<double>(config.frames > 0 ? config.frames - 1 : 0) * period_s;
    return wc;
  }

  /// Typical cruise speed of a world kind [m/s] (urban 11, rural 16, highway 25).
  static double cruise_speed(WorldKind k) {
    switch (k) {
      case WorldKind::kRural: return 16.0;
      case WorldKind::kHighway: return 25.0;
      default: return 11.0;
    }
  }

  /// The configuration.
  [[nodiscard]] const SimulatorConfig& config() const noexcept { return config_; }
  /// The world.
  [[nodiscard]] const World& world() const noexcept { return *world_; }
  /// The lidar model.
  [[nodiscard]] const Lidar& lidar() const noexcept { return lidar_; }
  /// The ego vehicle's trajectory (body frame on the ground, x forward).
  [[nodiscard]] const Trajectory& ego() const noexcept { return ego_; }
  /// The traffic.
  [[nodiscard]] const Traffic& traffic() const noexcept { return *traffic_; }
  /// Number of frames.
  [[nodiscard]] std::size_t frame_count() const noexcept { return config_.frames; }
  /// Mounting of the lidar on the vehicle body (1.73 m above the ground point).
  [[nodiscard]] const SE3d& T_body_lidar() const noexcept { return T_body_lidar_; }
  /// Sweep start time of frame i [s].
  [[nodiscard]] double frame_stamp_s(std::size_t i) const { return static_cast<double>(i) * lidar_.period_s(); }
  /// Lidar pose in the world at time t [s].
  [[nodiscard]] SE3d T_world_lidar(double t_s) const { return ego_.pose(t_s) * T_body_lidar_; }

  /// Ground truth of every frame relative to frame 0: T_lidar0_lidar_i at the
  /// sweep starts (lidar frame; poses.txt holds the same in camera-0 form).
  [[nodiscard]] std::vector<SE3d> lidar_poses() const {
    std::vector<SE3d> out(config_.frames);
    const SE3d T0_inv = T_world_lidar(frame_stamp_s(0)).inverse();
    for (std::size_t i = 0; i < config_.frames; ++i) out[i] = T0_inv * T_world_lidar(frame_stamp_s(i));
    return out;
  }

  /// IMU samples (config().imu_rate_hz) over the frames' time span for an IMU
  /// at T_imu_lidar on the vehicle; noise densities and seed from `imu`
  /// (its rate_hz and T_imu_body are overwritten).
  [[nodiscard]] SimulatedImu imu(ImuConfig imu_config = {}, const SE3d& T_imu_lidar = default_T_imu_lidar()) const {
    imu_config.rate_hz = config_.imu_rate_hz;
    imu_config.T_imu_body = T_imu_lidar * T_body_lidar_.inverse();
    const double t_end = frame_stamp_s(config_.frames - 1) + lidar_.period_s();
    return simulate_imu(ego_, imu_config, 0.0, t_end);
  }

  /// Generates frame i (0 <= i < frame_count()).
  [[nodiscard]] Frame frame(std::size_t i) const {
    if (i >= config_.frames) {
      throw ValueError("Simulator::frame: index " + std::to_string(i) + " out of range [0, " +
                       std::to_string(config_.frames) + ")");
    }
    const int rings = lidar_.rings();
    const int cols = lidar_.columns();
    const double stamp = frame_stamp_s(i);
    Frame f;
    f.index = i;
    f.T_world_lidar = T_world_lidar(stamp);
    // Lidar pose per column (one pose for all when distortion is off).
    std::vector<SE3d> poses(config_.distortion ? static_cast<std::size_t>(cols) : 1U);
    for (std::size_t c = 0; c < poses.size(); ++c) {
      poses[c] = config_.distortion ? T_world_lidar(stamp + lidar_.column_time_s(static_cast<int>(c))) : f.T_world_lidar;
    }
    // Actors near the ego this frame (evaluated once, posed per chunk).
    std::vector<std::size_t> near;
    const Eigen::Vector3d ego_pos = f.T_world_lidar.translation();
    for (std::size_t k = 0; k < traffic_->actors().size(); ++k) {
      const double reach = lidar_.config().max_range_m + 20.0;
      if ((traffic_->actor_pose(k, stamp + 0.5 * lidar_.period_s()).translation() - ego_pos).norm() < reach) {
        near.push_back(k);
      }
    }
    std::vector<Cell> cells(static_cast<std::size_t>(rings) * static_cast<std::size_t>(cols));
    const int chunks = config_.chunks;
    const auto run_chunk = [&](int chunk) {
      const int c0 = chunk * cols / chunks;
      const int c1 = (chunk + 1) * cols / chunks;
      const double t_mid = stamp + 0.5 * (lidar_.column_time_s(c0) + lidar_.column_time_s(c1));
      std::vector<Primitive> dyn;
      for (const std::size_t k : near) traffic_->append_primitives(k, t_mid, dyn);
      const Bvh dyn_bvh(std::move(dyn));
      for (int c = c0; c < c1; ++c) {
        const SE3d& T = poses[config_.distortion ? static_cast<std::size_t>(c) : 0U];
        cast_column(T, c, i, dyn_bvh, cells);
      }
    };
    const int threads = std::min(config_.threads, chunks);
    if (threads <= 1) {
      for (int k = 0; k < chunks; ++k) run_chunk(k);
    } else {
      // Fixed round-robin chunk assignment; cells are disjoint, so the result
      // does not depend on scheduling.
      std::vector<std::thread> pool;
      for (int w = 0; w < threads; ++w) {
        pool.emplace_back([&, w] {
          for (int k = w; k < chunks; k += threads) run_chunk(k);
        });
      }
      for (auto& t : pool) t.join();
    }
    gather(cells, stamp, f);
    return f;
  }

 private:
  struct Cell {
    Eigen::Vector3f p = Eigen::Vector3f::Zero();
    float intensity = 0.0F;
    std::uint32_t raw = 0;
    bool valid = false;
  };

  void cast_column(const SE3d& T_world_lidar, int c, std::size_t frame, const Bvh& dyn, std::vector<Cell>& cells) const {
    const Eigen::Matrix3d R = T_world_lidar.rotation();
    const Eigen::Vector3d origin = T_world_lidar.translation();
    const int cols = lidar_.columns();
    const double t_max = lidar_.config().max_range_m + 1.0;
    for (int r = 0; r < lidar_.rings(); ++r) {
      if (lidar_.self_occluded(r, c)) continue;
      const Eigen::Vector3d d_lidar = lidar_.direction(r, c);
      Ray ray;
      ray.origin = origin;
      ray.dir = R * d_lidar;
      ray.inv_dir = ray.dir.cwiseInverse();
      Hit hit;
      const Primitive* prim = nullptr;
      if (world_->bvh.cast(ray, 0.0, t_max, hit)) prim = &world_->bvh.primitives()[hit.primitive];
      Hit dyn_hit;
      if (dyn.cast(ray, 0.0, prim != nullptr ? hit.t_m : t_max, dyn_hit)) {
        hit = dyn_hit;
        prim = &dyn.primitives()[dyn_hit.primitive];
      }
      if (prim == nullptr) continue;
      const Eigen::Vector3d x = origin + hit.t_m * ray.dir;
      const double cos_inc = std::abs(surface_normal(*prim, x, origin).dot(ray.dir));
      const std::uint64_t key = hash_keys(config_.seed, frame, static_cast<std::uint64_t>(r), static_cast<std::uint64_t>(c));
      const ReturnModel m = lidar_.measure(hit.t_m, cos_inc, static_cast<double>(prim->surface.reflectivity), key);
      if (!m.keep) continue;
      Cell& cell = cells[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)];
      cell.p = (d_lidar * m.range_m).cast<float>();
      cell.intensity = m.intensity;
      cell.raw = static_cast<std::uint32_t>(prim->surface.raw_label) |
                 (static_cast<std::uint32_t>(prim->surface.instance) << 16U);
      cell.valid = true;
    }
  }

  void gather(const std::vector<Cell>& cells, double stamp, Frame& f) const {
    const int rings = lidar_.rings();
    const int cols = lidar_.columns();
    Scan& scan = f.scan;
    scan.stamp_s = stamp;
    std::size_t n = 0;
    for (const Cell& c : cells) n += c.valid ? 1U : 0U;
    scan.points.reserve(n);
    scan.intensity.reserve(n);
    scan.labels.reserve(n);
    scan.instances.reserve(n);
    scan.rings.reserve(n);
    scan.times_s.reserve(n);
    f.raw_labels.reserve(n);
    f.columns.reserve(n);
    for (int r = rings - 1; r >= 0; --r) {
      for (int k = 0; k < cols; ++k) {
        // Increasing azimuth from straight ahead: column cols/2 faces forward,
        // smaller columns turn left (azimuth grows towards +pi).
        const int c = ((cols / 2 - k) % cols + cols) % cols;
        const Cell& cell = cells[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)];
        if (!cell.valid) continue;
        scan.points.push_back(cell.p);
        scan.intensity.push_back(cell.intensity);
        scan.labels.push_back(learning_class(cell.raw & 0xFFFFU));
        scan.instances.push_back(static_cast<std::uint16_t>(cell.raw >> 16U));
        scan.rings.push_back(static_cast<std::uint16_t>(r));
        scan.times_s.push_back(static_cast<float>(lidar_.column_time_s(c)));
        f.raw_labels.push_back(cell.raw);
        f.columns.push_back(static_cast<std::uint16_t>(c));
      }
    }
  }

  SimulatorConfig config_;
  Lidar lidar_;
  std::shared_ptr<const World> world_;
  Trajectory ego_;
  std::shared_ptr<const Traffic> traffic_;
  SE3d T_body_lidar_;
};

}  // namespace semlio::sim
