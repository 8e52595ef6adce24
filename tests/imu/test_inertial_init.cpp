// Inertial initialisation while moving: gravity direction, gyro bias and
// velocities from lidar poses + a noisy, biased simulated IMU on a drive that
// starts at speed; failure statuses for too little data, no excitation,
// inconsistent data and IMU trouble.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include <semlio/imu/inertial_init.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/rng.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

namespace test_inertial_init {  // one namespace per test file: the area compiles as one TU

using semlio::InertialInitConfig;
using semlio::InertialInitStatus;
using semlio::SE3d;
using semlio::SO3d;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Window {
  std::vector<double> stamps;
  std::vector<SE3d> T_map_lidar;
  std::vector<Eigen::Vector3d> v_map_imu;  // truth
  Eigen::Vector3d g_map;                   // truth
};

// Frames every 0.1 s over [t0, t0 + duration]; lidar = the trajectory's body;
// map = lidar at t0; poses perturbed by pose_noise (1 sigma: m, rad).
Window make_window(double t0, double duration, double pos_noise_m, double rot_noise_rad) {
  const auto& tr = semlio_test::inertial_drive();
  const SE3d T_imu_lidar = semlio_test::inertial_T_imu_body();
  Window w;
  const SE3d T_map_world = tr.pose(t0).inverse();
  semlio::sim::Xoshiro256 rng(5, 11);
  for (double t = t0; t <= t0 + duration + 1e-9; t += 0.1) {
    w.stamps.push_back(t);
    Eigen::Matrix<double, 6, 1> xi;
    xi << pos_noise_m * rng.normal(), pos_noise_m * rng.normal(), pos_noise_m * rng.normal(),
        rot_noise_rad * rng.normal(), rot_noise_rad * rng.normal(), rot_noise_rad * rng.normal();
    w.T_map_lidar.push_back(T_map_world * tr.pose(t) * SE3d::exp(xi));
    w.v_map_imu.push_back(T_map_world.rotation() * semlio_test::inertial_truth(tr, T_imu_lidar, t).v_world_mps);
  }
  w.g_map = T_map_world.rotation() * Eigen::Vector3d(0.0, 0.0, -9.80665);
  return w;
}

// Noisy IMU (the simulator's densities and small random biases) plus a known bias.
std::vector<semlio::ImuSample> noisy_imu(double t0, double t1, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                                         Eigen::Vector3d* total_bg) {
  semlio::sim::ImuConfig c;
  c.rate_hz = 100.0;
  c.T_imu_body = semlio_test::inertial_T_imu_body();
  c.seed = 3;
  auto imu = semlio::sim::simulate_imu(semlio_test::inertial_drive(), c, t0, t1);
  for (auto& s : imu.samples) {
    s.gyro_radps += bg;
    s.accel_mps2 += ba;
  }
  if (total_bg != nullptr) *total_bg = bg + imu.gyro_bias_radps.front();
  return imu.samples;
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

TEST_CASE("inertial init: gravity, gyro bias and velocity while moving", "[imu]") {
  const Eigen::Vector3d bg(0.004, -0.003, 0.005);
  const Eigen::Vector3d ba(0.03, -0.02, 0.02);
  // Two windows: the very start (already at cruise speed, nearly straight)
  // and one through the first bend.
  for (const double t0 : {0.0, 6.0}) {
    CAPTURE(t0);
    const Window w = make_window(t0, 2.0, 0.01, 0.05 * kDeg);
    Eigen::Vector3d bg_true;
    const auto samples = noisy_imu(t0, t0 + 2.2, bg, ba, &bg_true);
    REQUIRE(w.v_map_imu.front().norm() > 5.0);  // really moving at the start
    const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, samples, semlio_test::inertial_T_imu_body(),
                                               0.0, semlio::PreintegrationConfig{});
    INFO(r.message);
    REQUIRE(r.ok());
    const double g_err = angle_between(r.gravity_map_mps2, w.g_map);
    double v_err = 0.0;
    for (std::size_t k = 0; k < w.stamps.size(); ++k) v_err = std::max(v_err, (r.velocities_map_mps[k] - w.v_map_imu[k]).norm());
    INFO("gravity error " << g_err / kDeg << " deg, gyro bias error " << (r.bias.gyro_radps - bg_true).norm()
                          << " rad/s, worst velocity error " << v_err << " m/s, |g_free| " << r.gravity_free_norm_mps2);
    CHECK(g_err < 1.0 * kDeg);
    CHECK(std::abs(r.gravity_map_mps2.norm() - 9.80665) < 1e-9);
    CHECK((r.bias.gyro_radps - bg_true).norm() < 1e-3);
    CHECK(v_err < 0.1);
    CHECK(r.states.size() == w.stamps.size());
  }
}

TEST_CASE("inertial init: exact data give the exact answer", "[imu]") {
  const Window w = make_window(6.0, 2.0, 0.0, 0.0);
  const Eigen::Vector3d bg(0.004, -0.003, 0.005);
  const auto samples = semlio_test::inertial_samples(semlio_test::inertial_drive(), semlio_test::inertial_T_imu_body(),
                                                     6.0, 8.2, 100.0, bg, Eigen::Vector3d::Zero());
  const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, samples, semlio_test::inertial_T_imu_body(), 0.0,
                                             semlio::PreintegrationConfig{});
  REQUIRE(r.ok());
  CHECK(angle_between(r.gravity_map_mps2, w.g_map) < 1e-4);
  CHECK((r.bias.gyro_radps - bg).norm() < 1e-5);
  CHECK((r.velocities_map_mps.back() - w.v_map_imu.back()).norm() < 1e-3);
}

TEST_CASE("inertial init: the accel bias needs rotation, failure statuses", "[imu]") {
  const Eigen::Vector3d ba(0.1, -0.08, 0.05);
  const semlio::PreintegrationConfig pc;
  const SE3d T_imu_lidar = semlio_test::inertial_T_imu_body();
  InertialInitConfig with_ba;
  with_ba.estimate_accel_bias = true;
  {  // straight start: not exciting for the accel bias
    const Window w = make_window(0.0, 2.0, 0.0, 0.0);
    const auto s = semlio_test::inertial_samples(semlio_test::inertial_drive(), T_imu_lidar, 0.0, 2.2, 100.0,
                                                 Eigen::Vector3d::Zero(), ba);
    const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, s, T_imu_lidar, 0.0, pc, with_ba);
    CHECK(r.status == InertialInitStatus::kNotExciting);
    CHECK_FALSE(r.message.empty());
    CHECK(r.gravity_map_mps2.allFinite());
  }
  {  // through a long bend: the accel bias is recovered
    const Window w = make_window(6.0, 6.0, 0.0, 0.0);
    const auto s = semlio_test::inertial_samples(semlio_test::inertial_drive(), T_imu_lidar, 6.0, 12.2, 100.0,
                                                 Eigen::Vector3d::Zero(), ba);
    const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, s, T_imu_lidar, 0.0, pc, with_ba);
    INFO(r.message << " span " << r.rotation_span_rad << " rad; accel bias " << r.bias.accel_mps2.transpose());
    REQUIRE(r.ok());
    CHECK((r.bias.accel_mps2 - ba).norm() < 0.01);
    CHECK(angle_between(r.gravity_map_mps2, w.g_map) < 0.05 * kDeg);
  }
  const Window w = make_window(6.0, 2.0, 0.0, 0.0);
  const auto s = semlio_test::inertial_samples(semlio_test::inertial_drive(), T_imu_lidar, 6.0, 8.2, 100.0,
                                               Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  {  // too few frames
    const auto r = semlio::initialize_inertial(std::span(w.stamps).first(4), std::span(w.T_map_lidar).first(4), s,
                                               T_imu_lidar, 0.0, pc);
    CHECK(r.status == InertialInitStatus::kTooFewFrames);
  }
  {  // IMU that does not cover the frames
    const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, std::span(s).first(100), T_imu_lidar, 0.0, pc);
    CHECK(r.status == InertialInitStatus::kImuError);
    CHECK(r.message.find("cover") != std::string::npos);
  }
  {  // a wrong time offset (IMU of another stretch of road): inconsistent
    const auto early = semlio_test::inertial_samples(semlio_test::inertial_drive(), T_imu_lidar, 0.0, 8.2, 100.0,
                                                     Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, early, T_imu_lidar, -3.0, pc);
    INFO(r.message);
    CHECK(r.status == InertialInitStatus::kInconsistent);
  }
  {  // a wrong extrinsic rotation: lidar and gyro rotations disagree
    const SE3d wrong(SO3d::exp(Eigen::Vector3d(1.2, 0.0, 0.0)), T_imu_lidar.translation());
    const auto r = semlio::initialize_inertial(w.stamps, w.T_map_lidar, s, wrong, 0.0, pc);
    CHECK(r.status != InertialInitStatus::kOk);
  }
  CHECK_THROWS_AS(semlio::initialize_inertial(std::span(w.stamps).first(3), w.T_map_lidar, s, T_imu_lidar, 0.0, pc),
                  semlio::ValueError);
}

}  // namespace test_inertial_init
