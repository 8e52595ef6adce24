#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <semlio/graph/between_error.hpp>
#include <semlio/graph/pose_graph.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/g2o_graph.hpp>
#include <semlio_test/data.hpp>

namespace test_pose_graph {  // one namespace per test file: the area compiles as one TU

using semlio::ErrorConvention;
using semlio::ErrorFrame;
using semlio::Pose2;
using semlio::PoseGraph2d;
using semlio::PoseGraph3d;
using semlio::RotationError;
using semlio::SE3d;
using semlio::GraphSolveMode;
using semlio::GraphSolveStatus;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

namespace {

SE3d random_pose(std::mt19937& rng, double rot_scale = 1.0) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6 xi;
  for (int k = 0; k < 6; ++k) xi[k] = n(rng);
  xi.tail<3>() *= rot_scale;
  return SE3d::exp(xi);
}

SE3d perturbed(const SE3d& T, std::mt19937& rng, double sigma_t, double sigma_r) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6 xi;
  for (int k = 0; k < 3; ++k) xi[k] = sigma_t * n(rng);
  for (int k = 3; k < 6; ++k) xi[k] = sigma_r * n(rng);
  return T * SE3d::exp(xi);
}

// chi2 of a benchmark file solved from its initial guess.
template <typename Graph>
double solve_chi2(Graph graph) {
  const semlio::GraphSolveReport r = graph.optimize();
  CHECK(r.status == GraphSolveStatus::converged);
  CHECK(std::abs(graph.chi2() - r.final_chi2) <= 1e-9 * r.final_chi2);
  return r.final_chi2;
}

// A noisy odometry chain around a square loop (truth, measurements).
struct Drive {
  std::vector<SE3d> truth;
  std::vector<SE3d> odometry;  // truth[k]^-1 truth[k+1] with noise
};

Drive make_drive(std::size_t n, std::mt19937& rng) {
  Drive d;
  SE3d T;
  for (std::size_t k = 0; k < n; ++k) {
    d.truth.push_back(T);
    Vector6 step;
    step << 1.0, 0.0, 0.0, 0.0, 0.0, 2.0 * 3.14159265358979 / static_cast<double>(n);  // a circle
    T = T * SE3d::exp(step);
  }
  for (std::size_t k = 0; k + 1 < n; ++k) {
    d.odometry.push_back(perturbed(d.truth[k].inverse() * d.truth[k + 1], rng, 0.02, 0.005));
  }
  return d;
}

}  // namespace

TEST_CASE("SE3 between error: analytic Jacobians match central differences in every convention", "[graph]") {
  std::mt19937 rng(7);
  for (const ErrorFrame frame : {ErrorFrame::measurement, ErrorFrame::ceres}) {
    for (const RotationError rot : {RotationError::two_vec, RotationError::log, RotationError::quat_vec}) {
      const ErrorConvention c{.frame = frame, .rotation = rot};
      for (int trial = 0; trial < 5; ++trial) {
        const SE3d Ti = random_pose(rng);
        const SE3d Tj = random_pose(rng);
        const SE3d Z = perturbed(Ti.inverse() * Tj, rng, 0.3, 0.4);
        Matrix6 Ji;
        Matrix6 Jj;
        semlio::between_error(Z, Ti, Tj, c, &Ji, &Jj);
        const double h = 1e-6;
        for (int k = 0; k < 6; ++k) {
          Vector6 d = Vector6::Zero();
          d[k] = h;
          const Vector6 num_i = (semlio::between_error(Z, Ti * SE3d::exp(d), Tj, c) -
                                 semlio::between_error(Z, Ti * SE3d::exp(-d), Tj, c)) /
                                (2 * h);
          const Vector6 num_j = (semlio::between_error(Z, Ti, Tj * SE3d::exp(d), c) -
                                 semlio::between_error(Z, Ti, Tj * SE3d::exp(-d), c)) /
                                (2 * h);
          CHECK((num_i - Ji.col(k)).norm() < 1e-7);
          CHECK((num_j - Jj.col(k)).norm() < 1e-7);
        }
      }
    }
  }
}

TEST_CASE("SE3 between error: zero at the measured pose, 2vec ~ log for small angles", "[graph]") {
  std::mt19937 rng(11);
  const SE3d Ti = random_pose(rng);
  const SE3d Tj = random_pose(rng);
  CHECK(semlio::between_error(Ti.inverse() * Tj, Ti, Tj).norm() < 1e-12);
  // A prior is the between error from the origin.
  Matrix6 J_prior;
  Matrix6 J_between;
  const Vector6 e_prior = semlio::prior_error(Ti, Tj, ErrorConvention{}, &J_prior);
  const Vector6 e_between = semlio::between_error(Ti, SE3d(), Tj, ErrorConvention{}, nullptr, &J_between);
  CHECK(e_prior == e_between);
  CHECK(J_prior == J_between);
  CHECK(e_prior.norm() > 0.1);
  // A pure rotation error of angle a: 2vec gives 2 sin(a/2), log gives a, vec gives sin(a/2).
  const double a = 0.3;
  Vector6 xi = Vector6::Zero();
  xi[5] = a;
  const SE3d Z = (Ti.inverse() * Tj) * SE3d::exp(-xi);
  const double two_vec = semlio::between_error(Z, Ti, Tj, {.rotation = RotationError::two_vec}).tail<3>().norm();
  const double log = semlio::between_error(Z, Ti, Tj, {.rotation = RotationError::log}).tail<3>().norm();
  const double vec = semlio::between_error(Z, Ti, Tj, {.rotation = RotationError::quat_vec}).tail<3>().norm();
  CHECK(two_vec == Approx(2.0 * std::sin(a / 2.0)).epsilon(1e-12));
  CHECK(log == Approx(a).epsilon(1e-12));
  CHECK(vec == Approx(std::sin(a / 2.0)).epsilon(1e-12));
}

TEST_CASE("SE2 between error: analytic Jacobians match central differences", "[graph]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (const ErrorFrame frame : {ErrorFrame::measurement, ErrorFrame::ceres}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Pose2 Ti(u(rng), u(rng), u(rng));
      const Pose2 Tj(u(rng), u(rng), u(rng));
      const Pose2 Z(u(rng), u(rng), 0.3 * u(rng));
      const ErrorConvention c{.frame = frame};
      Eigen::Matrix3d Ji;
      Eigen::Matrix3d Jj;
      semlio::between_error(Z, Ti, Tj, c, &Ji, &Jj);
      const double h = 1e-6;
      using V = semlio::Variable<Pose2>;
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d[k] = h;
        Eigen::Vector3d num_i =
            (semlio::between_error(Z, V::retract(Ti, d), Tj, c) - semlio::between_error(Z, V::retract(Ti, -d), Tj, c)) /
            (2 * h);
        Eigen::Vector3d num_j =
            (semlio::between_error(Z, Ti, V::retract(Tj, d), c) - semlio::between_error(Z, Ti, V::retract(Tj, -d), c)) /
            (2 * h);
        num_i[2] = semlio::wrap_angle_rad(num_i[2] * 2 * h) / (2 * h);
        num_j[2] = semlio::wrap_angle_rad(num_j[2] * 2 * h) / (2 * h);
        CHECK((num_i - Ji.col(k)).norm() < 1e-7);
        CHECK((num_j - Jj.col(k)).norm() < 1e-7);
      }
    }
  }
}

TEST_CASE("benchmark graphs reach the reference chi2 of the data README", "[graph]") {
  // References: tests/data/posegraphs/README.md (independent Ceres solution).
  SECTION("tinyGrid3D") {
    const auto file = semlio::io::read_g2o(semlio_test::data_path("posegraphs/tinyGrid3D.g2o"));
    CHECK(solve_chi2(semlio::io::make_pose_graph3(file)) == Approx(18.519366421).epsilon(1e-6));
  }
  SECTION("smallGrid3D") {
    const auto file = semlio::io::read_g2o(semlio_test::data_path("posegraphs/smallGrid3D.g2o"));
    CHECK(solve_chi2(semlio::io::make_pose_graph3(file)) == Approx(1025.3980556).epsilon(1e-6));
  }
  SECTION("M3500 (2D)") {
    const auto file = semlio::io::read_g2o(semlio_test::data_path("posegraphs/M3500.g2o"));
    CHECK(solve_chi2(semlio::io::make_pose_graph2(file)) == Approx(137.91295094).epsilon(1e-6));
  }
  SECTION("g2o's vec convention gives a different (smaller) optimum on tinyGrid3D") {
    const auto file = semlio::io::read_g2o(semlio_test::data_path("posegraphs/tinyGrid3D.g2o"));
    semlio::PoseGraphConfig config;
    config.convention.rotation = RotationError::quat_vec;
    const double chi2 = solve_chi2(semlio::io::make_pose_graph3(file, config));
    CHECK(chi2 < 18.519366421 * 0.9);
  }
}

TEST_CASE("a node without factors makes the system singular: a status, no NaN", "[graph]") {
  PoseGraph3d graph;
  const auto a = graph.add_node(SE3d());
  const auto b = graph.add_node(SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 0.0, 0.0)));
  const auto c = graph.add_node(SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(5.0, 1.0, 0.0)));
  graph.add_between(a, b, SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.1, 0.0, 0.0)), Matrix6::Identity());
  const semlio::GraphSolveReport r = graph.optimize();
  CHECK(r.status == GraphSolveStatus::singular);
  CHECK_FALSE(r.ok());
  CHECK(r.degenerate_node == static_cast<long>(c));
  // Estimates unchanged and finite.
  CHECK(graph.pose(b).translation().x() == 1.0);
  CHECK(graph.pose(c).translation().allFinite());
  // Constraining the node makes it solvable.
  graph.add_between(b, c, SE3d(), Matrix6::Identity());
  const semlio::GraphSolveReport r2 = graph.optimize();
  CHECK(r2.status == GraphSolveStatus::converged);
  CHECK(graph.pose(c).translation().isApprox(Eigen::Vector3d(1.1, 0.0, 0.0), 1e-9));
}

TEST_CASE("rank-deficient information gives a singular status", "[graph]") {
  PoseGraph3d graph;
  graph.add_node(SE3d());
  graph.add_node(SE3d());
  Matrix6 info = Matrix6::Identity();
  info.bottomRightCorner<3, 3>().setZero();  // rotation unobserved
  graph.add_between(0, 1, SE3d(), info);
  const semlio::GraphSolveReport r = graph.optimize();
  CHECK(r.status == GraphSolveStatus::singular);
  CHECK(r.degenerate_node == 1);
  CHECK(graph.pose(1).so3().quaternion().coeffs().allFinite());
}

TEST_CASE("an indefinite information matrix given directly gives a singular status, no NaN", "[graph]") {
  PoseGraph3d graph;
  graph.add_node(SE3d());
  graph.add_node(SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.5, 0.0, 0.0)));
  Matrix6 info = Matrix6::Identity();
  info(4, 4) = -1.0;  // the g2o reader would have projected this to PSD
  graph.add_between(0, 1, SE3d(), info);
  const semlio::GraphSolveReport r = graph.optimize();
  CHECK(r.status == GraphSolveStatus::singular);
  CHECK(graph.pose(1).translation().x() == 0.5);
}

TEST_CASE("bad input throws, non-finite estimates give a status", "[graph]") {
  PoseGraph3d graph;
  graph.add_node(SE3d());
  graph.add_node(SE3d());
  Matrix6 nan_info = Matrix6::Identity();
  nan_info(2, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(graph.add_between(0, 1, SE3d(), nan_info), semlio::ValueError);
  CHECK_THROWS_AS(graph.add_between(0, 7, SE3d(), Matrix6::Identity()), semlio::ValueError);
  CHECK_THROWS_AS(graph.add_between(1, 1, SE3d(), Matrix6::Identity()), semlio::ValueError);
  CHECK_THROWS_AS(PoseGraph3d(semlio::PoseGraphConfig{.window_size = 0}), semlio::ConfigError);
  graph.add_between(0, 1, SE3d(), Matrix6::Identity());
  graph.set_pose(
      1, SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0)));
  const semlio::GraphSolveReport r = graph.optimize();
  CHECK(r.status == GraphSolveStatus::non_finite);
}

TEST_CASE("a prior replaces the fixed first node as gauge", "[graph]") {
  semlio::PoseGraphConfig config;
  config.fix_first_node = false;
  PoseGraph3d graph(config);
  std::mt19937 rng(5);
  const SE3d prior = random_pose(rng, 0.5);
  const SE3d step(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(1.0, 0.0, 0.0));
  graph.add_node(SE3d());
  graph.add_node(SE3d());
  CHECK_FALSE(graph.is_fixed(0));
  graph.add_prior(0, prior, 100.0 * Matrix6::Identity());
  graph.add_between(0, 1, step, Matrix6::Identity());
  const semlio::GraphSolveReport r = graph.optimize();
  REQUIRE(r.status == GraphSolveStatus::converged);
  CHECK(r.final_chi2 < 1e-16);
  CHECK((graph.pose(0).inverse() * prior).log().norm() < 1e-9);
  CHECK(((prior * step).inverse() * graph.pose(1)).log().norm() < 1e-9);
}

TEST_CASE("incremental window updates then a final full solve agree with a batch solve", "[graph]") {
  std::mt19937 rng(21);
  const Drive d = make_drive(120, rng);
  semlio::PoseGraphConfig config;
  config.window_size = 10;
  PoseGraph3d inc(config);
  PoseGraph3d batch(config);
  const Matrix6 info = Matrix6::Identity() * 100.0;
  inc.add_node(d.truth[0]);
  batch.add_node(d.truth[0]);
  bool saw_window = false;
  bool saw_loop_full = false;
  for (std::size_t k = 1; k < d.truth.size(); ++k) {
    const SE3d guess = inc.pose(static_cast<semlio::NodeId>(k - 1)) * d.odometry[k - 1];
    inc.add_node(guess);
    batch.add_node(batch.pose(static_cast<semlio::NodeId>(k - 1)) * d.odometry[k - 1]);
    inc.add_between(static_cast<semlio::NodeId>(k - 1), static_cast<semlio::NodeId>(k), d.odometry[k - 1], info);
    batch.add_between(static_cast<semlio::NodeId>(k - 1), static_cast<semlio::NodeId>(k), d.odometry[k - 1], info);
    const bool loop = k % 40 == 0;
    if (loop) {
      // Closes the circle back to node k - 100 when possible, else to node 0.
      const auto from = static_cast<semlio::NodeId>(k >= 100 ? k - 100 : 0);
      const SE3d Z = perturbed(d.truth[from].inverse() * d.truth[k], rng, 0.02, 0.005);
      inc.add_loop(from, static_cast<semlio::NodeId>(k), Z, info, false);
      batch.add_loop(from, static_cast<semlio::NodeId>(k), Z, info, false);
    }
    const semlio::GraphSolveReport r = inc.update();
    REQUIRE(r.ok());
    if (k > config.window_size && !loop) {
      CHECK(r.mode == GraphSolveMode::window);
      CHECK(r.free_nodes == config.window_size);
      CHECK(r.active_factors <= config.window_size + 1);  // window cost, not graph size
      saw_window = true;
    }
    if (loop) {
      CHECK(r.mode == GraphSolveMode::full);
      CHECK(r.free_nodes == k);
      saw_loop_full = true;
    }
  }
  CHECK(saw_window);
  CHECK(saw_loop_full);
  const semlio::GraphSolveReport ri = inc.optimize();
  const semlio::GraphSolveReport rb = batch.optimize();
  REQUIRE(ri.status == GraphSolveStatus::converged);
  REQUIRE(rb.status == GraphSolveStatus::converged);
  CHECK(ri.final_chi2 == Approx(rb.final_chi2).epsilon(1e-8));
  double max_diff = 0.0;
  for (semlio::NodeId k = 0; k < inc.num_nodes(); ++k) {
    max_diff = std::max(max_diff, (inc.pose(k).inverse() * batch.pose(k)).log().norm());
  }
  CHECK(max_diff < 1e-7);
}

TEST_CASE("a loop closure triggers a warm-started full re-solve", "[graph]") {
  std::mt19937 rng(33);
  const Drive d = make_drive(200, rng);
  semlio::PoseGraphConfig config;
  config.window_size = 15;
  PoseGraph3d graph(config);
  const Matrix6 info = Matrix6::Identity() * 100.0;
  graph.add_node(d.truth[0]);
  for (std::size_t k = 1; k < d.truth.size(); ++k) {
    graph.add_node(graph.pose(static_cast<semlio::NodeId>(k - 1)) * d.odometry[k - 1]);
    graph.add_between(static_cast<semlio::NodeId>(k - 1), static_cast<semlio::NodeId>(k), d.odometry[k - 1], info);
    REQUIRE(graph.update().mode == (k + 1 <= config.window_size ? GraphSolveMode::full : GraphSolveMode::window));
  }
  const auto last = static_cast<semlio::NodeId>(d.truth.size() - 1);
  const SE3d Z = perturbed(d.truth[0].inverse() * d.truth[last], rng, 0.01, 0.002);
  graph.add_loop(0, last, Z, info);
  CHECK(graph.full_solve_pending());
  PoseGraph3d cold = graph;  // same graph; re-solved from the odometry chain below
  for (semlio::NodeId k = 1; k <= last; ++k) cold.set_pose(k, cold.pose(k - 1) * d.odometry[k - 1]);
  const double drift_before = (graph.pose(last).inverse() * d.truth[last]).log().norm();
  const semlio::GraphSolveReport r = graph.update();
  REQUIRE(r.status == GraphSolveStatus::converged);
  CHECK(r.mode == GraphSolveMode::full);
  CHECK(r.free_nodes == d.truth.size() - 1);
  CHECK_FALSE(graph.full_solve_pending());
  // Warm start: the solve starts from the current estimate (its initial chi2
  // is the graph's chi2 before the update, loop factor included).
  const semlio::GraphSolveReport rc = cold.optimize();
  REQUIRE(rc.status == GraphSolveStatus::converged);
  CHECK(r.final_chi2 == Approx(rc.final_chi2).epsilon(1e-6));
  CHECK(r.iterations <= rc.iterations + 1);
  const double drift_after = (graph.pose(last).inverse() * d.truth[last]).log().norm();
  CHECK(drift_after < drift_before);
  // The next update without a loop is a window update again.
  graph.add_node(graph.pose(last));
  graph.add_between(last, last + 1, SE3d(), info);
  CHECK(graph.update().mode == GraphSolveMode::window);
}

TEST_CASE("a robust loop closure limits the damage of an outlier", "[graph]") {
  std::mt19937 rng(44);
  const Drive d = make_drive(60, rng);
  const Matrix6 odo_info = Matrix6::Identity() * 1e4;
  const Matrix6 loop_info = Matrix6::Identity() * 100.0;
  PoseGraph3d chain;
  chain.add_node(d.truth[0]);
  for (std::size_t k = 1; k < d.truth.size(); ++k) {
    chain.add_node(chain.pose(static_cast<semlio::NodeId>(k - 1)) * d.odometry[k - 1]);
    chain.add_between(static_cast<semlio::NodeId>(k - 1), static_cast<semlio::NodeId>(k), d.odometry[k - 1], odo_info);
  }
  // Deviation from the odometry-only solution after adding a wrong loop that
  // claims node 30 sits 5 m away from where the odometry puts it.
  auto damage = [&](bool robust) {
    PoseGraph3d g(semlio::PoseGraphConfig{.huber_delta = 1.0});
    for (const SE3d& p : chain.poses()) g.add_node(p);
    for (const auto& f : chain.factors()) g.add_between(f.from, f.to, f.measured, f.information);
    const SE3d wrong = chain.pose(10).inverse() * chain.pose(30) *
                       SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(5.0, 0.0, 0.0));
    g.add_loop(10, 30, wrong, loop_info, robust);
    REQUIRE(g.optimize().ok());
    double err = 0.0;
    for (semlio::NodeId k = 0; k < g.num_nodes(); ++k)
      err = std::max(err, (g.pose(k).translation() - chain.pose(k).translation()).norm());
    return err;
  };
  const double err_robust = damage(true);
  const double err_plain = damage(false);
  // Huber only down-weights (a soft chain still bends), but clearly less.
  CHECK(err_plain > 1.0);
  CHECK(err_robust < 0.5 * err_plain);
}

TEST_CASE("2D graph: window updates and a full solve", "[graph]") {
  PoseGraph2d graph(semlio::PoseGraphConfig{.window_size = 5});
  const Pose2 step(1.0, 0.0, 0.1);
  graph.add_node(Pose2());
  for (semlio::NodeId k = 1; k < 30; ++k) {
    graph.add_node(graph.pose(k - 1) * Pose2(1.05, 0.02, 0.09));  // biased guess
    graph.add_between(k - 1, k, step, Eigen::Matrix3d::Identity());
    REQUIRE(graph.update().ok());
  }
  // Consistent measurements: every node lands on the composed steps.
  Pose2 expected;
  for (semlio::NodeId k = 0; k < 30; ++k) {
    CHECK((graph.pose(k).translation() - expected.translation()).norm() < 1e-9);
    CHECK(std::abs(semlio::wrap_angle_rad(graph.pose(k).theta() - expected.theta())) < 1e-9);
    expected = expected * step;
  }
}

TEST_CASE("the optional trace records every LM iteration with non-increasing chi2", "[graph]") {
  const auto file = semlio::io::read_g2o(semlio_test::data_path("posegraphs/smallGrid3D.g2o"));
  semlio::PoseGraphConfig config;
  config.record_trace = true;
  PoseGraph3d graph = semlio::io::make_pose_graph3(file, config);
  const semlio::GraphSolveReport r = graph.optimize();
  REQUIRE(r.status == GraphSolveStatus::converged);
  REQUIRE(!r.trace.empty());
  CHECK(r.trace.size() <= static_cast<std::size_t>(r.iterations));
  CHECK(r.trace.front().lambda == 0.0);  // the first step is Gauss-Newton
  double previous = r.initial_chi2;
  for (const semlio::GraphSolveIteration& it : r.trace) {
    CHECK(it.chi2 <= previous * (1.0 + 1e-12));
    previous = it.chi2;
  }
  CHECK(previous == Approx(r.final_chi2).epsilon(1e-12));
  // Without the flag, no trace.
  CHECK(semlio::io::make_pose_graph3(file).optimize().trace.empty());
}

}  // namespace test_pose_graph
