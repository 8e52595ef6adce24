// KeyframeInertialGraph: hand-checked residuals; noise-free IMU and exact
// poses are a fixed point; a perturbed node is recovered through IMU and
// between factors; a loop pulls a drifted chain back with consistent
// velocities (window updates, then a full solve); singular input gives a
// status, never NaN; the 4-DoF gauge (position + yaw) lets the IMU factors
// set roll and pitch (a tilted gravity is recovered).
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/graph/keyframe_inertial_graph.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

namespace test_keyframe_inertial_graph {  // one namespace per test file: the area compiles as one TU

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

// ---------------------------------------------------------------------------
// The 4-DoF gauge (gravity_gauge_information): the first node's prior holds
// position and the rotation about gravity only, so the IMU factors set roll
// and pitch (the graph estimates the gravity direction).

namespace {

const Eigen::Vector3d kGravity(0.0, 0.0, -9.80665);

// First-node prior information: 6-DoF pose (1 mm, 0.1 mrad), or the 4-DoF
// gauge (same sigmas, roll and pitch free); velocity and bias as prior_information().
Matrix15d gauge_prior(bool four_dof, const SO3d& R_world_imu, const Eigen::Vector3d& g) {
  Matrix15d info = prior_information();
  if (four_dof) info.topLeftCorner<6, 6>() = gravity_gauge_information(R_world_imu, g, 1e-3, 1e-4);
  return info;
}

// A chain with lidar-grade between factors (1 mm, 0.1 mrad: bending the
// chain to follow a wrong gravity is expensive) of the true sensor motion,
// IMU factors from c.pims, the first node's prior at the truth.
KeyframeInertialGraph build_gauge(const Chain& c, const std::vector<NavState>& guess, bool four_dof) {
  KeyframeInertialGraph g({.T_imu_sensor = test_T_imu_sensor()});
  const SE3d X = test_T_imu_sensor();
  for (std::size_t k = 0; k < c.t.size(); ++k) {
    const NodeId id = g.add_node(c.t[k], guess[k], ImuBias{});
    if (k == 0) {
      g.add_prior(id, c.truth[0], ImuBias{}, gauge_prior(four_dof, c.truth[0].R_world_imu, kGravity));
      continue;
    }
    const SE3d Z = (c.truth[k - 1].pose() * X).inverse() * (c.truth[k].pose() * X);
    g.add_between(id - 1, id, Z, pose_information(1e-3, 1e-4));
    g.add_imu(id - 1, id, c.pims[k - 1]);
  }
  return g;
}

// The truth rotated by C about node 0's position (poses and velocities).
std::vector<NavState> rotated(const Chain& c, const SO3d& C, const Eigen::Vector3d& shift_m = Eigen::Vector3d::Zero()) {
  std::vector<NavState> out = c.truth;
  const Eigen::Vector3d p0 = c.truth[0].p_world_m;
  for (NavState& x : out) {
    x.R_world_imu = C * x.R_world_imu;
    x.p_world_m = p0 + C * (x.p_world_m - p0) + shift_m;
    x.v_world_mps = C * x.v_world_mps;
  }
  return out;
}

// Largest position [m] and rotation [rad] difference between a graph's nodes and `ref`.
std::pair<double, double> worst_error(const KeyframeInertialGraph& g, const std::vector<NavState>& ref) {
  double dp = 0.0;
  double dr = 0.0;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    const NavState& x = g.node(static_cast<NodeId>(k)).state;
    dp = std::max(dp, (x.p_world_m - ref[k].p_world_m).norm());
    dr = std::max(dr, (ref[k].R_world_imu.inverse() * x.R_world_imu).log().norm());
  }
  return {dp, dr};
}

}  // namespace

TEST_CASE("gravity gauge information: free about world horizontal axes, holds position and yaw", "[graph]") {
  // A node with roll and pitch (so body and world axes differ) and a gravity
  // that is not along world z (a map frame's): the free directions must be
  // world rotations about axes perpendicular to gravity.
  NavState ref;
  ref.R_world_imu = SO3d::exp(Eigen::Vector3d(0.3, -0.2, 1.0));
  ref.p_world_m = Eigen::Vector3d(4.0, -2.0, 1.0);
  const Eigen::Vector3d g = SO3d::exp(Eigen::Vector3d(0.05, 0.1, 0.0)) * kGravity;
  const Eigen::Vector3d u = g.normalized();
  const double sigma_m = 1e-3;
  const double sigma_rad = 1e-4;
  Matrix15d info = Matrix15d::Zero();
  info.topLeftCorner<6, 6>() = gravity_gauge_information(ref.R_world_imu, g, sigma_m, sigma_rad);
  const auto chi2_at = [&](const NavState& x) {
    KeyframeInertialGraph h;
    h.add_node(0.0, x, ImuBias{});
    h.add_prior(0, ref, ImuBias{}, info);
    return h.chi2();
  };
  const auto world_rotated = [&](const Eigen::Vector3d& theta) {
    NavState x = ref;
    x.R_world_imu = SO3d::exp(theta) * ref.R_world_imu;
    return x;
  };
  // Two world axes perpendicular to gravity: free (zero cost at 10 mrad).
  const Eigen::Vector3d h1 = u.unitOrthogonal();
  const Eigen::Vector3d h2 = u.cross(h1);
  CHECK(chi2_at(world_rotated(0.01 * h1)) < 1e-12);
  CHECK(chi2_at(world_rotated(0.01 * h2)) < 1e-12);
  CHECK(chi2_at(world_rotated(0.01 * (h1 - 2.0 * h2))) < 1e-12);
  // Yaw (about gravity) costs (angle / sigma)^2, position (offset / sigma)^2.
  CHECK(chi2_at(world_rotated(1e-4 * u)) == Approx(1.0).epsilon(1e-3));
  NavState moved = ref;
  moved.p_world_m += Eigen::Vector3d(1e-3, -2e-3, 2e-3);
  CHECK(chi2_at(moved) == Approx(9.0).epsilon(1e-6));
  // A rotation about the BODY z axis is not free (the node is rolled and
  // pitched): its cost is that of its component about gravity. The
  // unconjugated information (R^T u taken as u) would get both of these wrong.
  NavState body = ref;
  body.R_world_imu = ref.R_world_imu * SO3d::exp(Eigen::Vector3d(0.0, 0.0, 1e-4));
  const double along = (ref.R_world_imu * Eigen::Vector3d::UnitZ()).dot(u);
  CHECK(std::abs(along) < 0.95);
  CHECK(chi2_at(body) == Approx(along * along).epsilon(1e-3));
  CHECK_THROWS_AS(gravity_gauge_information(SO3d(), Eigen::Vector3d::Zero(), 1.0, 1.0), ValueError);
  CHECK_THROWS_AS(gravity_gauge_information(SO3d(), kGravity, 0.0, 1.0), ValueError);
}

TEST_CASE("keyframe inertial graph: the 4-DoF gauge recovers a gravity tilt, the 6-DoF prior cannot", "[graph]") {
  // The graph's gravity is tilted by 3.6 mrad from the one the IMU felt (as a
  // front end's estimate of it). The IMU factors are then consistent with the
  // true trajectory rotated by that tilt about node 0: with the 4-DoF prior the
  // graph finds that rotation; the 6-DoF prior holds node 0's attitude, so the
  // chain has to fight either the IMU or the (stiff) lidar factors.
  const SO3d tilt = SO3d::exp(Eigen::Vector3d(0.003, -0.002, 0.0));
  PreintegrationConfig pc;
  pc.gravity_world_mps2 = tilt * kGravity;
  const Chain c = make_chain(12, 5.0, 1.0, pc);  // 11 s along the drive's straight and first turn
  const std::vector<NavState> expected = rotated(c, tilt);
  KeyframeInertialGraph four = build_gauge(c, c.truth, true);
  KeyframeInertialGraph six = build_gauge(c, c.truth, false);
  const GraphSolveReport r4 = four.update();
  const GraphSolveReport r6 = six.update();
  REQUIRE(r4.ok());
  REQUIRE(r6.ok());
  const auto [dp4, dr4] = worst_error(four, expected);
  const auto [dp6, dr6] = worst_error(six, expected);
  const SO3d C4 = four.node(0).state.R_world_imu * c.truth[0].R_world_imu.inverse();
  INFO("chi2 " << r4.initial_chi2 << " -> " << r4.final_chi2 << " (4 DoF), " << r6.initial_chi2 << " -> "
               << r6.final_chi2 << " (6 DoF); worst error to the tilted truth: " << dp4 << " m, " << dr4
               << " rad (4 DoF), " << dp6 << " m, " << dr6 << " rad (6 DoF); node 0 rotated by "
               << C4.log().transpose() << " (tilt " << tilt.log().transpose() << ")");
  CHECK(r4.initial_chi2 > 1e3);  // the tilt is visible to the IMU factors
  CHECK(r4.final_chi2 < 1.0);
  CHECK(r6.final_chi2 > 100.0 * std::max(r4.final_chi2, 1e-3));
  // 4 DoF: every node is the truth rotated by the tilt; node 0's rotation is the tilt.
  // Measured: 0.9 urad, 14 um (6 DoF: 3.3 mrad, 0.16 m; chi2 0.0013 against 107).
  CHECK(dr4 < 2e-5);
  CHECK(dp4 < 1e-3);
  CHECK((C4.inverse() * tilt).log().norm() < 2e-5);
  // ... and its position and its rotation about gravity stay where the prior holds them.
  CHECK((four.node(0).state.p_world_m - c.truth[0].p_world_m).norm() < 1e-5);
  CHECK(std::abs(C4.log().dot(kGravity.normalized())) < 1e-5);
  // 6 DoF: node 0 keeps its attitude, so the chain is not the rotated truth.
  CHECK(dr6 > 10.0 * dr4);
}

TEST_CASE("keyframe inertial graph: the 4-DoF gauge pins position and yaw, not roll and pitch", "[graph]") {
  // IMU felt the graph's gravity (no tilt); guesses perturbed as a whole about
  // node 0: by a yaw and a shift the prior undoes, by a tilt the IMU undoes.
  const Chain c = make_chain(12, 5.0, 1.0);
  const SO3d R0 = c.truth[0].R_world_imu;
  for (const int which : {0, 1}) {
    const SO3d C = which == 0 ? SO3d::exp(Eigen::Vector3d(0.0, 0.0, 0.02)) : SO3d::exp(Eigen::Vector3d(0.01, -0.01, 0.0));
    const Eigen::Vector3d shift = which == 0 ? Eigen::Vector3d(0.3, -0.2, 0.1) : Eigen::Vector3d::Zero();
    KeyframeInertialGraph g = build_gauge(c, rotated(c, C, shift), true);
    const GraphSolveReport r = g.update();
    REQUIRE(r.ok());
    const auto [dp, dr] = worst_error(g, c.truth);
    INFO((which == 0 ? "yaw 20 mrad + shift" : "tilt 14 mrad") << ": chi2 " << r.initial_chi2 << " -> "
                                                                << r.final_chi2 << ", worst error " << dp << " m, "
                                                                << dr << " rad");
    CHECK(r.final_chi2 < 1.0);
    CHECK(dp < 1e-3);
    CHECK(dr < 1e-4);
  }
  // Without IMU factors nothing sets roll and pitch: the 4-DoF gauge is then
  // singular (a status, not NaN), the 6-DoF prior is not -- why Slam holds
  // all 6 DoF until the first IMU factor and then relaxes the prior.
  for (const bool four_dof : {true, false}) {
    KeyframeInertialGraph g({.T_imu_sensor = test_T_imu_sensor()});
    const SE3d X = test_T_imu_sensor();
    std::size_t first_prior = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const NodeId id = g.add_node(c.t[k], c.truth[k], ImuBias{});
      Matrix15d info = prior_information();
      info.topLeftCorner<6, 6>().setZero();  // velocity and bias held on every node
      if (k == 0) info = gauge_prior(four_dof, R0, kGravity);
      const std::size_t f = g.add_prior(id, c.truth[k], ImuBias{}, info);
      if (k == 0) first_prior = f;
      if (k > 0) {
        const SE3d Z = (c.truth[k - 1].pose() * X).inverse() * (c.truth[k].pose() * X);
        g.add_between(id - 1, id, Z, pose_information(1e-3, 1e-4));
      }
    }
    const GraphSolveReport r = g.update();
    INFO((four_dof ? "4" : "6") << "-DoF gauge without IMU factors: " << to_string(r.status));
    CHECK(r.ok() == !four_dof);
    if (four_dof) {
      CHECK(r.status == GraphSolveStatus::singular);
      // Relaxing works the other way too: the full prior makes it solvable.
      g.set_prior_information(first_prior, gauge_prior(false, R0, kGravity));
      CHECK(g.update().ok());
    }
  }
  KeyframeInertialGraph g = build_gauge(c, c.truth, true);
  CHECK_THROWS_AS(g.set_prior_information(1, Matrix15d::Identity()), ValueError);  // factor 1 is a between
  CHECK_THROWS_AS(g.set_prior_information(99, Matrix15d::Identity()), ValueError);
}

}  // namespace test_keyframe_inertial_graph
