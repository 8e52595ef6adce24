// IMU preintegration: exact deltas on a noise-free simulated IMU, covariance
// consistency on a noisy one, bias Jacobians vs re-integration, bad input.
#include <catch2/catch.hpp>

#include <Eigen/Core>
#include <Eigen/Cholesky>

#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/imu/imu_buffer.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/trajectory.hpp>

namespace test_preintegration {  // one namespace per test file: the area compiles as one TU

using semlio::ImuBias;
using semlio::ImuPreintegration;
using semlio::ImuSample;
using semlio::NavState;
using semlio::PreintegrationConfig;
using semlio::SE3d;
using semlio::SO3d;
using semlio::Vector9d;
using semlio::sim::ImuConfig;
using semlio::sim::Trajectory;
using semlio::sim::TrajectoryConfig;

namespace {

// Corners, a climb with a bend, a stop: every IMU term is exercised (~70 s).
const Trajectory& test_drive() {
  static const Trajectory tr = [] {
    TrajectoryConfig c;
    c.stop_at_arclength_m = {260.0};
    c.stop_duration_s = 3.0;
    return Trajectory::through({{0, 0, 0}, {150, 0, 0}, {150, 80, 5}, {100, 140, 6}, {0, 140, 0}, {0, 40, -2}}, c);
  }();
  return tr;
}

// A rotated, offset IMU, so lever-arm and frame mistakes show.
SE3d tilted_extrinsic() { return SE3d(SO3d::exp(Eigen::Vector3d(0.02, -0.03, 0.5)), Eigen::Vector3d(0.81, -0.32, 0.8)); }

// Exact IMU navigation state from the trajectory (IMU mounted at T_imu_body).
NavState truth(const Trajectory& tr, const SE3d& T_imu_body, double t) {
  const auto s = tr.state(t);
  const SE3d T_body_imu = T_imu_body.inverse();
  const SE3d T_world_imu = s.T_world_body * T_body_imu;
  NavState x;
  x.R_world_imu = T_world_imu.so3();
  x.p_world_m = T_world_imu.translation();
  x.v_world_mps = s.velocity_world_mps +
                  s.T_world_body.rotation() * s.angular_velocity_body_radps.cross(T_body_imu.translation());
  return x;
}

PreintegrationConfig noise_free_config() {
  PreintegrationConfig c;
  c.max_gap_s = 0.05;
  return c;
}

ImuConfig sim_config(bool noise, double rate_hz, const SE3d& T_imu_body) {
  ImuConfig c;
  c.noise = noise;
  c.rate_hz = rate_hz;
  c.T_imu_body = T_imu_body;
  return c;
}

}  // namespace

TEST_CASE("noise-free IMU: preintegrated deltas match the ground truth to 1e-6", "[imu]") {
  const Trajectory& tr = test_drive();
  const SE3d T_imu_body = tilted_extrinsic();
  // 200 Hz: the second-order scheme's O(dt^2) error is then below 1e-6 over a
  // 0.1 s sweep even in the bends (at 100 Hz it is a few 1e-6 there; checked below).
  const auto imu = semlio::sim::simulate_imu(tr, sim_config(false, 200.0, T_imu_body), 0.0, 60.0);
  ImuPreintegration pre(noise_free_config());
  double worst_R = 0.0;
  double worst_v = 0.0;
  double worst_p = 0.0;
  for (double t_i = 0.5037; t_i + 0.1 < 60.0; t_i += 1.3) {  // window ends between samples
    const double t_j = t_i + 0.1;
    pre.integrate(imu.samples, t_i, t_j, ImuBias{});
    const NavState xi = truth(tr, T_imu_body, t_i);
    const NavState xj = truth(tr, T_imu_body, t_j);
    const Vector9d r = pre.residual(xi, xj, ImuBias{});
    worst_R = std::max(worst_R, r.segment<3>(0).norm());
    worst_v = std::max(worst_v, r.segment<3>(3).norm());
    worst_p = std::max(worst_p, r.segment<3>(6).norm());
    const NavState pj = pre.predict(xi);
    CHECK((pj.p_world_m - xj.p_world_m).norm() < 1e-6);
    CHECK((pj.v_world_mps - xj.v_world_mps).norm() < 1e-6);
    CHECK((pj.R_world_imu.inverse() * xj.R_world_imu).angle() < 1e-6);
    REQUIRE(pre.delta_t_s() == Approx(0.1).margin(1e-12));
  }
  INFO("worst |r_R| " << worst_R << " rad, |r_v| " << worst_v << " m/s, |r_p| " << worst_p << " m");
  CHECK(worst_R < 1e-6);
  CHECK(worst_v < 1e-6);
  CHECK(worst_p < 1e-6);
}

TEST_CASE("noise-free IMU: error shrinks as dt^2 (second-order scheme)", "[imu]") {
  const Trajectory& tr = test_drive();
  const SE3d T_imu_body = tilted_extrinsic();
  const auto worst_v = [&](double rate_hz) {
    const auto imu = semlio::sim::simulate_imu(tr, sim_config(false, rate_hz, T_imu_body), 20.0, 40.0);
    ImuPreintegration pre(noise_free_config());
    double worst = 0.0;
    for (double t_i = 20.2; t_i + 1.0 < 40.0; t_i += 2.0) {
      pre.integrate(imu.samples, t_i, t_i + 1.0, ImuBias{});
      const Vector9d r = pre.residual(truth(tr, T_imu_body, t_i), truth(tr, T_imu_body, t_i + 1.0), ImuBias{});
      worst = std::max(worst, r.norm());
    }
    return worst;
  };
  const double e50 = worst_v(50.0);
  const double e100 = worst_v(100.0);
  INFO("1 s windows: worst residual " << e50 << " at 50 Hz, " << e100 << " at 100 Hz");
  CHECK(e100 < 1e-4);
  CHECK(e100 < e50 / 3.0);  // ~4x for a second-order scheme, 2x for first order
}

TEST_CASE("noisy IMU: errors stay within the propagated covariance", "[imu]") {
  const Trajectory& tr = test_drive();
  const SE3d T_imu_body = tilted_extrinsic();
  const double duration = tr.duration_s();
  ImuConfig ic = sim_config(true, 100.0, T_imu_body);
  ic.seed = 7;
  const auto imu = semlio::sim::simulate_imu(tr, ic, 0.0, duration);
  PreintegrationConfig pc;
  pc.gyro_noise_density_radps_per_sqrthz = ic.gyro_noise_density;
  pc.accel_noise_density_mps2_per_sqrthz = ic.accel_noise_density;
  pc.gravity_world_mps2 = Eigen::Vector3d(0.0, 0.0, -ic.gravity_mps2);
  ImuPreintegration pre(pc);

  // Disjoint 0.3 s windows (independent noise), ends between samples.
  const double chi2_9_95 = 16.918977604620448;  // 95% quantile of chi-square, 9 dof
  std::size_t n = 0;
  std::size_t inside = 0;
  double nees_sum = 0.0;
  for (double t_i = 0.0123; t_i + 0.3 < duration && n < 200; t_i += 0.33) {
    const double t_j = t_i + 0.3;
    const auto k = static_cast<std::size_t>(t_i * ic.rate_hz);
    ImuBias b;  // the simulator's true bias at the window start (its walk is negligible over 0.3 s)
    b.gyro_radps = imu.gyro_bias_radps[k];
    b.accel_mps2 = imu.accel_bias_mps2[k];
    pre.integrate(imu.samples, t_i, t_j, b);
    const Vector9d r = pre.residual(truth(tr, T_imu_body, t_i), truth(tr, T_imu_body, t_j), b);
    const Eigen::LDLT<semlio::Matrix9d> ldlt(pre.covariance());
    REQUIRE(ldlt.info() == Eigen::Success);
    const double d2 = r.dot(ldlt.solve(r));
    nees_sum += d2;
    inside += d2 <= chi2_9_95 ? 1U : 0U;
    ++n;
  }
  REQUIRE(n == 200);
  const double fraction = static_cast<double>(inside) / static_cast<double>(n);
  const double mean_nees = nees_sum / static_cast<double>(n);
  INFO("inside the 95% ellipsoid: " << inside << " / " << n << ", mean NEES " << mean_nees << " (9 expected)");
  // A calibrated covariance puts 95% inside on average; with 200 windows the
  // binomial std of the fraction is 1.5%, so allow 2 std below 95%.
  CHECK(fraction >= 0.95 - 2.0 * std::sqrt(0.95 * 0.05 / 200.0));
  // And it is not simply inflated: mean NEES near 9 (std of the mean ~0.3).
  CHECK(mean_nees > 7.5);
  CHECK(mean_nees < 10.5);
}

TEST_CASE("bias Jacobians match re-integration with a perturbed bias", "[imu]") {
  const Trajectory& tr = test_drive();
  const auto imu = semlio::sim::simulate_imu(tr, sim_config(false, 100.0, tilted_extrinsic()), 10.0, 16.0);
  ImuBias b0;
  b0.gyro_radps = Eigen::Vector3d(0.01, -0.02, 0.015);
  b0.accel_mps2 = Eigen::Vector3d(0.1, 0.05, -0.2);
  const double t_i = 10.55;
  const double t_j = 14.05;  // long window in the climbing bend: large Jacobians
  ImuPreintegration pre(noise_free_config(), b0);
  pre.integrate(imu.samples, t_i, t_j, b0);
  const auto& J = pre.jacobians();
  for (int axis = 0; axis < 6; ++axis) {
    const double eps = axis < 3 ? 1e-6 : 1e-5;
    ImuBias bp = b0;
    ImuBias bm = b0;
    if (axis < 3) {
      bp.gyro_radps[axis] += eps;
      bm.gyro_radps[axis] -= eps;
    } else {
      bp.accel_mps2[axis - 3] += eps;
      bm.accel_mps2[axis - 3] -= eps;
    }
    ImuPreintegration pp(noise_free_config());
    ImuPreintegration pm(noise_free_config());
    pp.integrate(imu.samples, t_i, t_j, bp);
    pm.integrate(imu.samples, t_i, t_j, bm);
    const Eigen::Vector3d dR = (pm.delta_R().inverse() * pp.delta_R()).log() / (2.0 * eps);
    const Eigen::Vector3d dv = (pp.delta_v_mps() - pm.delta_v_mps()) / (2.0 * eps);
    const Eigen::Vector3d dp = (pp.delta_p_m() - pm.delta_p_m()) / (2.0 * eps);
    INFO("bias axis " << axis);
    if (axis < 3) {
      const Eigen::Vector3d jR = J.J_dR_bg.col(axis);
      CHECK((dR - jR).norm() < 1e-5 * std::max(1.0, jR.norm()));
      CHECK((dv - J.J_dv_bg.col(axis)).norm() < 1e-5 * std::max(1.0, J.J_dv_bg.col(axis).norm()));
      CHECK((dp - J.J_dp_bg.col(axis)).norm() < 1e-5 * std::max(1.0, J.J_dp_bg.col(axis).norm()));
      CHECK(J.J_dp_bg.col(axis).norm() > 1e-2);  // not trivially zero
    } else {
      CHECK((dR).norm() < 1e-9);  // rotation does not depend on the accel bias
      CHECK((dv - J.J_dv_ba.col(axis - 3)).norm() < 1e-5 * std::max(1.0, J.J_dv_ba.col(axis - 3).norm()));
      CHECK((dp - J.J_dp_ba.col(axis - 3)).norm() < 1e-5 * std::max(1.0, J.J_dp_ba.col(axis - 3).norm()));
    }
  }

  // Bias correction (eq. 44) vs re-integration at a nearby bias: error is second order.
  ImuBias b1 = b0;
  b1.gyro_radps += Eigen::Vector3d(2e-4, -1e-4, 3e-4);
  b1.accel_mps2 += Eigen::Vector3d(-3e-3, 2e-3, 1e-3);
  const auto corrected_error = [&](const ImuBias& b) {
    ImuPreintegration re(noise_free_config());
    re.integrate(imu.samples, t_i, t_j, b);
    Vector9d e;
    e << (pre.delta_R(b).inverse() * re.delta_R()).log(), pre.delta_v_mps(b) - re.delta_v_mps(),
        pre.delta_p_m(b) - re.delta_p_m();
    const double uncorrected = (pre.delta_p_m() - re.delta_p_m()).norm() + (pre.delta_v_mps() - re.delta_v_mps()).norm();
    return std::pair{e.norm(), uncorrected};
  };
  ImuBias b_half = b0;
  b_half.gyro_radps += 0.5 * (b1.gyro_radps - b0.gyro_radps);
  b_half.accel_mps2 += 0.5 * (b1.accel_mps2 - b0.accel_mps2);
  const auto [e1, u1] = corrected_error(b1);
  const auto [e_half, u_half] = corrected_error(b_half);
  INFO("corrected error " << e1 << " (uncorrected " << u1 << "), at half the change " << e_half << " (" << u_half << ")");
  CHECK(e1 < 1e-2 * u1);              // first-order correction removes almost all of it
  CHECK(e1 / e_half > 3.5);           // what remains is second order (x4 per doubling)
  CHECK(e1 / e_half < 4.5);
  CHECK(u1 / u_half == Approx(2.0).epsilon(0.05));
}

TEST_CASE("preintegration of a body at rest", "[imu]") {
  // Level and still: accel reads +g up; deltas are zero, predict keeps the state.
  std::vector<ImuSample> s;
  for (int k = 0; k <= 20; ++k) {
    s.push_back(ImuSample{0.01 * k, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 9.80665)});
  }
  ImuPreintegration pre;
  pre.integrate(s, 0.0, 0.2, ImuBias{});
  CHECK(pre.delta_R().angle() < 1e-15);
  CHECK(pre.delta_v_mps().isApprox(Eigen::Vector3d(0.0, 0.0, 9.80665 * 0.2), 1e-12));
  CHECK(pre.delta_p_m().isApprox(Eigen::Vector3d(0.0, 0.0, 0.5 * 9.80665 * 0.04), 1e-12));
  NavState x;
  x.p_world_m = Eigen::Vector3d(1.0, 2.0, 3.0);
  const NavState y = pre.predict(x);
  CHECK((y.p_world_m - x.p_world_m).norm() < 1e-12);
  CHECK(y.v_world_mps.norm() < 1e-12);
  // Covariance: position variance of integrated white accel noise is sigma^2 T^3 / 3.
  const double sa = pre.config().accel_noise_density_mps2_per_sqrthz;
  CHECK(pre.covariance()(8, 8) == Approx(sa * sa * 0.008 / 3.0).epsilon(0.01));
  CHECK(pre.covariance()(5, 5) == Approx(sa * sa * 0.2).epsilon(1e-9));
  // Horizontal velocity also collects gyro noise tilting gravity: + g^2 sigma_g^2 T^3 / 3.
  const double sg = pre.config().gyro_noise_density_radps_per_sqrthz;
  const double g2 = 9.80665 * 9.80665;
  CHECK(pre.covariance()(3, 3) == Approx(sa * sa * 0.2 + g2 * sg * sg * 0.008 / 3.0).epsilon(1e-3));
  CHECK(pre.covariance()(4, 4) == Approx(pre.covariance()(3, 3)).epsilon(1e-9));
  CHECK(pre.covariance()(0, 0) == Approx(sg * sg * 0.2).epsilon(1e-9));
  CHECK(pre.bias_walk_covariance()(0, 0) == Approx(2e-6 * 2e-6 * 0.2));
}

TEST_CASE("preintegration rejects bad IMU input with ValueError", "[imu]") {
  std::vector<ImuSample> s;
  for (int k = 0; k <= 10; ++k) s.push_back(ImuSample{1.0 + 0.01 * k, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  ImuPreintegration pre;
  SECTION("samples start after the window") {
    CHECK_THROWS_AS(pre.integrate(s, 0.99, 1.05, ImuBias{}), semlio::ValueError);
    CHECK_THROWS_WITH(pre.integrate(s, 0.99, 1.05, ImuBias{}), Catch::Contains("do not cover"));
  }
  SECTION("samples end before the window") {
    CHECK_THROWS_WITH(pre.integrate(s, 1.02, 1.2, ImuBias{}), Catch::Contains("do not cover") && Catch::Contains("1.200000"));
  }
  SECTION("time going backwards") {
    s[6].stamp_s = 1.045;  // before sample 5 at 1.05
    CHECK_THROWS_AS(pre.integrate(s, 1.0, 1.1, ImuBias{}), semlio::ValueError);
    CHECK_THROWS_WITH(pre.integrate(s, 1.0, 1.1, ImuBias{}),
                      Catch::Contains("backwards") && Catch::Contains("sample 6") && Catch::Contains("sample 5"));
  }
  SECTION("repeated stamp") {
    s[3].stamp_s = s[2].stamp_s;
    CHECK_THROWS_WITH(pre.integrate(s, 1.0, 1.1, ImuBias{}), Catch::Contains("sample 3"));
  }
  SECTION("gap larger than max_gap_s") {
    s.erase(s.begin() + 4, s.begin() + 9);  // 1.03 -> 1.09
    PreintegrationConfig c;
    c.max_gap_s = 0.05;
    ImuPreintegration p(c);
    CHECK_THROWS_AS(p.integrate(s, 1.0, 1.1, ImuBias{}), semlio::ValueError);
    CHECK_THROWS_WITH(p.integrate(s, 1.0, 1.1, ImuBias{}), Catch::Contains("gap") && Catch::Contains("sample 3"));
    // A gap outside the window does not matter.
    CHECK_NOTHROW(p.integrate(s, 1.0, 1.03, ImuBias{}));
  }
  SECTION("non-finite measurement") {
    s[4].gyro_radps.y() = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH(pre.integrate(s, 1.0, 1.1, ImuBias{}), Catch::Contains("sample 4") && Catch::Contains("non-finite"));
  }
  SECTION("reversed window and empty input") {
    CHECK_THROWS_AS(pre.integrate(s, 1.05, 1.02, ImuBias{}), semlio::ValueError);
    CHECK_THROWS_AS(pre.integrate(std::vector<ImuSample>{}, 1.0, 1.1, ImuBias{}), semlio::ValueError);
  }
  SECTION("bad config") {
    PreintegrationConfig c;
    c.accel_noise_density_mps2_per_sqrthz = -1.0;
    CHECK_THROWS_WITH(ImuPreintegration(c), Catch::Contains("accel_noise_density_mps2_per_sqrthz"));
    c = PreintegrationConfig{};
    c.max_gap_s = 0.0;
    CHECK_THROWS_AS(ImuPreintegration(c), semlio::ConfigError);
  }
  SECTION("a window inside the samples works, also on exact sample times") {
    CHECK_NOTHROW(pre.integrate(s, 1.0, 1.1, ImuBias{}));
    CHECK(pre.delta_t_s() == Approx(0.1));
    CHECK_NOTHROW(pre.integrate(s, 1.0333, 1.0333, ImuBias{}));
    CHECK(pre.delta_t_s() == 0.0);
  }
}

TEST_CASE("ImuBuffer keeps time order and extracts covering ranges", "[imu]") {
  semlio::ImuBuffer buf;
  for (int k = 0; k < 10; ++k) buf.push(ImuSample{0.1 * k, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  CHECK_THROWS_WITH(buf.push(ImuSample{0.85, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}),
                    Catch::Contains("backwards"));
  CHECK(buf.size() == 10);
  const auto span = buf.covering(0.25, 0.55, 0.2);
  REQUIRE(span.size() == 5);  // 0.2 .. 0.6
  CHECK(span.front().stamp_s == Approx(0.2));
  CHECK(span.back().stamp_s == Approx(0.6));
  CHECK_THROWS_AS(buf.covering(0.25, 1.5, 0.2), semlio::ValueError);
  buf.drop_before(0.45);
  CHECK(buf.samples().front().stamp_s == Approx(0.4));
  CHECK_NOTHROW(buf.covering(0.45, 0.9, 0.2));
}

}  // namespace test_preintegration
