// Deskew: constructed distorted sweeps of a static scene under known motion,
// the simulator's distorted sweeps, and bad input.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/imu/deskew.hpp>
#include <semlio/imu/imu_buffer.hpp>
#include <semlio/pipeline/odometry.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio/sim/trajectory.hpp>

namespace test_deskew {  // one namespace per test file: the area compiles as one TU

using semlio::ConstantVelocityDeskew;
using semlio::DeskewTarget;
using semlio::ImuDeskew;
using semlio::ImuSample;
using semlio::Scan;
using semlio::SE3d;
using semlio::SO3d;

static_assert(semlio::ScanDeskewer<semlio::NoDeskew>);  // same slot signature as the odometry's default

namespace {

using PoseAt = std::function<SE3d(double)>;  // T_world_lidar at time since sweep start

struct Sweep {
  Scan distorted;                       // each point in the lidar frame at its firing time
  std::vector<Eigen::Vector3d> p_world;  // the static scene
};

// A static scene (points 3..60 m around the start pose) swept in firing order
// over [0, sweep_s) by a sensor moving along pose_at.
Sweep make_sweep(const PoseAt& pose_at, double sweep_s, double stamp_s, std::size_t n = 4000) {
  std::mt19937 rng(42);
  const auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng()) / 4294967296.0);
  };
  Sweep s;
  s.distorted.stamp_s = stamp_s;
  const SE3d T0 = pose_at(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = sweep_s * static_cast<double>(i) / static_cast<double>(n);
    const double az = 3.14159 - 6.28318 * static_cast<double>(i) / static_cast<double>(n);  // clockwise spin
    const double el = uniform(-0.4, 0.05);
    const double r = uniform(3.0, 60.0);
    const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Vector3d P = T0 * (r * dir);
    s.p_world.push_back(P);
    s.distorted.points.push_back((pose_at(t).inverse() * P).cast<float>());
    s.distorted.times_s.push_back(static_cast<float>(t));
  }
  return s;
}

// Largest distance between scan points and the scene seen from pose T_world_target.
double max_error(const Scan& scan, const Sweep& s, const SE3d& T_world_target) {
  double worst = 0.0;
  const SE3d T_target_world = T_world_target.inverse();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    worst = std::max(worst, (scan.points[i].cast<double>() - T_target_world * s.p_world[i]).norm());
  }
  return worst;
}

// Constant body twist xi = [v; w] (lidar frame) from a start pose.
PoseAt screw(const SE3d& T0, const SE3d::Vector6& xi) {
  return [T0, xi](double t) { return T0 * SE3d::exp(t * xi); };
}

SE3d::Vector6 fast_turn() {
  SE3d::Vector6 xi;
  xi << 15.0, 0.8, 0.3, 0.03, -0.02, 0.6;  // 15 m/s forward, 0.6 rad/s yaw
  return xi;
}

// Gyro samples (IMU frame and clock) of a constant lidar rate w_lidar.
std::vector<ImuSample> constant_gyro(const Eigen::Vector3d& w_lidar, const SE3d& T_imu_lidar, double t0, double t1,
                                     double rate_hz) {
  std::vector<ImuSample> out;
  for (double t = t0; t <= t1; t += 1.0 / rate_hz) {
    out.push_back(ImuSample{t, T_imu_lidar.so3() * w_lidar, Eigen::Vector3d(0.0, 0.0, 9.81)});
  }
  return out;
}

}  // namespace

TEST_CASE("constant-velocity deskew undoes a constant-twist sweep", "[imu]") {
  const SE3d T0(SO3d::exp(Eigen::Vector3d(0.01, 0.02, 1.0)), Eigen::Vector3d(5.0, -3.0, 1.7));
  const SE3d::Vector6 xi = fast_turn();
  const PoseAt pose = screw(T0, xi);
  const Sweep s = make_sweep(pose, 0.1, 100.0);
  const SE3d T_prev_current = SE3d::exp(0.1 * xi);  // frame period 0.1 s

  REQUIRE(max_error(s.distorted, s, T0) > 0.5);  // the distortion is real
  SECTION("to the sweep start") {
    Scan scan = s.distorted;
    ConstantVelocityDeskew(ConstantVelocityDeskew::Config{}).deskew(scan, T_prev_current);
    CHECK(max_error(scan, s, T0) < 0.01);
    CHECK(max_error(scan, s, T0) < 1e-4);  // exact model: only float rounding remains
    CHECK(scan.times_s == s.distorted.times_s);
  }
  SECTION("to the sweep end") {
    Scan scan = s.distorted;
    ConstantVelocityDeskew({.target = DeskewTarget::kEnd}).deskew(scan, T_prev_current);
    CHECK(max_error(scan, s, pose(0.1)) < 1e-4);
  }
  SECTION("to the middle of the sweep") {
    Scan scan = s.distorted;
    ConstantVelocityDeskew({.target = DeskewTarget::kMiddle}).deskew(scan, T_prev_current);
    CHECK(max_error(scan, s, pose(0.05)) < 1e-4);
    ImuDeskew imu_mid({.target = DeskewTarget::kMiddle});
    imu_mid.set_imu(constant_gyro(xi.tail<3>(), SE3d(), 99.98, 100.13, 100.0));
    Scan by_imu = s.distorted;
    imu_mid.deskew(by_imu, T_prev_current);
    CHECK(max_error(by_imu, s, pose(0.05)) < 1e-3);
  }
  SECTION("sweep shorter than the frame period") {
    const Sweep half = make_sweep(pose, 0.05, 100.0);
    Scan scan = half.distorted;
    ConstantVelocityDeskew({.target = DeskewTarget::kEnd, .frame_period_s = 0.1, .sweep_period_s = 0.05})
        .deskew(scan, T_prev_current);
    CHECK(max_error(scan, half, pose(0.05)) < 1e-4);
  }
  SECTION("free function with the sweep motion") {
    Scan scan = s.distorted;
    semlio::deskew_constant_velocity(scan, T0.inverse() * pose(0.1), 0.1);
    CHECK(max_error(scan, s, T0) < 1e-4);
  }
}

TEST_CASE("IMU deskew undoes a constant-twist sweep (rotated IMU, time offset)", "[imu]") {
  const SE3d T0(SO3d::exp(Eigen::Vector3d(-0.02, 0.01, 2.0)), Eigen::Vector3d(-40.0, 7.0, 2.0));
  const SE3d::Vector6 xi = fast_turn();
  const PoseAt pose = screw(T0, xi);
  const double stamp = 50.0;
  const Sweep s = make_sweep(pose, 0.1, stamp);
  semlio::ImuDeskewConfig c;
  c.T_imu_lidar = SE3d(SO3d::exp(Eigen::Vector3d(0.3, -0.2, 1.2)), Eigen::Vector3d(0.8, -0.3, 0.8));
  c.imu_time_offset_s = 0.37;  // t_imu = t_lidar + 0.37
  const auto imu = constant_gyro(xi.tail<3>(), c.T_imu_lidar, stamp + 0.37 - 0.0213, stamp + 0.37 + 0.13, 100.0);
  const SE3d T_prev_current = SE3d::exp(0.1 * xi);

  SECTION("to the start, velocity from the predicted motion") {
    ImuDeskew d(c);
    d.set_imu(imu);
    Scan scan = s.distorted;
    d.deskew(scan, T_prev_current);
    CHECK(max_error(scan, s, T0) < 0.01);
    CHECK(max_error(scan, s, T0) < 1e-3);
  }
  SECTION("to the end, explicit velocity; a wrong prediction does not matter") {
    c.target = DeskewTarget::kEnd;
    ImuDeskew d(c);
    d.set_imu(imu);
    d.set_velocity(xi.head<3>());
    Scan scan = s.distorted;
    d.deskew(scan, SE3d());
    CHECK(max_error(scan, s, pose(0.1)) < 1e-3);
  }
  SECTION("full motion: accelerometer with lever arm and gravity") {
    // Synthesised IMU on the screw motion: lidar acceleration R_L(t) (w x rho),
    // IMU acceleration adds w x (w x r_lidar_imu); specific force in the IMU frame.
    const Eigen::Vector3d w = xi.tail<3>();
    const Eigen::Vector3d rho = xi.head<3>();
    const Eigen::Vector3d g_start = T0.rotation().transpose() * Eigen::Vector3d(0.0, 0.0, -9.81);
    const Eigen::Vector3d r_imu = c.T_imu_lidar.inverse().translation();  // IMU origin in the lidar frame
    const Eigen::Matrix3d R_imu_lidar = c.T_imu_lidar.rotation();
    std::vector<ImuSample> full;
    for (const ImuSample& m : imu) {
      const double t = m.stamp_s - (stamp + 0.37);
      const Eigen::Matrix3d R_L = SO3d::exp(w * t).matrix();
      const Eigen::Vector3d a_imu = R_L * (w.cross(rho) + w.cross(w.cross(r_imu)));
      full.push_back(ImuSample{m.stamp_s, m.gyro_radps, R_imu_lidar * (R_L.transpose() * (a_imu - g_start))});
    }
    ImuDeskew d(c);
    d.set_imu(full);
    d.set_motion(rho, g_start);
    Scan scan = s.distorted;
    d.deskew(scan, SE3d());
    CHECK(max_error(scan, s, T0) < 1e-3);
  }
  SECTION("gyro bias is removed") {
    auto biased = imu;
    const Eigen::Vector3d b(0.01, -0.02, 0.03);
    for (auto& m : biased) m.gyro_radps += b;
    ImuDeskew d(c);
    d.set_imu(biased);
    Scan scan = s.distorted;
    d.deskew(scan, T_prev_current);
    CHECK(max_error(scan, s, T0) > 0.02);  // 0.03 rad/s over 0.1 s at 60 m
    semlio::ImuBias bias;
    bias.gyro_radps = b;
    d.set_bias(bias);
    scan = s.distorted;
    d.deskew(scan, T_prev_current);
    CHECK(max_error(scan, s, T0) < 1e-3);
  }
}

TEST_CASE("IMU deskew on a realistic drive (varying rates, noise-free simulated IMU)", "[imu]") {
  semlio::sim::TrajectoryConfig tc;
  tc.cruise_speed_mps = 16.0;
  const auto tr = semlio::sim::Trajectory::through({{0, 0, 0}, {150, 0, 0}, {150, 80, 5}, {100, 140, 6}, {0, 140, 0}}, tc);
  const SE3d T_body_lidar(SO3d(), Eigen::Vector3d(0.0, 0.0, 1.73));
  semlio::sim::ImuConfig ic;
  ic.noise = false;  // default lever arm to the lidar
  const SE3d T_imu_lidar = ic.T_imu_body * T_body_lidar;
  const auto imu = semlio::sim::simulate_imu(tr, ic, 0.0, tr.duration_s());
  semlio::ImuDeskewConfig c;
  c.T_imu_lidar = T_imu_lidar;
  ImuDeskew d(c);
  d.set_imu(imu.samples);
  double worst_motion = 0.0;
  double worst_velocity = 0.0;
  double worst_raw = 0.0;
  for (double stamp = 1.0; stamp + 0.2 < tr.duration_s(); stamp += 1.7) {
    const PoseAt pose = [&](double t) { return tr.pose(stamp + t) * T_body_lidar; };
    const Sweep s = make_sweep(pose, 0.1, stamp, 1000);
    const auto st = tr.state(stamp);
    const Eigen::Vector3d v_world =
        st.velocity_world_mps + st.T_world_body.rotation() * st.angular_velocity_body_radps.cross(T_body_lidar.translation());
    const Eigen::Matrix3d R_lidar_world = pose(0.0).rotation().transpose();
    // Full IMU state known (velocity and gravity at the sweep start): accelerometer integrated.
    d.set_motion(R_lidar_world * v_world, R_lidar_world * Eigen::Vector3d(0.0, 0.0, -ic.gravity_mps2));
    Scan scan = s.distorted;
    d.deskew(scan, SE3d());
    worst_motion = std::max(worst_motion, max_error(scan, s, pose(0.0)));
    // Only the start velocity: constant body velocity, off by a t^2 / 2 when braking.
    d.set_velocity(R_lidar_world * v_world);
    scan = s.distorted;
    d.deskew(scan, SE3d());
    worst_velocity = std::max(worst_velocity, max_error(scan, s, pose(0.0)));
    worst_raw = std::max(worst_raw, max_error(s.distorted, s, pose(0.0)));
  }
  INFO("worst deskewed error " << worst_motion << " m (velocity + gravity), " << worst_velocity
                               << " m (velocity only), worst distortion " << worst_raw << " m");
  CHECK(worst_raw > 1.0);
  CHECK(worst_motion < 0.01);
  CHECK(worst_motion < 1e-3);
  // Bound by hand: max_decel 2 m/s^2 * (0.1 s)^2 / 2 = 1 cm, plus a little for turning.
  CHECK(worst_velocity < 0.012);
}

TEST_CASE("deskewed simulator sweeps match the exact sweep-start points within 1 cm", "[imu]") {
  // The urban drive's first seconds are straight at cruise speed (11 m/s, 1.1 m
  // per sweep); turns and braking are covered by the realistic-drive test above.
  semlio::sim::SimulatorConfig sc;
  sc.frames = 30;
  sc.traffic = semlio::sim::TrafficLevel::kNone;
  sc.distortion = true;
  sc.lidar.noise = false;
  const semlio::sim::Simulator sim(sc);
  semlio::sim::ImuConfig ic;
  ic.noise = false;
  ic.rate_hz = sc.imu_rate_hz;
  const auto imu = semlio::sim::simulate_imu(sim.ego(), ic, 0.0, 3.2);
  semlio::ImuDeskewConfig c;
  c.T_imu_lidar = ic.T_imu_body * sim.T_body_lidar();
  ImuDeskew imu_deskew(c);
  imu_deskew.set_imu(imu.samples);
  const ConstantVelocityDeskew cv_deskew;
  for (const std::size_t i : {std::size_t{5}, std::size_t{25}}) {
    const semlio::sim::Frame f = sim.frame(i);
    const double stamp = f.scan.stamp_s;
    REQUIRE(f.scan.has_times());
    // Ground truth per the simulator's documentation: p_start = T(stamp)^-1 T(t_i) p_i.
    std::vector<Eigen::Vector3d> expected(f.scan.size());
    const SE3d T_start_world = sim.T_world_lidar(stamp).inverse();
    for (std::size_t k = 0; k < f.scan.size(); ++k) {
      expected[k] = T_start_world * (sim.T_world_lidar(stamp + static_cast<double>(f.scan.times_s[k])) *
                                     f.scan.points[k].cast<double>());
    }
    const auto worst = [&](const Scan& scan) {
      double w = 0.0;
      for (std::size_t k = 0; k < scan.size(); ++k) w = std::max(w, (scan.points[k].cast<double>() - expected[k]).norm());
      return w;
    };
    // Prediction: the true frame-to-frame motion (what a converged odometry would predict).
    const SE3d T_prev_current = sim.T_world_lidar(stamp - 0.1).inverse() * sim.T_world_lidar(stamp);
    Scan a = f.scan;
    imu_deskew.deskew(a, T_prev_current);
    Scan b = f.scan;
    cv_deskew.deskew(b, sim.T_world_lidar(stamp).inverse() * sim.T_world_lidar(stamp + 0.1));
    // With the full state at the sweep start (velocity and gravity in the lidar frame).
    const auto st = sim.ego().state(stamp);
    const Eigen::Matrix3d R_lidar_world = sim.T_world_lidar(stamp).rotation().transpose();
    const Eigen::Vector3d v_world = st.velocity_world_mps + st.T_world_body.rotation() *
                                                                st.angular_velocity_body_radps.cross(sim.T_body_lidar().translation());
    ImuDeskew full(c);
    full.set_imu(imu.samples);
    full.set_motion(R_lidar_world * v_world, R_lidar_world * Eigen::Vector3d(0.0, 0.0, -ic.gravity_mps2));
    Scan m = f.scan;
    full.deskew(m, SE3d());
    INFO("frame " << i << ": raw " << worst(f.scan) << " m, IMU " << worst(a) << " m, IMU + state " << worst(m)
                  << " m, constant velocity " << worst(b) << " m");
    CHECK(worst(f.scan) > 0.05);
    CHECK(worst(a) < 0.01);
    CHECK(worst(m) < 0.01);
    CHECK(worst(b) < 0.01);
  }
}

TEST_CASE("deskew rejects bad input with typed errors", "[imu]") {
  const SE3d::Vector6 xi = fast_turn();
  const Sweep s = make_sweep(screw(SE3d(), xi), 0.1, 10.0, 200);
  SECTION("scan without per-point times") {
    Scan scan = s.distorted;
    scan.times_s.clear();
    CHECK_THROWS_WITH(ConstantVelocityDeskew{}.deskew(scan, SE3d()), Catch::Contains("times_s"));
    CHECK_THROWS_AS(ImuDeskew{}.deskew(scan, SE3d()), semlio::ValueError);
    Scan empty;
    CHECK_NOTHROW(ConstantVelocityDeskew{}.deskew(empty, SE3d()));
  }
  SECTION("non-finite point time") {
    Scan scan = s.distorted;
    scan.times_s[17] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(ConstantVelocityDeskew{}.deskew(scan, SE3d()), Catch::Contains("times_s[17]"));
    scan.times_s[17] = -0.01F;
    CHECK_THROWS_WITH(ImuDeskew{}.deskew(scan, SE3d()), Catch::Contains("times_s[17]"));
  }
  SECTION("bad config") {
    CHECK_THROWS_WITH(ConstantVelocityDeskew({.frame_period_s = 0.0}), Catch::Contains("frame_period_s"));
    CHECK_THROWS_AS(ImuDeskew({.sweep_period_s = -1.0}), semlio::ConfigError);
  }
  auto imu = constant_gyro(xi.tail<3>(), SE3d(), 9.98, 10.13, 100.0);
  ImuDeskew d;
  Scan scan = s.distorted;
  SECTION("IMU not covering the sweep") {
    d.set_imu(std::vector<ImuSample>(imu.begin(), imu.begin() + 8));  // ends at 10.05
    CHECK_THROWS_AS(d.deskew(scan, SE3d()), semlio::ValueError);
    CHECK_THROWS_WITH(d.deskew(scan, SE3d()), Catch::Contains("do not cover"));
    d.set_imu(std::vector<ImuSample>(imu.begin() + 3, imu.end()));  // starts at 10.01
    CHECK_THROWS_WITH(d.deskew(scan, SE3d()), Catch::Contains("do not cover"));
    d.set_imu({});
    CHECK_THROWS_WITH(d.deskew(scan, SE3d()), Catch::Contains("no IMU samples"));
  }
  SECTION("IMU time going backwards") {
    std::swap(imu[5], imu[6]);
    d.set_imu(imu);
    CHECK_THROWS_WITH(d.deskew(scan, SE3d()), Catch::Contains("backwards") && Catch::Contains("sample 6"));
  }
  SECTION("non-finite IMU value inside the sweep") {
    imu[7].accel_mps2.x() = std::numeric_limits<double>::infinity();
    d.set_imu(imu);
    CHECK_THROWS_WITH(d.deskew(scan, SE3d()), Catch::Contains("sample 7") && Catch::Contains("non-finite"));
  }
  SECTION("IMU gap") {
    imu.erase(imu.begin() + 4, imu.begin() + 12);  // 0.09 s gap inside the sweep
    ImuDeskew strict({.max_gap_s = 0.05});
    strict.set_imu(imu);
    CHECK_THROWS_WITH(strict.deskew(scan, SE3d()), Catch::Contains("gap") && Catch::Contains("sample 3"));
    d.set_imu(imu);  // default max_gap_s 0.15 accepts it
    CHECK_NOTHROW(d.deskew(scan, SE3d()));
  }
  SECTION("samples from an attached ImuBuffer (the odometry slot's way)") {
    semlio::ImuBuffer buffer;
    ImuDeskew attached(buffer, semlio::ImuDeskewConfig{});
    const ImuDeskew copy = attached;  // copies read the same buffer
    CHECK_THROWS_WITH(copy.deskew(scan, SE3d::exp(0.1 * xi)), Catch::Contains("no IMU samples"));
    for (const auto& m : imu) buffer.push(m);
    copy.deskew(scan, SE3d::exp(0.1 * xi));
    CHECK(max_error(scan, s, SE3d()) < 1e-3);
  }
  SECTION("a valid stream works and keeps the scan's other fields") {
    d.set_imu(imu);
    scan.intensity.assign(scan.size(), 0.5F);
    d.deskew(scan, SE3d::exp(0.1 * xi));
    CHECK(scan.intensity.size() == scan.size());
    CHECK(max_error(scan, s, SE3d()) < 1e-3);
  }
}

TEST_CASE("poses_at_sweep_start re-times a constant-velocity trajectory exactly", "[imu]") {
  const SE3d T0(SO3d::exp(Eigen::Vector3d(0.0, 0.0, 0.4)), Eigen::Vector3d(1.0, 2.0, 0.0));
  const SE3d::Vector6 xi = fast_turn();
  const PoseAt pose = screw(T0, xi);
  std::vector<SE3d> starts;
  std::vector<SE3d> mids;
  std::vector<SE3d> ends;
  std::vector<double> stamps;
  for (const double t : {0.0, 0.1, 0.2, 0.4, 0.5}) {  // one frame skipped: the span comes from the stamps
    stamps.push_back(t);
    starts.push_back(pose(t));
    mids.push_back(pose(t + 0.05));
    ends.push_back(pose(t + 0.1));
  }
  const auto worst = [&](const std::vector<SE3d>& got) {
    double w = 0.0;
    for (std::size_t i = 0; i < got.size(); ++i) {
      w = std::max(w, (got[i].translation() - starts[i].translation()).norm());
      w = std::max(w, (got[i].so3().inverse() * starts[i].so3()).angle());
    }
    return w;
  };
  CHECK(worst(mids) > 0.5);
  CHECK(worst(semlio::poses_at_sweep_start(mids, stamps, DeskewTarget::kMiddle, 0.1)) < 1e-9);
  CHECK(worst(semlio::poses_at_sweep_start(ends, stamps, DeskewTarget::kEnd, 0.1)) < 1e-9);
  CHECK(worst(semlio::poses_at_sweep_start(starts, stamps, DeskewTarget::kStart, 0.1)) == 0.0);
  CHECK_THROWS_AS(semlio::poses_at_sweep_start(mids, {0.0}, DeskewTarget::kMiddle, 0.1), semlio::ValueError);
}

}  // namespace test_deskew
