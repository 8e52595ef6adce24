#include <catch2/catch.hpp>

#include <semlio/solve/gauss_newton.hpp>

#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace test_gauss_newton {  // one namespace per test file: the area compiles as one TU

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

namespace {

// Correspondences whose quality depends on where they were chosen, as nearest
// neighbours picked from an offset pose are pulled towards it: associate(T)
// aims the translation halfway between T and the truth, so a solver that
// stops on a small step from matches chosen at an earlier pose stops short.
// Rotation is held at identity by its own rows.
struct BiasedMatchProblem {
  Eigen::Vector3d truth{0.3, -0.2, 0.1};
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  int associations = 0;

  void associate(const SE3d& T) {
    target = truth + 0.5 * (T.translation() - truth);
    ++associations;
  }

  void linearize(const SE3d& T, semlio::NormalEquations& eq) const {
    constexpr double kWeight = 10.0;  // information well above the degeneracy threshold
    Eigen::Matrix<double, 3, 6> Jt = Eigen::Matrix<double, 3, 6>::Zero();
    Jt.leftCols<3>() = kWeight * T.rotation();
    Eigen::Matrix<double, 3, 6> Jr = Eigen::Matrix<double, 3, 6>::Zero();
    Jr.rightCols<3>() = kWeight * Eigen::Matrix3d::Identity();
    const Eigen::Vector3d rt = kWeight * (T.translation() - target);
    const Eigen::Vector3d rr = kWeight * T.log().tail<3>();
    for (int k = 0; k < 10; ++k) {
      eq.add<3>(rt, Jt);
      eq.add<3>(rr, Jr);
    }
  }
};

}  // namespace

TEST_CASE("Gauss-Newton re-associates before it declares convergence", "[solve]") {
  for (const int every : {1, 2, 3}) {
    BiasedMatchProblem problem;
    SE3d T;
    const semlio::GaussNewtonConfig config{.max_iterations = 60, .reassociate_every = every};
    const auto report = semlio::gauss_newton(problem, T, config);
    INFO("reassociate_every = " << every);
    CHECK(report.status == semlio::SolveStatus::kConverged);
    // Each association halves the error, so reaching the truth within the
    // 0.5 mm step tolerance needs ~10 of them whatever the schedule; stopping
    // on a step from stale matches left it 18.7 cm short.
    CHECK((T.translation() - problem.truth).norm() < 1e-3);
    CHECK(problem.associations >= 9);
    // The last system solved came from matches chosen at (nearly) the final pose.
    CHECK((problem.target - problem.truth).norm() < 1e-3);
  }
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
  // The constrained subspace converges to the step tolerance, not to zero.
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

namespace {

// Plane points matched only while they are within `gate_m` of their plane at
// the current pose (a nearest-neighbour distance gate), re-evaluated at every
// association.
struct GatedPlaneProblem {
  PlaneProblem all;
  std::vector<bool> active;
  double gate_m = 1.0;

  void associate(const SE3d& T) {
    active.assign(all.points.size(), false);
    for (std::size_t i = 0; i < all.points.size(); ++i) {
      const double d = all.normals[i].dot(T * all.points[i]) + all.offsets[i];
      active[i] = std::abs(d) < gate_m;
    }
  }

  void linearize(const SE3d& T, semlio::NormalEquations& eq) const {
    for (std::size_t i = 0; i < all.points.size(); ++i) {
      if (!active[i]) continue;
      const Eigen::Vector3d q = T * all.points[i];
      Eigen::Matrix<double, 1, 1> r;
      r(0) = all.normals[i].dot(q) + all.offsets[i];
      Eigen::Matrix<double, 1, 6> J;
      J.head<3>() = all.normals[i].transpose() * T.rotation();
      J.tail<3>() = -all.normals[i].transpose() * T.rotation() * semlio::hat(all.points[i]);
      eq.add<1>(r, J);
    }
  }
};

// Adds `count` points of the plane n.x + d = 0 (map frame) seen from T_true,
// spread over a square of half-size `half_m` around the plane's foot point
// shifted by `centre`.
void add_plane(PlaneProblem& p, const SE3d& T_true, const Eigen::Vector3d& n, double d, const Eigen::Vector3d& centre,
               double half_m, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-half_m, half_m);
  const Eigen::Vector3d a = n.unitOrthogonal();
  const Eigen::Vector3d b = n.cross(a);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d q_map = -d * n + centre + u(rng) * a + u(rng) * b;
    p.points.push_back(T_true.inverse() * q_map);
    p.normals.push_back(n);
    p.offsets.push_back(d);
  }
}

}  // namespace

TEST_CASE("Gauss-Newton re-analyses degeneracy after re-association", "[solve]") {
  // Truth: the sensor moved 0.9 m along x and turned -0.03 rad in yaw. Ground
  // (normal z) and two walls along x (normal y) constrain everything but x. A
  // cross wall (normal x) off to the left (y = 4..12 m) would constrain x,
  // but at the identity start its points are 0.9 m (x) + 0.12-0.36 m (yaw
  // times lateral offset) = 1.02-1.26 m from it, outside the 1 m gate: the
  // first system is degenerate in x. Once the yaw is solved (x still at the
  // start) they are 0.9 m away and get matched.
  const SE3d T_true = pose(0.9, 0.05, 0.02, 0.0, 0.0, -0.03);
  std::mt19937 rng(11);
  GatedPlaneProblem problem;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  add_plane(problem.all, T_true, z, 1.7, Eigen::Vector3d(5.0, 0.0, 0.0), 4.0, 2000, rng);
  add_plane(problem.all, T_true, y, -4.0, Eigen::Vector3d(5.0, 0.0, 0.0), 4.0, 1500, rng);
  add_plane(problem.all, T_true, -y, -4.0, Eigen::Vector3d(5.0, 0.0, 0.0), 4.0, 1500, rng);
  add_plane(problem.all, T_true, x, -15.0, Eigen::Vector3d(0.0, 8.0, 0.0), 4.0, 1500, rng);
  problem.associate(SE3d());
  std::size_t cross_active = 0;
  for (std::size_t i = 5000; i < problem.all.points.size(); ++i) cross_active += problem.active[i] ? 1U : 0U;
  REQUIRE(cross_active == 0);
  // LIO-SAM's absolute test only: this small scene's x/yaw coupling is below
  // the default relative ratio (tested separately below).

  SECTION("LIO-SAM semantics (first iteration only) freeze x at the start") {
    SE3d T;
    const semlio::GaussNewtonConfig config{.degeneracy_ratio = 0.0, .reanalyse_degeneracy = false};
    const auto report = semlio::gauss_newton(problem, T, config);
    INFO("eigenvalues " << report.eigenvalues.transpose() << " v0 " << report.eigenvectors.col(0).transpose());
    CHECK(report.ok());
    CHECK(report.initial_degenerate_directions == 1);
    CHECK(report.analyses == 1);
    // x barely moves (only through the yaw coupling of body-frame steps).
    CHECK(std::abs(T.translation().x()) < 0.02);
  }
  SECTION("re-analysis follows the problem: x converges once the cross wall is matched") {
    SE3d T;
    const auto report = semlio::gauss_newton(problem, T, {.degeneracy_ratio = 0.0, .reanalyse_degeneracy = true});
    INFO("analyses " << report.analyses << " residuals " << report.num_residuals << " T " << T.log().transpose()
                     << " eigenvalues " << report.eigenvalues.transpose() << " v0 " << report.eigenvectors.col(0).transpose());
    CHECK(report.ok());
    // The first analysis found x unconstrained...
    CHECK(report.initial_degenerate_directions == 1);
    CHECK(report.analyses > 1);
    // ...the last one does not: the cross wall's points are used.
    CHECK_FALSE(report.degenerate());
    CHECK(report.num_residuals == problem.all.points.size());
    CHECK((T.inverse() * T_true).log().norm() < 1e-6);
    CHECK(T.matrix().allFinite());
  }
}

TEST_CASE("Gauss-Newton damps a weak direction instead of freezing it when asked", "[solve]") {
  // Truth: 1.1 m along x. Ground and two walls along x fix everything but x.
  // A small slanted wall (40 points, normal 45 deg between x and y) is within
  // the 1 m gate at the identity start (0.78 m off) but gives x only ~20 of
  // information, below the absolute threshold (100): x is degenerate there.
  // A large cross wall (normal x) would fix x, but its points are 1.1 m off,
  // outside the gate, until x has moved by 0.1 m. Re-analysis alone cannot
  // get there (x frozen -> same association -> x still weak); damping moves
  // x by a shortened step, the cross wall enters and x converges.
  const SE3d T_true = pose(1.1, 0.0, 0.0, 0.0, 0.0, 0.0);
  std::mt19937 rng(13);
  GatedPlaneProblem problem;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  add_plane(problem.all, T_true, z, 1.7, Eigen::Vector3d(5.0, 0.0, 0.0), 4.0, 2000, rng);
  add_plane(problem.all, T_true, y, -4.0, Eigen::Vector3d(5.0, 0.0, 0.0), 4.0, 1500, rng);
  add_plane(problem.all, T_true, -y, -4.0, Eigen::Vector3d(5.0, 0.0, 0.0), 4.0, 1500, rng);
  add_plane(problem.all, T_true, Eigen::Vector3d(1.0, 1.0, 0.0).normalized(), -12.0, Eigen::Vector3d::Zero(), 0.5,
            40, rng);
  add_plane(problem.all, T_true, x, -15.0, Eigen::Vector3d::Zero(), 3.0, 1500, rng);
  problem.associate(SE3d());
  std::size_t slanted = 0;
  std::size_t cross = 0;
  for (std::size_t i = 5000; i < 5040; ++i) slanted += problem.active[i] ? 1U : 0U;
  for (std::size_t i = 5040; i < problem.all.points.size(); ++i) cross += problem.active[i] ? 1U : 0U;
  REQUIRE(slanted == 40);
  REQUIRE(cross == 0);

  SECTION("frozen: x stays at the start, reported degenerate") {
    SE3d T;
    const auto report = semlio::gauss_newton(problem, T, {.degeneracy_ratio = 0.0, .reanalyse_degeneracy = true});
    INFO("eigenvalues " << report.eigenvalues.transpose() << " T " << T.log().transpose());
    CHECK(report.ok());
    CHECK(report.degenerate());
    CHECK(std::abs(T.translation().x()) < 0.02);
  }
  SECTION("damped: x converges to the truth, the final system is not degenerate") {
    SE3d T;
    const auto report = semlio::gauss_newton(
        problem, T, {.degeneracy_ratio = 0.0, .reanalyse_degeneracy = true, .damp_degenerate = true});
    INFO("eigenvalues " << report.eigenvalues.transpose() << " T " << T.log().transpose() << " iterations "
                        << report.iterations);
    CHECK(report.ok());
    CHECK(report.initial_degenerate_directions == 1);
    CHECK_FALSE(report.degenerate());
    CHECK(report.num_residuals == problem.all.points.size());
    CHECK((T.inverse() * T_true).log().norm() < 1e-6);
  }
  SECTION("a start reset along weak directions is a measurement: damping is not applied, x stays") {
    SE3d T;
    const auto report = semlio::gauss_newton(problem, T,
                                             {.degeneracy_ratio = 0.0, .reanalyse_degeneracy = true,
                                              .reset_weak_directions = true, .damp_degenerate = true});
    CHECK(report.ok());
    CHECK(report.degenerate());
    CHECK(std::abs(T.translation().x()) < 0.02);
  }
}

TEST_CASE("Gauss-Newton in a corridor reports the corridor axis as degenerate", "[solve]") {
  // Ground and two walls along x: motion along x is unconstrained, whatever
  // the re-association does; the solver must say so, in that direction.
  const SE3d T_true = pose(0.3, 0.05, 0.02, 0.01, 0.0, 0.02);
  std::mt19937 rng(5);
  GatedPlaneProblem problem;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  add_plane(problem.all, T_true, z, 1.7, Eigen::Vector3d(5.0, 0.0, 0.0), 10.0, 300, rng);
  add_plane(problem.all, T_true, y, -3.0, Eigen::Vector3d(5.0, 0.0, 0.0), 10.0, 200, rng);
  add_plane(problem.all, T_true, -y, -3.0, Eigen::Vector3d(5.0, 0.0, 0.0), 10.0, 200, rng);
  for (const auto& [reanalyse, damp] : {std::pair{true, false}, std::pair{false, false}, std::pair{true, true}}) {
    SE3d T = pose(0.1, 0.0, 0.0, 0.0, 0.0, 0.0);
    const semlio::GaussNewtonConfig config{.reanalyse_degeneracy = reanalyse, .damp_degenerate = damp};
    const auto report = semlio::gauss_newton(problem, T, config);
    INFO("reanalyse " << reanalyse << " damp " << damp);
    REQUIRE(report.ok());
    CHECK(report.degenerate_directions == 1);
    // The degenerate direction (first column) is the corridor axis: pure x.
    const Eigen::Matrix<double, 6, 1> v = report.eigenvectors.col(0);
    CHECK(std::abs(v(0)) > 0.999);
    CHECK(report.eigenvalues(0) < 1e-6);
    CHECK(report.eigenvalues.allFinite());
    CHECK(report.eigenvectors.allFinite());
    CHECK(report.hessian.allFinite());
    CHECK(std::isfinite(report.final_cost));
    CHECK(T.matrix().allFinite());
    // x stays at the start (up to the yaw coupling of body-frame steps),
    // everything else is solved -- damped too: the data give x no gradient.
    CHECK(std::abs(T.translation().x() - 0.1) < 0.005);
    CHECK(std::abs(T.translation().y() - T_true.translation().y()) < 1e-3);
    CHECK(std::abs(T.translation().z() - T_true.translation().z()) < 1e-3);
  }
}

TEST_CASE("Gauss-Newton's relative degeneracy test does not depend on the residual count", "[solve]") {
  // A corridor (ground + two walls along x) with a weak cross wall holding 2 %
  // as many points: x's eigenvalue grows with the point count and passes the
  // absolute threshold (100) for dense scans, but stays ~1/50 of the
  // translational information at any density.
  for (const int n : {300, 10000}) {
    std::mt19937 rng(3);
    PlaneProblem problem;
    const SE3d T_true;
    const Eigen::Vector3d c(5.0, 0.0, 0.0);
    add_plane(problem, T_true, Eigen::Vector3d::UnitZ(), 1.7, c, 10.0, n, rng);
    add_plane(problem, T_true, Eigen::Vector3d::UnitY(), -3.0, c, 10.0, n, rng);
    add_plane(problem, T_true, -Eigen::Vector3d::UnitY(), -3.0, c, 10.0, n, rng);
    add_plane(problem, T_true, Eigen::Vector3d::UnitX(), -20.0, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0, n / 50, rng);
    INFO("points per plane " << n);
    SE3d T;
    const auto absolute = semlio::gauss_newton(problem, T, {.degeneracy_ratio = 0.0});
    REQUIRE(absolute.ok());
    // x's eigenvalue is about the cross wall's point count (unit normals).
    if (n == 300) CHECK(absolute.degenerate_directions == 1);
    if (n == 10000) CHECK_FALSE(absolute.degenerate());
    T = SE3d();
    const auto relative = semlio::gauss_newton(problem, T, {.degeneracy_ratio = 0.05});
    REQUIRE(relative.ok());
    CHECK(relative.degenerate_directions == 1);
    CHECK(std::abs(relative.eigenvectors(0, 0)) > 0.99);
    // The other five directions are well inside the ratio.
    const double t_scale = relative.hessian.diagonal().head<3>().mean();
    CHECK(relative.eigenvalues(0) < 0.05 * t_scale);
    CHECK(relative.eigenvalues.tail<5>().minCoeff() > 0.05 * t_scale);
  }
}

TEST_CASE("Gauss-Newton puts weak directions back at the start only when asked", "[solve]") {
  // The corridor with a weak cross wall (x has ~1/50 of the translational
  // information): the data pull x to the truth (0); the relative test calls
  // x weak. By default that is only reported; with reset_weak_directions the
  // start's x (the prediction) is kept and the rest is re-solved.
  std::mt19937 rng(3);
  PlaneProblem problem;
  const SE3d T_true;
  const Eigen::Vector3d c(5.0, 0.0, 0.0);
  add_plane(problem, T_true, Eigen::Vector3d::UnitZ(), 1.7, c, 10.0, 10000, rng);
  add_plane(problem, T_true, Eigen::Vector3d::UnitY(), -3.0, c, 10.0, 10000, rng);
  add_plane(problem, T_true, -Eigen::Vector3d::UnitY(), -3.0, c, 10.0, 10000, rng);
  add_plane(problem, T_true, Eigen::Vector3d::UnitX(), -20.0, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0, 200, rng);
  const SE3d T_start = pose(0.3, 0.1, 0.05, 0.0, 0.0, 0.0);
  for (const bool reset : {false, true}) {
    INFO("reset " << reset);
    SE3d T = T_start;
    const auto report = semlio::gauss_newton(problem, T, {.reset_weak_directions = reset});
    REQUIRE(report.ok());
    CHECK(report.degenerate_directions == 1);
    CHECK(std::abs(report.eigenvectors(0, 0)) > 0.99);
    CHECK(T.matrix().allFinite());
    // y and z are solved either way.
    CHECK(std::abs(T.translation().y()) < 1e-3);
    CHECK(std::abs(T.translation().z()) < 1e-3);
    if (reset) {
      CHECK(std::abs(T.translation().x() - 0.3) < 1e-3);
    } else {
      CHECK(std::abs(T.translation().x()) < 1e-3);
    }
  }
}

}  // namespace test_gauss_newton
