// KeyframeInertialGraph: hand-checked residuals; noise-free IMU and exact
// poses are a fixed point; a perturbed node is recovered through IMU and
// between factors; a loop pulls a drifted chain back with consistent
// velocities (window updates, then a full solve); singular input gives a
// status, never NaN.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/graph/keyframe_inertial_graph.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

using namespace semlio;

namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;

// A lidar-like extrinsic (sensor -> IMU), so frame mistakes show.
SE3d test_T_imu_sensor() { return SE3d(SO3d::exp(Eigen::Vector3d(0.01, -0.02, 1.2)), Eigen::Vector3d(0.3, -0.1, 0.7)); }

// A chain of keyframes every dt_s from t0 on the test drive: exact states,
// noise-free IMU (100 Hz) preintegrated over each interval.
struct Chain {
  std::vector<double> t;
  std::vector<NavState> truth;
  std::vector<ImuPreintegration> pims;  // pims[k]: node k -> k + 1
};

Chain make_chain(std::size_t nodes, double t0, double dt_s, PreintegrationConfig pc = {}) {
  const auto& tr = semlio_test::inertial_drive();
  const SE3d T_imu_body = semlio_test::inertial_T_imu_body();
  const double t1 = t0 + dt_s * static_cast<double>(nodes - 1);
  const auto samples = semlio_test::inertial_samples(tr, T_imu_body, t0 - 0.05, t1 + 0.05, 100.0,
                                                     Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  Chain c;
  for (std::size_t k = 0; k < nodes; ++k) {
    c.t.push_back(t0 + dt_s * static_cast<double>(k));
    c.truth.push_back(semlio_test::inertial_truth(tr, T_imu_body, c.t.back()));
  }
  pc.max_gap_s = 0.05;
  for (std::size_t k = 0; k + 1 < nodes; ++k) {
    ImuPreintegration pim(pc);
    pim.integrate(samples, c.t[k], c.t[k + 1], ImuBias{});
    c.pims.push_back(pim);
  }
  return c;
}

Matrix15d prior_information() {
  Vector15d sigma;
  sigma << Eigen::Vector3d::Constant(1e-3), Eigen::Vector3d::Constant(1e-4), Eigen::Vector3d::Constant(1.0),
      Eigen::Vector3d::Constant(1e-3), Eigen::Vector3d::Constant(0.1);
  return sigma.cwiseInverse().cwiseAbs2().asDiagonal();
}

Matrix6 pose_information(double sigma_m, double sigma_rad) {
  Matrix6 info = Matrix6::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return info;
}

// Builds the graph of a chain: prior on node 0, IMU factors, between factors
// of the true sensor motion; node guesses from `guess`.
KeyframeInertialGraph build(const Chain& c, const std::vector<NavState>& guess, std::size_t window = 30) {
  KeyframeInertialGraph g({.window_size = window, .T_imu_sensor = test_T_imu_sensor()});
  const SE3d X = test_T_imu_sensor();
  for (std::size_t k = 0; k < c.t.size(); ++k) {
    const NodeId id = g.add_node(c.t[k], guess[k], ImuBias{});
    if (k == 0) {
      g.add_prior(id, c.truth[0], ImuBias{}, prior_information());
      continue;
    }
    const SE3d Z = (c.truth[k - 1].pose() * X).inverse() * (c.truth[k].pose() * X);
    g.add_between(id - 1, id, Z, pose_information(0.05, 0.005));
    g.add_imu(id - 1, id, c.pims[k - 1]);
  }
  return g;
}

}  // namespace

TEST_CASE("keyframe inertial graph: hand-checked between and IMU residuals", "[graph]") {
  // Between: IMU at the origin and 1 m ahead; sensor rotated 90 deg about z,
  // so the sensor sees the motion along its -y: Z_true = (0, -1, 0). Measured
  // (0, -0.9, 0), unit information: e = (0, -0.1, 0), chi2 = 0.01.
  const SE3d X(SO3d::exp(Eigen::Vector3d(0.0, 0.0, std::numbers::pi / 2)), Eigen::Vector3d::Zero());
  KeyframeInertialGraph g({.T_imu_sensor = X});
  NavState a;
  NavState b;
  b.p_world_m = Eigen::Vector3d(1.0, 0.0, 0.0);
  g.add_node(0.0, a, ImuBias{});
  g.add_node(1.0, b, ImuBias{});
  g.add_between(0, 1, SE3d(SO3d(), Eigen::Vector3d(0.0, -0.9, 0.0)), Matrix6::Identity());
  CHECK(g.chi2() == Approx(0.01).epsilon(1e-9));
  CHECK(g.pose(1).translation().isApprox(Eigen::Vector3d(1.0, 0.0, 0.0)));

  // IMU: at rest for 1 s (specific force +g up), but node j is 0.5 m higher
  // with zero velocity: r_p = R^T (p_j - p_i - g dt^2 / 2) - dp = 0.5 m up,
  // every other component zero; chi2 = 0.25 * (covariance^-1)_pz,pz.
  PreintegrationConfig pc;
  std::vector<ImuSample> rest;
  for (int k = 0; k <= 100; ++k) rest.push_back({0.01 * k, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 9.80665)});
  ImuPreintegration pim(pc);
  pim.integrate(rest, 0.0, 1.0, ImuBias{});
  KeyframeInertialGraph h;
  NavState up;
  up.p_world_m = Eigen::Vector3d(0.0, 0.0, 0.5);
  h.add_node(0.0, NavState{}, ImuBias{});
  h.add_node(1.0, up, ImuBias{});
  h.add_imu(0, 1, pim);
  Matrix9d cov = pim.covariance();
  cov.diagonal().array() += h.config().min_variance;
  const double expected = 0.25 * cov.inverse()(8, 8);
  CHECK(h.chi2() == Approx(expected).epsilon(1e-9));
  // imu_information_scale weighs the IMU (and bias walk) information.
  KeyframeInertialGraph scaled({.imu_information_scale = 1e-3});
  scaled.add_node(0.0, NavState{}, ImuBias{});
  scaled.add_node(1.0, up, ImuBias{});
  scaled.add_imu(0, 1, pim);
  CHECK(scaled.chi2() == Approx(1e-3 * expected).epsilon(1e-9));
  CHECK_THROWS_AS(KeyframeInertialGraph({.imu_information_scale = 0.0}), ConfigError);
  // The IMU factors can be read back (diagnostics: chi2 at other states).
  REQUIRE(scaled.num_imu_factors() == 1);
  CHECK(scaled.imu_factor(0).from == 0);
  CHECK(scaled.imu_factor(0).to == 1);
  CHECK(scaled.imu_factor(0).pim.delta_t_s() == pim.delta_t_s());
  CHECK_THROWS_AS(scaled.imu_factor(1), ValueError);
}

TEST_CASE("keyframe inertial graph: exact states with noise-free IMU are a fixed point", "[graph]") {
  const Chain c = make_chain(6, 10.0, 1.0);
  KeyframeInertialGraph g = build(c, c.truth);
  const double chi2_before = g.chi2();
  const GraphSolveReport r = g.update();
  INFO("chi2 before " << chi2_before << ", after " << r.final_chi2 << ", status " << to_string(r.status));
  REQUIRE(r.ok());
  CHECK(r.mode == GraphSolveMode::full);
  CHECK(chi2_before < 0.1);  // second-order preintegration: ~1e-6 per window, not exact
  for (std::size_t k = 0; k < c.t.size(); ++k) {
    const KeyframeInertialNode& x = g.node(static_cast<NodeId>(k));
    CHECK((x.state.p_world_m - c.truth[k].p_world_m).norm() < 1e-4);
    CHECK((x.state.v_world_mps - c.truth[k].v_world_mps).norm() < 1e-4);
    CHECK((c.truth[k].R_world_imu.inverse() * x.state.R_world_imu).log().norm() < 1e-5);
    CHECK(x.bias.accel_mps2.norm() < 1e-3);
  }
}

TEST_CASE("keyframe inertial graph: a perturbed node is recovered", "[graph]") {
  const Chain c = make_chain(6, 20.0, 1.0);
  std::vector<NavState> guess = c.truth;
  guess[3].p_world_m += Eigen::Vector3d(0.4, -0.3, 0.2);
  guess[3].R_world_imu = guess[3].R_world_imu * SO3d::exp(Eigen::Vector3d(0.02, -0.03, 0.05));
  guess[3].v_world_mps += Eigen::Vector3d(1.0, 0.5, -0.2);
  guess[5].v_world_mps.setZero();  // the newest velocity unknown
  KeyframeInertialGraph g = build(c, guess);
  const GraphSolveReport r = g.update();
  REQUIRE(r.ok());
  CHECK(r.final_chi2 < 1e-3 * r.initial_chi2);
  for (const std::size_t k : {std::size_t{3}, std::size_t{5}}) {
    const KeyframeInertialNode& x = g.node(static_cast<NodeId>(k));
    CAPTURE(k);
    CHECK((x.state.p_world_m - c.truth[k].p_world_m).norm() < 1e-3);
    CHECK((x.state.v_world_mps - c.truth[k].v_world_mps).norm() < 1e-3);
    CHECK((c.truth[k].R_world_imu.inverse() * x.state.R_world_imu).log().norm() < 1e-4);
  }
}

TEST_CASE("keyframe inertial graph: a loop pulls a drifted chain back, velocities stay consistent", "[graph]") {
  // Odometry that overestimates the motion by 3 % and turns 3 mrad per
  // keyframe too much; the IMU factors weighted as a MEMS unit's (noise
  // densities 30x the default), so the odometry pulls the chain away.
  constexpr std::size_t kNodes = 16;
  PreintegrationConfig mems;
  mems.gyro_noise_density_radps_per_sqrthz = 5e-3;
  mems.accel_noise_density_mps2_per_sqrthz = 5e-2;
  mems.gyro_bias_walk_radps2_per_sqrthz = 1e-4;
  mems.accel_bias_walk_mps3_per_sqrthz = 1e-3;
  const Chain c = make_chain(kNodes, 5.0, 1.0, mems);
  const SE3d X = test_T_imu_sensor();
  const auto run = [&](bool loop, GraphSolveMode* last_mode) {
    KeyframeInertialGraph g({.window_size = 5, .T_imu_sensor = X});
    NavState guess = c.truth[0];
    for (std::size_t k = 0; k < kNodes; ++k) {
      if (k > 0) {
        SE3d Z = (c.truth[k - 1].pose() * X).inverse() * (c.truth[k].pose() * X);
        Z = SE3d(Z.so3() * SO3d::exp(Eigen::Vector3d(0.0, 0.0, 0.003)), 1.03 * Z.translation());
        const SE3d T_guess = g.pose(static_cast<NodeId>(k - 1)) * Z * X.inverse();
        guess.R_world_imu = T_guess.so3();
        guess.p_world_m = T_guess.translation();
        guess.v_world_mps = g.node(static_cast<NodeId>(k - 1)).state.v_world_mps;
      }
      const NodeId id = g.add_node(c.t[k], guess, ImuBias{});
      if (k == 0) {
        g.add_prior(id, c.truth[0], ImuBias{}, prior_information());
      } else {
        SE3d Z = (c.truth[k - 1].pose() * X).inverse() * (c.truth[k].pose() * X);
        Z = SE3d(Z.so3() * SO3d::exp(Eigen::Vector3d(0.0, 0.0, 0.003)), 1.03 * Z.translation());
        g.add_between(id - 1, id, Z, pose_information(0.05, 0.005));
        g.add_imu(id - 1, id, c.pims[k - 1]);
      }
      const GraphSolveReport r = g.update();
      REQUIRE(r.ok());
      if (k > 5) CHECK(r.mode == GraphSolveMode::window);
    }
    if (loop) {
      const SE3d Z = (c.truth[0].pose() * X).inverse() * (c.truth[kNodes - 1].pose() * X);
      g.add_loop(0, kNodes - 1, Z, pose_information(0.02, 0.002));
      CHECK(g.full_solve_pending());
      const GraphSolveReport r = g.update();
      REQUIRE(r.ok());
      *last_mode = r.mode;
    }
    return g;
  };
  GraphSolveMode mode = GraphSolveMode::window;
  const KeyframeInertialGraph drifted = run(false, &mode);
  const KeyframeInertialGraph closed = run(true, &mode);
  CHECK(mode == GraphSolveMode::full);
  const auto end_error = [&](const KeyframeInertialGraph& g) {
    return (g.node(kNodes - 1).state.p_world_m - c.truth[kNodes - 1].p_world_m).norm();
  };
  double worst_v = 0.0;
  double worst_v_drifted = 0.0;
  for (std::size_t k = 0; k < kNodes; ++k) {
    const KeyframeInertialNode& x = closed.node(static_cast<NodeId>(k));
    REQUIRE(x.state.v_world_mps.allFinite());
    REQUIRE(x.bias.accel_mps2.allFinite());
    worst_v = std::max(worst_v, (x.state.v_world_mps - c.truth[k].v_world_mps).norm());
    worst_v_drifted = std::max(worst_v_drifted,
                               (drifted.node(static_cast<NodeId>(k)).state.v_world_mps - c.truth[k].v_world_mps).norm());
  }
  INFO("end-node error without the loop " << end_error(drifted) << " m, with it " << end_error(closed)
                                          << " m; worst velocity error " << worst_v_drifted << " / " << worst_v << " m/s");
  CHECK(end_error(drifted) > 0.1);
  CHECK(end_error(closed) < 0.5 * end_error(drifted));
  CHECK(worst_v <= worst_v_drifted + 0.05);
  CHECK(worst_v < 0.5);
}

TEST_CASE("keyframe inertial graph: singular input gives a status, never NaN", "[graph]") {
  const Chain c = make_chain(3, 30.0, 1.0);
  const SE3d X = test_T_imu_sensor();
  // No prior, no IMU: the pose gauge and every velocity and bias are free.
  KeyframeInertialGraph g({.T_imu_sensor = X});
  for (std::size_t k = 0; k < 3; ++k) g.add_node(c.t[k], c.truth[k], ImuBias{});
  g.add_between(0, 1, SE3d(SO3d(), Eigen::Vector3d(1.0, 0.0, 0.0)), pose_information(0.05, 0.005));
  g.add_between(1, 2, SE3d(SO3d(), Eigen::Vector3d(1.0, 0.0, 0.0)), pose_information(0.05, 0.005));
  const GraphSolveReport r = g.update();
  CHECK(r.status == GraphSolveStatus::singular);
  CHECK_FALSE(r.ok());
  for (std::size_t k = 0; k < 3; ++k) {
    CHECK(g.node(static_cast<NodeId>(k)).state.p_world_m == c.truth[k].p_world_m);  // unchanged
  }
  // Non-finite input: typed errors, nothing added.
  Matrix6 bad = Matrix6::Identity();
  bad(0, 0) = std::nan("");
  CHECK_THROWS_AS(g.add_between(0, 1, SE3d(), bad), ValueError);
  CHECK_THROWS_AS(g.add_loop(0, 0, SE3d(), Matrix6::Identity()), ValueError);
  CHECK_THROWS_AS(g.add_imu(2, 1, c.pims[0]), ValueError);
  CHECK_THROWS_AS(g.node(7), ValueError);
  CHECK_THROWS_AS(KeyframeInertialGraph({.window_size = 0}), ConfigError);
  // A non-finite state gives non_finite, not NaN spreading.
  NavState nan_state = c.truth[0];
  nan_state.v_world_mps.x() = std::nan("");
  KeyframeInertialGraph h;
  h.add_node(0.0, nan_state, ImuBias{});
  h.add_prior(0, c.truth[0], ImuBias{}, prior_information());
  CHECK(h.update().status == GraphSolveStatus::non_finite);
}
