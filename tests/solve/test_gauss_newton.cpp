#include <catch2/catch.hpp>

#include <semlio/solve/gauss_newton.hpp>

#include <cmath>
#include <random>
#include <vector>

using semlio::SE3d;

namespace {

// Point-to-plane problem with exact planes: point p_i (scan frame) lies on the
// plane (n_i, d_i) in the map frame under T_true. Residual n^T (T p) + d.
struct PlaneProblem {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> offsets;
  int associations = 0;

  void associate(const SE3d&) { ++associations; }

  void linearize(const SE3d& T, semlio::NormalEquations& eq) const {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d q = T * points[i];
      Eigen::Matrix<double, 1, 1> r;
      r(0) = normals[i].dot(q) + offsets[i];
      // d(T exp(xi) p)/dxi = R [I, -p^]
      Eigen::Matrix<double, 1, 6> J;
      J.head<3>() = normals[i].transpose() * T.rotation();
      J.tail<3>() = -normals[i].transpose() * T.rotation() * semlio::hat(points[i]);
      eq.add<1>(r, J);
    }
  }
};

// Points on three orthogonal walls + ground seen from T_true: constrains all 6 DoF.
PlaneProblem box_scene(const SE3d& T_true, bool only_ground) {
  PlaneProblem p;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  const std::vector<std::pair<Eigen::Vector3d, double>> planes = {
      {Eigen::Vector3d::UnitZ(), 1.7}, {Eigen::Vector3d::UnitX(), -6.0},
      {Eigen::Vector3d::UnitY(), -4.0}, {Eigen::Vector3d(1, 1, 0).normalized(), 9.0}};
  const std::size_t used = only_ground ? 1 : planes.size();
  for (std::size_t k = 0; k < used; ++k) {
    const auto& [n, d] = planes[k];
    // Basis of the plane.
    const Eigen::Vector3d a = n.unitOrthogonal();
    const Eigen::Vector3d b = n.cross(a);
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d q_map = -d * n + u(rng) * a + u(rng) * b;
      p.points.push_back(T_true.inverse() * q_map);
      p.normals.push_back(n);
      p.offsets.push_back(d);
    }
  }
  return p;
}

SE3d pose(double x, double y, double z, double rx, double ry, double rz) {
  SE3d::Vector6 xi;
  xi << x, y, z, rx, ry, rz;
  return SE3d::exp(xi);
}

}  // namespace

TEST_CASE("Gauss-Newton recovers a pose from exact plane constraints", "[solve]") {
  const SE3d T_true = pose(0.4, -0.3, 0.1, 0.02, -0.03, 0.15);
  PlaneProblem problem = box_scene(T_true, false);
  for (const bool lm : {false, true}) {
    SE3d T;  // identity start
    const semlio::GaussNewtonConfig config{.levenberg_marquardt = lm};
    const auto report = semlio::gauss_newton(problem, T, config);
    CHECK(report.status == semlio::SolveStatus::kConverged);
    CHECK((T.inverse() * T_true).log().norm() < 1e-6);
    CHECK(report.final_cost < 1e-10);
    CHECK(report.initial_cost > report.final_cost);
    CHECK_FALSE(report.degenerate());
    CHECK(report.num_residuals == problem.points.size());
    // The reported Hessian is J^T J at the solution: symmetric positive definite.
    CHECK((report.hessian - report.hessian.transpose()).norm() < 1e-9);
    CHECK(report.hessian.ldlt().isPositive());
  }
  CHECK(problem.associations > 0);
}

TEST_CASE("Gauss-Newton re-associates every n-th iteration", "[solve]") {
  PlaneProblem problem = box_scene(pose(0.2, 0, 0, 0, 0, 0.05), false);
  SE3d T;
  const semlio::GaussNewtonConfig config{.max_iterations = 6, .reassociate_every = 3,
                                         .translation_tolerance_m = 0.0,
                                         .rotation_tolerance_rad = 0.0};
  const auto report = semlio::gauss_newton(problem, T, config);
  CHECK(report.status == semlio::SolveStatus::kMaxIterations);
  CHECK(report.iterations == 6);
  CHECK(problem.associations == 2);  // iterations 0 and 3
}

TEST_CASE("Gauss-Newton on a flat plane reports three degenerate directions", "[solve]") {
  const SE3d T_true = pose(0.0, 0.0, 0.05, 0.01, -0.02, 0.0);
  PlaneProblem problem = box_scene(T_true, true);
  SE3d T = pose(0.3, 0.2, 0.0, 0.0, 0.0, 0.1);  // in-plane offset the data cannot see
  const SE3d T_start = T;
  const auto report = semlio::gauss_newton(problem, T);
  CHECK(report.ok());
  CHECK(report.degenerate_directions == 3);
  CHECK(T.matrix().allFinite());
  // Constrained directions (height, roll, pitch) are solved...
  CHECK(std::abs((T * Eigen::Vector3d(0, 0, 0)).z() - (T_true * Eigen::Vector3d(0, 0, 0)).z()) < 0.05);
  // The projection is fixed at the first iteration (as in LOAM), so the
  // constrained subspace converges to the step tolerance, not to zero.
  CHECK(std::sqrt(report.final_cost / static_cast<double>(report.num_residuals)) < 1e-3);
  // ...and the unconstrained ones (x, y, yaw) are left where the prior put them.
  CHECK(std::abs(T.translation().x() - T_start.translation().x()) < 0.05);
  CHECK(std::abs(T.translation().y() - T_start.translation().y()) < 0.05);
}

TEST_CASE("Gauss-Newton with too few residuals leaves the pose unchanged", "[solve]") {
  PlaneProblem problem = box_scene(SE3d(), false);
  problem.points.resize(3);
  SE3d T = pose(1, 2, 3, 0.1, 0.2, 0.3);
  const SE3d before = T;
  const auto report = semlio::gauss_newton(problem, T);
  CHECK(report.status == semlio::SolveStatus::kTooFewResiduals);
  CHECK_FALSE(report.ok());
  CHECK((T.matrix() - before.matrix()).norm() == 0.0);
}

TEST_CASE("Gauss-Newton with NaN input reports a numerical failure, never NaN", "[solve]") {
  PlaneProblem problem = box_scene(SE3d(), false);
  problem.points[5] = Eigen::Vector3d(std::nan(""), 0, 0);
  SE3d T = pose(0.1, 0, 0, 0, 0, 0);
  const SE3d before = T;
  const auto report = semlio::gauss_newton(problem, T);
  CHECK(report.status == semlio::SolveStatus::kNumericalFailure);
  CHECK(T.matrix().allFinite());
  CHECK((T.matrix() - before.matrix()).norm() == 0.0);
}

TEST_CASE("Gauss-Newton with every residual identical stays finite", "[solve]") {
  // All points at one location: rank-1 system (a single plane normal, one point).
  PlaneProblem problem;
  for (int i = 0; i < 50; ++i) {
    problem.points.emplace_back(1.0, 2.0, -1.7);
    problem.normals.emplace_back(0.0, 0.0, 1.0);
    problem.offsets.push_back(1.7);
  }
  SE3d T = pose(0.1, 0.1, 0.1, 0, 0, 0);
  const auto report = semlio::gauss_newton(problem, T);
  CHECK(report.ok());
  CHECK(report.degenerate_directions >= 5);
  CHECK(T.matrix().allFinite());
}
