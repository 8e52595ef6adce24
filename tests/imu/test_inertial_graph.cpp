// IMU factor Jacobians vs numeric differentiation; the sliding-window
// inertial graph on exact poses (states converge to the truth, a known bias
// is recovered); singular problems give a status, never NaN.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/graph/inertial_graph.hpp>
#include <semlio/imu/imu_factor.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

namespace test_inertial_graph {  // one namespace per test file: the area compiles as one TU

using semlio::ImuBias;
using semlio::ImuPreintegration;
using semlio::InertialGraph;
using semlio::InertialSolveStatus;
using semlio::Matrix15d;
using semlio::Matrix9x15d;
using semlio::NavState;
using semlio::PreintegrationConfig;
using semlio::SE3d;
using semlio::SO3d;
using semlio::Vector15d;
using semlio::Vector9d;

namespace {

PreintegrationConfig test_config() {
  PreintegrationConfig c;
  c.max_gap_s = 0.05;
  return c;
}

struct DriveResult {
  double worst_v = 0.0;        // worst velocity error of the newest state [m/s]
  double worst_p = 0.0;        // worst position error [m]
  ImuBias final_bias;          // bias of the newest state at the end
  int solves_ok = 0;
  int solves = 0;
};

// Runs the graph over [t0, t1] with states every 0.1 s, exact IMU poses as
// pose factors (sigma 1 cm / 0.1 deg), IMU with a constant bias.
DriveResult run_drive(double t0, double t1, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba) {
  const auto& tr = semlio_test::inertial_drive();
  const SE3d T_imu_body = semlio_test::inertial_T_imu_body();
  const auto samples = semlio_test::inertial_samples(tr, T_imu_body, t0 - 0.05, t1 + 0.05, 100.0, bg, ba);
  InertialGraph graph({.window_size = 8});
  Eigen::Matrix<double, 6, 6> pose_info = Eigen::Matrix<double, 6, 6>::Zero();
  pose_info.diagonal() << 1e4, 1e4, 1e4, 3.3e5, 3.3e5, 3.3e5;
  // First state: pose from truth, velocity unknown (zero guess, weak prior),
  // bias zero with a weak prior.
  NavState x0 = semlio_test::inertial_truth(tr, T_imu_body, t0);
  x0.v_world_mps.setZero();
  Vector15d sig;
  sig << 0.01, 0.01, 0.01, 1e-3, 1e-3, 1e-3, 20.0, 20.0, 20.0, 0.05, 0.05, 0.05, 0.5, 0.5, 0.5;
  Matrix15d info = sig.cwiseInverse().cwiseAbs2().asDiagonal();
  auto id = graph.add_state(t0, x0, ImuBias{});
  graph.add_prior(id, x0, ImuBias{}, info);
  graph.add_pose(id, x0.pose(), pose_info);
  DriveResult out;
  ImuPreintegration pim(test_config());
  for (double t = t0; t + 0.1 < t1 + 1e-9; t += 0.1) {
    const auto& last = graph.node(id);
    pim.integrate(samples, t, t + 0.1, last.bias);
    const NavState guess = pim.predict(last.state, last.bias);
    const auto j = graph.add_state(t + 0.1, guess, last.bias);
    graph.add_imu(id, j, pim);
    graph.add_pose(j, semlio_test::inertial_truth(tr, T_imu_body, t + 0.1).pose(), pose_info);
    const auto rep = graph.optimize();
    ++out.solves;
    out.solves_ok += rep.ok() ? 1 : 0;
    REQUIRE(graph.size() <= 8);
    id = j;
    const NavState truth = semlio_test::inertial_truth(tr, T_imu_body, t + 0.1);
    const auto& x = graph.node(j).state;
    REQUIRE(x.v_world_mps.allFinite());
    if (t > t0 + 1.0) {  // after a second the velocity is known
      out.worst_v = std::max(out.worst_v, (x.v_world_mps - truth.v_world_mps).norm());
      out.worst_p = std::max(out.worst_p, (x.p_world_m - truth.p_world_m).norm());
    }
  }
  out.final_bias = graph.node(id).bias;
  return out;
}

}  // namespace

TEST_CASE("IMU factor: analytic Jacobians match numeric differences", "[imu]") {
  const auto& tr = semlio_test::inertial_drive();
  const SE3d T_imu_body = semlio_test::inertial_T_imu_body();
  const auto samples = semlio_test::inertial_samples(tr, T_imu_body, 9.0, 12.0, 100.0, Eigen::Vector3d::Zero(),
                                                     Eigen::Vector3d::Zero());
  const ImuBias b_lin{Eigen::Vector3d(0.002, -0.001, 0.003), Eigen::Vector3d(0.05, -0.02, 0.03)};
  ImuPreintegration pim(test_config());
  pim.integrate(samples, 9.53, 10.71, b_lin);  // a long window in a bend: large Jacobians
  // States away from the truth and a bias away from the linearisation point,
  // so every Jacobian term (incl. Jr^-1 of a nonzero residual) matters.
  NavState xi = semlio_test::inertial_truth(tr, T_imu_body, 9.53);
  NavState xj = semlio_test::inertial_truth(tr, T_imu_body, 10.71);
  xi.R_world_imu = xi.R_world_imu * SO3d::exp(Eigen::Vector3d(0.03, -0.02, 0.05));
  xj.R_world_imu = xj.R_world_imu * SO3d::exp(Eigen::Vector3d(-0.04, 0.01, 0.02));
  xi.v_world_mps += Eigen::Vector3d(0.3, -0.2, 0.1);
  xj.p_world_m += Eigen::Vector3d(0.5, 0.2, -0.3);
  ImuBias bi{Eigen::Vector3d(0.004, 0.001, 0.0), Eigen::Vector3d(0.08, 0.01, -0.02)};
  ImuBias bj;
  Matrix9x15d Ji;
  Matrix9x15d Jj;
  const Vector9d r0 = semlio::imu_factor_error(pim, xi, bi, xj, &Ji, &Jj);
  REQUIRE(r0.norm() > 0.01);
  Matrix9x15d Ni;
  Matrix9x15d Nj;
  const double eps = 1e-6;
  for (int k = 0; k < 15; ++k) {
    Vector15d d = Vector15d::Zero();
    d[k] = eps;
    NavState a = xi;
    ImuBias ab = bi;
    semlio::retract(a, ab, d);
    NavState m = xi;
    ImuBias mb = bi;
    semlio::retract(m, mb, -d);
    Ni.col(k) = (semlio::imu_factor_error(pim, a, ab, xj) - semlio::imu_factor_error(pim, m, mb, xj)) / (2 * eps);
    NavState aj = xj;
    ImuBias abj = bj;
    semlio::retract(aj, abj, d);
    NavState mj = xj;
    ImuBias mbj = bj;
    semlio::retract(mj, mbj, -d);
    Nj.col(k) = (semlio::imu_factor_error(pim, xi, bi, aj) - semlio::imu_factor_error(pim, xi, bi, mj)) / (2 * eps);
  }
  INFO("J_i analytic\n" << Ji << "\nnumeric\n" << Ni);
  CHECK((Ji - Ni).cwiseAbs().maxCoeff() < 1e-6 * std::max(1.0, Ni.cwiseAbs().maxCoeff()));
  INFO("J_j analytic\n" << Jj << "\nnumeric\n" << Nj);
  CHECK((Jj - Nj).cwiseAbs().maxCoeff() < 1e-6 * std::max(1.0, Nj.cwiseAbs().maxCoeff()));

  // Bias walk and nav_difference Jacobians.
  semlio::Matrix6x15d Bi;
  semlio::Matrix6x15d Bj;
  semlio::bias_walk_error(bi, bj, &Bi, &Bj);
  CHECK(Bi.rightCols<6>().isApprox(-Eigen::Matrix<double, 6, 6>::Identity()));
  CHECK(Bj.leftCols<9>().isZero());
  Matrix15d Jd;
  semlio::nav_difference(xj, bj, xi, bi, &Jd);
  Matrix15d Nd;
  for (int k = 0; k < 15; ++k) {
    Vector15d d = Vector15d::Zero();
    d[k] = eps;
    NavState a = xj;
    ImuBias ab = bj;
    semlio::retract(a, ab, d);
    NavState m = xj;
    ImuBias mb = bj;
    semlio::retract(m, mb, -d);
    Nd.col(k) = (semlio::nav_difference(a, ab, xi, bi) - semlio::nav_difference(m, mb, xi, bi)) / (2 * eps);
  }
  CHECK((Jd - Nd).cwiseAbs().maxCoeff() < 1e-6);
}

TEST_CASE("inertial graph: noise-free IMU and exact poses converge to the true states", "[imu]") {
  const DriveResult r = run_drive(5.0, 9.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  INFO("worst velocity error " << r.worst_v << " m/s, position " << r.worst_p << " m");
  CHECK(r.solves_ok == r.solves);
  CHECK(r.worst_v < 5e-3);
  CHECK(r.worst_p < 2e-3);
  CHECK(r.final_bias.gyro_radps.norm() < 1e-4);
  CHECK(r.final_bias.accel_mps2.norm() < 5e-3);
}

TEST_CASE("inertial graph: a known gyro and accel bias is recovered", "[imu]") {
  const Eigen::Vector3d bg(0.003, -0.002, 0.004);
  const Eigen::Vector3d ba(0.08, -0.05, 0.06);
  const DriveResult r = run_drive(12.0, 22.0, bg, ba);
  INFO("gyro bias " << r.final_bias.gyro_radps.transpose() << ", accel bias " << r.final_bias.accel_mps2.transpose());
  CHECK(r.solves_ok == r.solves);
  CHECK((r.final_bias.gyro_radps - bg).norm() < 2e-4);
  CHECK((r.final_bias.accel_mps2 - ba).norm() < 1e-2);
  CHECK(r.worst_v < 2e-2);
}

TEST_CASE("inertial graph: singular problems give a status and no NaN", "[imu]") {
  const auto& tr = semlio_test::inertial_drive();
  const SE3d T_imu_body = semlio_test::inertial_T_imu_body();
  const auto samples = semlio_test::inertial_samples(tr, T_imu_body, 4.9, 6.2, 100.0, Eigen::Vector3d::Zero(),
                                                     Eigen::Vector3d::Zero());
  InertialGraph empty;
  CHECK(empty.optimize().status == InertialSolveStatus::kEmpty);

  // Two states tied only by an IMU factor: the gauge (pose, velocity) is free.
  InertialGraph g;
  const NavState x0 = semlio_test::inertial_truth(tr, T_imu_body, 5.0);
  ImuPreintegration pim(test_config());
  pim.integrate(samples, 5.0, 6.0, ImuBias{});
  const auto a = g.add_state(5.0, x0, ImuBias{});
  const auto b = g.add_state(6.0, pim.predict(x0), ImuBias{});
  g.add_imu(a, b, pim);
  const auto rep = g.optimize();
  CHECK(rep.status == InertialSolveStatus::kSingular);
  CHECK_FALSE(rep.ok());
  CHECK(g.node(b).state.p_world_m.allFinite());
  CHECK(g.node(b).state.p_world_m.isApprox(pim.predict(x0).p_world_m));
  CHECK(g.covariance(b).allFinite());

  // Non-finite guess: a status, the state untouched.
  InertialGraph h;
  NavState bad = x0;
  bad.v_world_mps.x() = std::nan("");
  const auto c = h.add_state(5.0, bad, ImuBias{});
  h.add_prior(c, x0, ImuBias{}, Matrix15d::Identity());
  CHECK(h.optimize().status == InertialSolveStatus::kNumericalFailure);

  // Misuse throws a typed error.
  CHECK_THROWS_AS(g.add_imu(b, a, pim), semlio::ValueError);
  CHECK_THROWS_AS(g.node(17), semlio::ValueError);
  CHECK_THROWS_AS(InertialGraph({.window_size = 1}), semlio::ConfigError);
}

}  // namespace test_inertial_graph
