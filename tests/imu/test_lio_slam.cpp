// Slam with a lidar-inertial front end (LidarInertialFrontEnd): keyframe
// nodes with velocity and bias, IMU factors over the keyframe intervals and
// loops (KeyframeInertialGraph). On a short simulated revisiting drive with
// IMU, whose lidar odometry is given a heading drift, loops reduce the error
// of the loop pair; every state stays finite; an IMU gap falls back (no IMU
// factor over it, no crash).
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include <semlio/loop/radius_detector.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/slam.hpp>
#include <semlio/segment/scan_labels.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

using namespace semlio;

namespace {

constexpr std::size_t kFrames = 120;  // the 12 s out-and-back revisit drive of tests/pipeline/test_slam.cpp

PipelineSettings settings() {
  PipelineSettings s;
  s.odometry.kitti_vertical_correction = false;
  s.odometry.solver.reset_weak_directions = true;  // as semlio_kitti --imu oxts
  return s;
}

using FrontEnd = decltype(make_baseline_odometry(ScanLabels{}, settings()));

// The LIO as Slam's front end with a heading drift of yaw_rad_per_m per
// metre on its reported poses (as test_slam.cpp's ReplayFrontEnd): the
// error loop closure exists to remove. Everything else is forwarded.
class DriftingLio {
 public:
  DriftingLio(const LidarInertialConfig& c, double yaw_rad_per_m)
      : lio_([] { return make_baseline_odometry(ScanLabels{}, settings()); }, c), yaw_rad_per_m_(yaw_rad_per_m) {}
  bool push_imu(const ImuSample& s) { return lio_.push_imu(s); }
  FrameReport process(Scan& scan, const std::optional<SE3d>& prior) {
    FrameReport r = lio_.process(scan, prior);
    const SE3d step = last_true_.inverse() * r.T_map_lidar;
    const double d = step.translation().norm();
    last_true_ = r.T_map_lidar;
    last_drifted_ = last_drifted_ * SE3d(step.so3() * SO3d::exp(Eigen::Vector3d(0.0, 0.0, yaw_rad_per_m_ * d)),
                                         step.translation());
    r.T_map_lidar = last_drifted_;
    return r;
  }
  [[nodiscard]] const LoamFeatures& features() const { return lio_.features(); }
  [[nodiscard]] std::optional<KeyframeInertialNode> inertial_state() const { return lio_.inertial_state(); }
  [[nodiscard]] std::optional<ImuPreintegration> preintegrate(double t0, double t1, const ImuBias& b,
                                                              const Eigen::Vector3d& g) const {
    return lio_.preintegrate(t0, t1, b, g);
  }
  [[nodiscard]] const Eigen::Vector3d& gravity_map_mps2() const { return lio_.gravity_map_mps2(); }
  [[nodiscard]] const SE3d& T_imu_lidar() const { return lio_.T_imu_lidar(); }
  [[nodiscard]] double imu_stamp_s(double t) const { return lio_.imu_stamp_s(t); }
  void drop_imu_before(double t) { lio_.drop_imu_before(t); }
  [[nodiscard]] const LidarInertialReport& last_report() const { return lio_.last_report(); }

 private:
  LidarInertialFrontEnd<FrontEnd> lio_;
  double yaw_rad_per_m_;
  SE3d last_true_;
  SE3d last_drifted_;
};
static_assert(InertialSlamFrontEnd<DriftingLio>);
static_assert(InertialSlamFrontEnd<LidarInertialFrontEnd<FrontEnd>>);

struct Drive {
  std::vector<Scan> scans;
  std::vector<SE3d> gt;
  std::vector<ImuSample> imu;
  SE3d T_imu_lidar;
};

const Drive& drive() {
  static const Drive d = [] {
    sim::SimulatorConfig c = semlio_test::small_lidar_drive_config(kFrames, false);
    c.traffic = sim::TrafficLevel::kLight;  // as test_slam.cpp's drive
    c.seed = 3;
    c.revisit = true;
    c.lidar.azimuth_steps = 1080;
    const sim::Simulator s(c);
    Drive out;
    out.gt = s.lidar_poses();
    out.T_imu_lidar = sim::default_T_imu_lidar();
    out.imu = s.imu({}, out.T_imu_lidar).samples;
    for (std::size_t i = 0; i < kFrames; ++i) out.scans.push_back(s.frame(i).scan);
    return out;
  }();
  return d;
}

struct Run {
  std::vector<SE3d> trajectory;
  std::vector<SlamLoop> loops;
  std::size_t imu_factors = 0;
  std::size_t nodes = 0;
  std::size_t fallbacks = 0;
  bool states_finite = true;
};

// Runs Slam over the drive with IMU samples up to each scan (none inside
// [gap_from_s, gap_to_s)).
Run run(bool loops, double gap_from_s = 0.0, double gap_to_s = 0.0) {
  const Drive& d = drive();
  LidarInertialConfig lc;
  lc.T_imu_lidar = d.T_imu_lidar;
  lc.init.min_frames = 15;
  lc.init.min_duration_s = 1.4;
  Slam slam(DriftingLio(lc, 0.003), RadiusLoopDetector({.radius_m = 15.0, .min_time_gap_s = 5.0}),
            SlamConfig{.loop_closure = loops, .loop_interval_s = 0.0});
  static_assert(decltype(slam)::kInertial);
  Run out;
  std::size_t next = 0;
  for (std::size_t i = 0; i < kFrames; ++i) {
    Scan scan = d.scans[i];
    // Up to one sweep after the stamp, as semlio_kitti (the IMU must cover the stamp).
    while (next < d.imu.size() && d.imu[next].stamp_s <= scan.stamp_s + lc.sweep_period_s + 1e-9) {
      const ImuSample& s = d.imu[next++];
      if (!(s.stamp_s >= gap_from_s && s.stamp_s < gap_to_s)) slam.push_imu(s);
    }
    const SlamFrameReport r = slam.process(scan);
    REQUIRE(r.T_world_lidar.matrix().allFinite());
    out.fallbacks += slam.odometry().last_report().imu_fallback ? 1U : 0U;
  }
  out.trajectory = slam.trajectory();
  out.loops = slam.loops();
  out.imu_factors = slam.imu_factors();
  out.nodes = slam.graph().num_nodes();
  for (std::size_t k = 0; k < out.nodes; ++k) {
    const KeyframeInertialNode& x = slam.graph().node(static_cast<NodeId>(k));
    out.states_finite = out.states_finite && x.state.pose().matrix().allFinite() && x.state.v_world_mps.allFinite() &&
                        x.bias.gyro_radps.allFinite() && x.bias.accel_mps2.allFinite();
  }
  return out;
}

// Each run once for all test cases.
const Run& run_on() {
  static const Run r = run(true);
  return r;
}

double pair_error(const std::vector<SE3d>& est, const std::vector<SE3d>& gt, std::size_t a, std::size_t b) {
  return ((gt[a].inverse() * gt[b]).inverse() * (est[a].inverse() * est[b])).translation().norm();
}

}  // namespace

TEST_CASE("lidar-inertial Slam: loops reduce the loop pair's error, states stay finite", "[imu]") {
  const Drive& d = drive();
  const Run off = run(false);
  const Run& on = run_on();
  REQUIRE(on.loops.size() >= 1);
  CHECK(on.states_finite);
  CHECK(off.states_finite);
  // IMU factors between all consecutive keyframes but those before (and the
  // first after) the LIO's initialisation (15 frames, ~5 keyframes here).
  INFO(on.imu_factors << " IMU factors on " << on.nodes << " keyframes");
  CHECK(on.imu_factors + 8 >= on.nodes);
  CHECK(on.imu_factors > 0);
  double err_on = 0.0;
  double err_off = 0.0;
  for (const SlamLoop& l : on.loops) {
    err_on += pair_error(on.trajectory, d.gt, l.from_frame, l.to_frame);
    err_off += pair_error(off.trajectory, d.gt, l.from_frame, l.to_frame);
    CHECK(l.solve.ok());
    CHECK(l.solve.mode == GraphSolveMode::full);
  }
  const double end_on = (on.trajectory.back().translation() - d.gt.back().translation()).norm();
  const double end_off = (off.trajectory.back().translation() - d.gt.back().translation()).norm();
  INFO(on.loops.size() << " loops, " << on.imu_factors << " IMU factors on " << on.nodes
                       << " keyframes; loop-pair error (sum) " << err_off << " m without loops, " << err_on
                       << " m with; endpoint " << end_off << " -> " << end_on << " m");
  CHECK(err_on < err_off);
  CHECK(end_on < end_off);
}

TEST_CASE("lidar-inertial Slam: an IMU gap falls back without a crash", "[imu]") {
  const Run gap = run(true, 6.0, 7.0);
  const Run& full = run_on();
  CHECK(gap.fallbacks > 0);
  CHECK(full.fallbacks == 0);
  CHECK(gap.states_finite);
  // No IMU factor can span the gap: more keyframe intervals are unlinked.
  const auto unlinked = [](const Run& r) { return r.nodes - 1 - r.imu_factors; };
  INFO("unlinked keyframe intervals: " << unlinked(gap) << " with the gap, " << unlinked(full) << " without");
  CHECK(unlinked(gap) > unlinked(full));
  for (const SE3d& T : gap.trajectory) REQUIRE(T.matrix().allFinite());
}
