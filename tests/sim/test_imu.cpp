#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/rng.hpp>
#include <semlio/sim/trajectory.hpp>

namespace test_imu {  // one namespace per test file: the area compiles as one TU

using semlio::ImuSample;
using semlio::SE3d;
using semlio::SO3d;
using semlio::sim::ImuConfig;
using semlio::sim::Trajectory;
using semlio::sim::TrajectoryConfig;

namespace {

// A corner, a climb with a bend on it, a stop: every IMU term is exercised.
Trajectory test_drive() {
  TrajectoryConfig c;
  c.stop_at_arclength_m = {260.0};
  c.stop_duration_s = 3.0;
  return Trajectory::through({{0, 0, 0}, {150, 0, 0}, {150, 80, 5}, {100, 140, 6}, {0, 140, 0}}, c);
}

// Extrinsic with a real rotation and lever arm, so frame mistakes show.
SE3d tilted_extrinsic() {
  return SE3d(SO3d::exp(Eigen::Vector3d(0.02, -0.03, 0.5)), Eigen::Vector3d(0.81, -0.32, 0.80));
}

struct ImuState {
  Eigen::Matrix3d R;  // R_world_imu
  Eigen::Vector3d v;  // world velocity of the IMU
  Eigen::Vector3d p;  // world position of the IMU
};

ImuState exact_state(const Trajectory& tr, const SE3d& T_imu_body, double t) {
  const auto s = tr.state(t);
  const SE3d T_body_imu = T_imu_body.inverse();
  const SE3d T_world_imu = s.T_world_body * T_body_imu;
  const Eigen::Vector3d v = s.velocity_world_mps + s.T_world_body.rotation() *
                                                       s.angular_velocity_body_radps.cross(T_body_imu.translation());
  return {T_world_imu.rotation(), v, T_world_imu.translation()};
}

ImuState deriv(const ImuState& x, const Eigen::Vector3d& w, const Eigen::Vector3d& f) {
  const Eigen::Vector3d g(0, 0, -9.80665);
  return {x.R * semlio::hat(w), x.R * f + g, x.v};
}

ImuState axpy(const ImuState& x, double h, const ImuState& d) { return {x.R + h * d.R, x.v + h * d.v, x.p + h * d.p}; }

// Classic RK4 step of length h with measurements at t, t + h/2, t + h.
void rk4(ImuState& x, double h, const ImuSample& m0, const ImuSample& m1, const ImuSample& m2) {
  const ImuState k1 = deriv(x, m0.gyro_radps, m0.accel_mps2);
  const ImuState k2 = deriv(axpy(x, h / 2, k1), m1.gyro_radps, m1.accel_mps2);
  const ImuState k3 = deriv(axpy(x, h / 2, k2), m1.gyro_radps, m1.accel_mps2);
  const ImuState k4 = deriv(axpy(x, h, k3), m2.gyro_radps, m2.accel_mps2);
  x.R += h / 6 * (k1.R + 2 * k2.R + 2 * k3.R + k4.R);
  x.v += h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v);
  x.p += h / 6 * (k1.p + 2 * k2.p + 2 * k3.p + k4.p);
  x.R = SO3d(Eigen::Matrix3d(x.R)).matrix();  // back onto SO(3)
}

ImuSample midpoint(const ImuSample& a, const ImuSample& b) {
  return {0.5 * (a.stamp_s + b.stamp_s), 0.5 * (a.gyro_radps + b.gyro_radps), 0.5 * (a.accel_mps2 + b.accel_mps2)};
}

struct Drift {
  double position_m = 0.0;
  double rotation_rad = 0.0;
};

// Integrates noise-free IMU samples from t0 for 10 s. With `half_steps` the
// stream is sampled at twice the step rate (exact midpoints); otherwise the
// midpoint is the average of neighbouring samples.
Drift integrate_10s(const Trajectory& tr, const SE3d& T_imu_body, double t0, double rate_hz, bool half_steps) {
  ImuConfig cfg;
  cfg.noise = false;
  cfg.T_imu_body = T_imu_body;
  cfg.rate_hz = half_steps ? 2.0 * rate_hz : rate_hz;
  const auto imu = semlio::sim::simulate_imu(tr, cfg, t0, t0 + 10.0);
  ImuState x = exact_state(tr, T_imu_body, t0);
  const double h = 1.0 / rate_hz;
  Drift d;
  const std::size_t stride = half_steps ? 2 : 1;
  for (std::size_t k = 0; k + stride < imu.samples.size(); k += stride) {
    const ImuSample& a = imu.samples[k];
    const ImuSample& c = imu.samples[k + stride];
    const ImuSample m = half_steps ? imu.samples[k + 1] : midpoint(a, c);
    rk4(x, h, a, m, c);
    const ImuState truth = exact_state(tr, T_imu_body, c.stamp_s);
    d.position_m = std::max(d.position_m, (x.p - truth.p).norm());
    d.rotation_rad = std::max(d.rotation_rad, SO3d(Eigen::Matrix3d(truth.R.transpose() * x.R)).angle());
  }
  return d;
}

double time_at_arclength(const Trajectory& tr, double s) {
  double lo = 0.0;
  double hi = tr.duration_s();
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (tr.arclength_m(mid) < s ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

TEST_CASE("imu at rest reads +g up and no rotation", "[sim]") {
  const Trajectory tr = test_drive();
  const ImuSample m = semlio::sim::ideal_imu_sample(tr, SE3d(), 0.0);
  CHECK((m.accel_mps2 - Eigen::Vector3d(0, 0, 9.80665)).norm() < 1e-9);
  CHECK(m.gyro_radps.norm() < 1e-12);
  // Rotated mount: the reading is the same vector in the IMU's axes.
  const SE3d T = tilted_extrinsic();
  const ImuSample r = semlio::sim::ideal_imu_sample(tr, T, 0.0);
  CHECK((r.accel_mps2 - T.rotation() * Eigen::Vector3d(0, 0, 9.80665)).norm() < 1e-9);
}

TEST_CASE("integrating the noise-free imu reproduces the trajectory (< 1 cm over 10 s)", "[sim]") {
  const Trajectory tr = test_drive();
  const SE3d T = tilted_extrinsic();
  const double t_corner = time_at_arclength(tr, 125.0);  // enters the first corner, then climbs
  const double t_hill = time_at_arclength(tr, 200.0);    // climbing bend, then the stop
  for (double t0 : {0.0, t_corner, t_hill}) {
    INFO("t0 = " << t0);
    const Drift exact_mid = integrate_10s(tr, T, t0, 100.0, true);
    CHECK(exact_mid.position_m < 0.01);
    CHECK(exact_mid.rotation_rad < 1e-4);
    const Drift interp_mid = integrate_10s(tr, T, t0, 100.0, false);
    CHECK(interp_mid.position_m < 0.01);
    CHECK(interp_mid.rotation_rad < 1e-4);
  }
}

TEST_CASE("noisy imu: white noise and bias walk match the densities", "[sim]") {
  const Trajectory tr = test_drive();
  ImuConfig cfg;
  cfg.rate_hz = 200.0;
  const auto imu = semlio::sim::simulate_imu(tr, cfg, 0.0, 60.0);
  REQUIRE(imu.samples.size() == 12001);
  double sg = 0.0;
  double sa = 0.0;
  double swg = 0.0;
  double swa = 0.0;
  double mean_g = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < imu.samples.size(); ++k) {
    const ImuSample truth = semlio::sim::ideal_imu_sample(tr, cfg.T_imu_body, imu.samples[k].stamp_s);
    const Eigen::Vector3d ng = imu.samples[k].gyro_radps - truth.gyro_radps - imu.gyro_bias_radps[k];
    const Eigen::Vector3d na = imu.samples[k].accel_mps2 - truth.accel_mps2 - imu.accel_bias_mps2[k];
    sg += ng.squaredNorm();
    sa += na.squaredNorm();
    mean_g += ng.sum();
    if (k > 0) {
      swg += (imu.gyro_bias_radps[k] - imu.gyro_bias_radps[k - 1]).squaredNorm();
      swa += (imu.accel_bias_mps2[k] - imu.accel_bias_mps2[k - 1]).squaredNorm();
    }
    ++n;
  }
  const auto N = static_cast<double>(3 * n);
  const double rate = cfg.rate_hz;
  // 36000 draws: the sample std is within ~1% of the truth (3 sigma ~ 1.1%).
  CHECK(std::sqrt(sg / N) == Approx(cfg.gyro_noise_density * std::sqrt(rate)).epsilon(0.02));
  CHECK(std::sqrt(sa / N) == Approx(cfg.accel_noise_density * std::sqrt(rate)).epsilon(0.02));
  CHECK(std::abs(mean_g / N) < 4.0 * cfg.gyro_noise_density * std::sqrt(rate) / std::sqrt(N));
  CHECK(std::sqrt(swg / (N - 3)) == Approx(cfg.gyro_bias_random_walk / std::sqrt(rate)).epsilon(0.02));
  CHECK(std::sqrt(swa / (N - 3)) == Approx(cfg.accel_bias_random_walk / std::sqrt(rate)).epsilon(0.02));
}

TEST_CASE("imu stream: rate, stamps, noise-free mode, determinism", "[sim]") {
  const Trajectory tr = test_drive();
  ImuConfig cfg;
  const auto a = semlio::sim::simulate_imu(tr, cfg, 1.0, 3.0);
  REQUIRE(a.samples.size() == 201);  // 100 Hz, both ends included
  CHECK(a.samples.front().stamp_s == 1.0);
  CHECK(a.samples.back().stamp_s == Approx(3.0).margin(1e-12));
  const auto b = semlio::sim::simulate_imu(tr, cfg, 1.0, 3.0);
  bool identical = true;
  for (std::size_t k = 0; k < a.samples.size(); ++k) {
    identical = identical && a.samples[k].gyro_radps == b.samples[k].gyro_radps &&
                a.samples[k].accel_mps2 == b.samples[k].accel_mps2;
  }
  CHECK(identical);
  ImuConfig other = cfg;
  other.seed = 2;
  const auto c = semlio::sim::simulate_imu(tr, other, 1.0, 3.0);
  CHECK(c.samples[5].gyro_radps != a.samples[5].gyro_radps);
  ImuConfig clean = cfg;
  clean.noise = false;
  const auto d = semlio::sim::simulate_imu(tr, clean, 1.0, 3.0);
  for (std::size_t k = 0; k < d.samples.size(); k += 37) {
    const ImuSample truth = semlio::sim::ideal_imu_sample(tr, clean.T_imu_body, d.samples[k].stamp_s);
    CHECK(d.samples[k].gyro_radps == truth.gyro_radps);
    CHECK(d.samples[k].accel_mps2 == truth.accel_mps2);
    CHECK(d.gyro_bias_radps[k].norm() == 0.0);
  }
  ImuConfig bad = cfg;
  bad.rate_hz = 0.0;
  CHECK_THROWS_AS(semlio::sim::simulate_imu(tr, bad), semlio::ConfigError);
}

TEST_CASE("noise generator: deterministic, independent streams, normal moments", "[sim]") {
  semlio::sim::Xoshiro256 a(42);
  semlio::sim::Xoshiro256 b(42);
  semlio::sim::Xoshiro256 other_stream(42, 1);
  bool same = true;
  bool differs = false;
  for (int i = 0; i < 100; ++i) {
    const std::uint64_t x = a.next();
    same = same && x == b.next();
    differs = differs || x != other_stream.next();
  }
  CHECK(same);
  CHECK(differs);
  // Moments of 200k normals: mean 0 (+-4.5e-3 at 2 sigma), variance 1,
  // fourth moment 3; uniforms stay in [0, 1) with mean 1/2.
  semlio::sim::Xoshiro256 g(7);
  const int n = 200000;
  double m1 = 0.0;
  double m2 = 0.0;
  double m4 = 0.0;
  double u_min = 1.0;
  double u_max = 0.0;
  double u_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = g.normal();
    m1 += x;
    m2 += x * x;
    m4 += x * x * x * x;
    const double u = g.uniform();
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    u_sum += u;
  }
  CHECK(std::abs(m1 / n) < 0.01);
  CHECK(m2 / n == Approx(1.0).epsilon(0.01));
  CHECK(m4 / n == Approx(3.0).epsilon(0.03));
  CHECK(u_min >= 0.0);
  CHECK(u_max < 1.0);
  CHECK(u_sum / n == Approx(0.5).epsilon(0.01));
  // Counter-based draws depend only on their keys.
  CHECK(semlio::sim::Xoshiro256::hashed_uniform(1, 2, 3) == semlio::sim::Xoshiro256::hashed_uniform(1, 2, 3));
  CHECK(semlio::sim::Xoshiro256::hashed_uniform(1, 2, 3) != semlio::sim::Xoshiro256::hashed_uniform(1, 2, 4));
}

}  // namespace test_imu
