#include <catch2/catch.hpp>

#include <semlio/solve/gauss_newton.hpp>

#include <cmath>
#include <random>
#include <vector>

// The degeneracy flag of gauss_newton() (file comment of solve/gauss_newton.hpp)
// on synthetic scenes whose weak directions follow from the geometry alone,
// and its invariance to the residual count and to the weights.
namespace test_degeneracy {  // one namespace per test file: the area compiles as one TU

using semlio::SE3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
constexpr double kPi = 3.14159265358979323846;
const double kRatio = semlio::GaussNewtonConfig{}.degeneracy_ratio;  // the default threshold

namespace {

// Exact point-to-plane terms seen from the identity pose (scan = map frame):
// residual n^T p + d, Jacobian [n^T, -n^T p^] (right perturbation at the
// identity). `weight` multiplies the squared cost (an IRLS weight);
// `residual_scale` multiplies r and J (a semantic weight, eq. 11-12), so H
// scales by its square; `copies` adds every term that many times.
struct PlaneTerms {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;
  double weight = 1.0;
  double residual_scale = 1.0;
  int copies = 1;

  void add(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    points.push_back(p);
    normals.push_back(n.normalized());
  }

  void linearize(const SE3d& T, semlio::NormalEquations& eq) const {
    for (int c = 0; c < copies; ++c) {
      for (std::size_t i = 0; i < points.size(); ++i) {
        // The plane through points[i] with normal normals[i], in the map frame.
        const Eigen::Vector3d& n = normals[i];
        Eigen::Matrix<double, 1, 1> r;
        r(0) = residual_scale * n.dot(T * points[i] - points[i]);
        Eigen::Matrix<double, 1, 6> J;
        J.head<3>() = residual_scale * n.transpose() * T.rotation();
        J.tail<3>() = -residual_scale * n.transpose() * T.rotation() * semlio::hat(points[i]);
        eq.add<1>(r, J, weight);
      }
    }
  }
};

// Uniform samples of [lo, hi].
struct Uniform {
  std::mt19937 rng{42};
  double operator()(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
};

// Ground: the plane z = -1.7 m (a sensor 1.7 m above it), points out to
// `radius_m` like a lidar's rings.
void add_ground(PlaneTerms& p, Uniform& u, int count, double radius_m) {
  for (int i = 0; i < count; ++i) {
    const double r = u(2.0, radius_m);
    const double a = u(-kPi, kPi);
    p.add({r * std::cos(a), r * std::sin(a), -1.7}, Eigen::Vector3d::UnitZ());
  }
}

// A wall y = y_m (normal along y) from x0 to x1, 0-3 m above the ground.
void add_side_wall(PlaneTerms& p, Uniform& u, int count, double y_m, double x0, double x1) {
  for (int i = 0; i < count; ++i) p.add({u(x0, x1), y_m, u(-1.7, 1.3)}, Eigen::Vector3d::UnitY());
}

// Solves from the truth (the identity) with the default settings and
// returns the report: the flag is judged on the final system (stage 2).
semlio::SolveReport analyse(PlaneTerms& p, const semlio::GaussNewtonConfig& config = {}) {
  SE3d T;
  const semlio::SolveReport report = semlio::gauss_newton(p, T, config);
  REQUIRE(report.ok());
  return report;
}

// Length of the part of unit vector e inside the span of the report's first
// degenerate_directions columns (1: e is a degenerate direction).
double flagged_part(const semlio::SolveReport& r, const Vector6& e) {
  Vector6 proj = Vector6::Zero();
  for (int k = 0; k < r.degenerate_directions; ++k) proj += r.eigenvectors.col(k).dot(e) * r.eigenvectors.col(k);
  return proj.norm();
}

Vector6 axis(int k) { return Vector6::Unit(k); }

void check_report_shape(const semlio::SolveReport& r) {
  CHECK(r.eigenvalues.allFinite());
  CHECK(r.normalized_eigenvalues.allFinite());
  // Orthonormal directions.
  CHECK((r.eigenvectors.transpose() * r.eigenvectors - Eigen::Matrix<double, 6, 6>::Identity()).norm() < 1e-9);
  // Degenerate ones first, each group ascending.
  for (int k = 1; k < 6; ++k) {
    if (k == r.degenerate_directions) continue;
    CHECK(r.normalized_eigenvalues[k] >= r.normalized_eigenvalues[k - 1] - 1e-12);
  }
}

}  // namespace

TEST_CASE("Degeneracy: a corridor is weak along its axis only", "[solve][degeneracy]") {
  // Ground and two walls along x, 3 m to either side, 40 m long: every point
  // has a normal across the axis, nothing can see a shift along it.
  Uniform u;
  PlaneTerms p;
  add_ground(p, u, 2000, 20.0);
  add_side_wall(p, u, 1500, 3.0, -20.0, 20.0);
  add_side_wall(p, u, 1500, -3.0, -20.0, 20.0);
  // (The ground's disk constrains nothing along x either: its normal is z.)
  const auto r = analyse(p);
  check_report_shape(r);
  CHECK(r.degenerate_directions == 1);
  CHECK(std::abs(r.eigenvectors(0, 0)) > 0.999);  // the weakest direction is x
  CHECK(r.normalized_eigenvalues[0] < 1e-9);
  CHECK(r.normalized_eigenvalues[1] > kRatio);
}

TEST_CASE("Degeneracy: a cylindrical tunnel is weak along its axis and in roll about it", "[solve][degeneracy]") {
  // Points on a 4 m cylinder around x, 40 m long: radial normals see neither
  // a shift along x nor a rotation about x (p x n has no x component).
  Uniform u;
  PlaneTerms p;
  for (int i = 0; i < 4000; ++i) {
    const double a = u(-kPi, kPi);
    const Eigen::Vector3d n(0.0, std::cos(a), std::sin(a));
    p.add(Eigen::Vector3d(u(-20.0, 20.0), 0.0, 0.0) + 4.0 * n, n);
  }
  const auto r = analyse(p);
  check_report_shape(r);
  CHECK(r.degenerate_directions == 2);
  CHECK(flagged_part(r, axis(0)) > 0.999);  // along the axis
  CHECK(flagged_part(r, axis(3)) > 0.999);  // roll about the axis
  CHECK(r.normalized_eigenvalues[2] > kRatio);
}

TEST_CASE("Degeneracy: a single wall leaves its in-plane translations and the rotation about its normal",
          "[solve][degeneracy]") {
  // A wall x = 10 m, 12 m wide and 8 m tall, centred on the sensor: it fixes
  // x (translation along its normal) and the two tilts; it cannot see y, z
  // (sliding in the plane) or the rotation about its normal (x).
  Uniform u;
  PlaneTerms p;
  for (int i = 0; i < 3000; ++i) p.add({10.0, u(-6.0, 6.0), u(-4.0, 4.0)}, Eigen::Vector3d::UnitX());
  const auto r = analyse(p);
  check_report_shape(r);
  CHECK(r.degenerate_directions == 3);
  CHECK(flagged_part(r, axis(1)) > 0.999);
  CHECK(flagged_part(r, axis(2)) > 0.999);
  CHECK(flagged_part(r, axis(3)) > 0.999);
  CHECK(flagged_part(r, axis(0)) < 1e-6);
  CHECK(r.normalized_eigenvalues.head<3>().maxCoeff() < 1e-9);
}

TEST_CASE("Degeneracy: an open field with ground only leaves x, y and yaw", "[solve][degeneracy]") {
  Uniform u;
  PlaneTerms p;
  add_ground(p, u, 5000, 40.0);
  const auto r = analyse(p);
  check_report_shape(r);
  CHECK(r.degenerate_directions == 3);
  CHECK(flagged_part(r, axis(0)) > 0.999);
  CHECK(flagged_part(r, axis(1)) > 0.999);
  CHECK(flagged_part(r, axis(5)) > 0.999);
  // Height, roll and pitch are well constrained: mu = 3 for z (the only
  // translation seen: the translational scale is a third of its
  // information); a tilt's mu is the mean squared lever arm about its axis
  // in units of degeneracy_length_m (1 m): ~y^2 or x^2 over a 40 m disk.
  CHECK(r.normalized_eigenvalues.tail<3>().minCoeff() == Approx(3.0).epsilon(0.02));
  CHECK(r.normalized_eigenvalues.tail<2>().minCoeff() > 100.0);
}

TEST_CASE("Degeneracy: a box of walls and ground is not degenerate", "[solve][degeneracy]") {
  Uniform u;
  PlaneTerms p;
  add_ground(p, u, 2000, 20.0);
  add_side_wall(p, u, 1000, 6.0, -15.0, 15.0);
  add_side_wall(p, u, 1000, -6.0, -15.0, 15.0);
  for (int i = 0; i < 1000; ++i) p.add({15.0, u(-6.0, 6.0), u(-1.7, 1.3)}, Eigen::Vector3d::UnitX());
  for (int i = 0; i < 1000; ++i) p.add({-15.0, u(-6.0, 6.0), u(-1.7, 1.3)}, Eigen::Vector3d::UnitX());
  const auto r = analyse(p);
  check_report_shape(r);
  CHECK_FALSE(r.degenerate());
  CHECK(r.normalized_eigenvalues.minCoeff() > kRatio);
  // The translational scale is the mean diagonal of H's translational block.
  const double s = r.hessian.diagonal().head<3>().mean();
  CHECK(r.normalized_eigenvalues[0] == Approx(r.eigenvalues[0] / s).epsilon(0.05));
}

TEST_CASE("Degeneracy: the flag does not depend on the residual count or the weights", "[solve][degeneracy]") {
  // A highway: ground, two low guard rails along x 8 m to either side, and
  // only a few points (50) of a sign gantry across the road that see x. The
  // along-road translation has ~1/20 of the translational information.
  Uniform u;
  PlaneTerms p;
  add_ground(p, u, 1500, 30.0);
  for (const double y : {8.0, -8.0}) {
    for (int i = 0; i < 400; ++i) p.add({u(-30.0, 30.0), y, u(-1.7, -0.9)}, Eigen::Vector3d::UnitY());
  }
  for (int i = 0; i < 50; ++i) p.add({25.0, u(-8.0, 8.0), u(3.0, 4.0)}, Eigen::Vector3d::UnitX());

  const auto reference = analyse(p);
  check_report_shape(reference);
  REQUIRE(reference.degenerate_directions == 1);
  CHECK(std::abs(reference.eigenvectors(0, 0)) > 0.99);  // along the road
  CHECK(reference.normalized_eigenvalues[0] < kRatio);
  CHECK(reference.normalized_eigenvalues[1] > kRatio);

  const auto same_flags = [&](const semlio::SolveReport& r, double h_factor) {
    CHECK(r.degenerate_directions == reference.degenerate_directions);
    for (int k = 0; k < 6; ++k) {
      CHECK(r.normalized_eigenvalues[k] == Approx(reference.normalized_eigenvalues[k]).epsilon(1e-9).margin(1e-12));
      // Information along each direction scales with H; directions agree up to sign.
      CHECK(r.eigenvalues[k] == Approx(h_factor * reference.eigenvalues[k]).epsilon(1e-9).margin(1e-9));
      CHECK(std::abs(r.eigenvectors.col(k).dot(reference.eigenvectors.col(k))) == Approx(1.0).epsilon(1e-9));
    }
  };
  SECTION("every residual twice") {
    p.copies = 2;
    const auto r = analyse(p);
    CHECK(r.num_residuals == 2 * reference.num_residuals);
    same_flags(r, 2.0);
  }
  SECTION("every residual ten times") {
    p.copies = 10;
    same_flags(analyse(p), 10.0);
  }
  SECTION("every IRLS weight x 0.3") {
    p.weight = 0.3;
    same_flags(analyse(p), 0.3);
  }
  SECTION("every semantic weight x 0.3 (r and J scaled: H x 0.09)") {
    p.residual_scale = 0.3;
    same_flags(analyse(p), 0.09);
  }
}

TEST_CASE("Degeneracy: LIO-SAM's absolute test moves with the weights, the normalised one does not",
          "[solve][degeneracy]") {
  // A well-constrained box with few points: the translational eigenvalues
  // of H are about 300-400 at weight 1 and 90-120 at weight 0.3, around
  // LIO-SAM's 100 -- the same geometry flagged or not depending on the
  // weights (the `full` preset's semantic weights are <= 1). The normalised
  // test calls it constrained at both.
  Uniform u;
  PlaneTerms p;
  add_ground(p, u, 400, 15.0);
  add_side_wall(p, u, 150, 5.0, -10.0, 10.0);
  add_side_wall(p, u, 150, -5.0, -10.0, 10.0);
  for (int i = 0; i < 150; ++i) p.add({10.0, u(-5.0, 5.0), u(-1.7, 1.3)}, Eigen::Vector3d::UnitX());
  for (int i = 0; i < 150; ++i) p.add({-10.0, u(-5.0, 5.0), u(-1.7, 1.3)}, Eigen::Vector3d::UnitX());
  for (const double w : {1.0, 0.3}) {
    INFO("weight " << w);
    p.weight = w;
    const auto absolute = analyse(p, {.degeneracy_ratio = 0.0});
    if (w == 1.0) CHECK_FALSE(absolute.degenerate());
    if (w == 0.3) CHECK(absolute.degenerate());
    const auto normalised = analyse(p);
    CHECK_FALSE(normalised.degenerate());
  }
}

TEST_CASE("Degeneracy: the flag on an empty block is all of it, never NaN", "[solve][degeneracy]") {
  // Every point at the origin: rotations see nothing (p x n = 0), the
  // rotational block of H is zero; normals along z and x fix two translations.
  PlaneTerms p;
  for (int i = 0; i < 20; ++i) p.add(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  for (int i = 0; i < 20; ++i) p.add(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  const auto r = analyse(p);
  check_report_shape(r);
  CHECK(r.degenerate_directions == 4);  // y and the three rotations
  CHECK(flagged_part(r, axis(1)) > 0.999);
  for (int k = 3; k < 6; ++k) CHECK(flagged_part(r, axis(k)) > 0.999);
}

TEST_CASE("Degeneracy: a length that is not a positive length is a ConfigError", "[solve][degeneracy]") {
  Uniform u;
  PlaneTerms p;
  add_ground(p, u, 100, 20.0);
  for (const double bad : {0.0, -1.0, std::nan("")}) {
    SE3d T;
    CHECK_THROWS_AS(semlio::gauss_newton(p, T, {.degeneracy_length_m = bad}), semlio::ConfigError);
  }
  // The absolute test alone does not use it.
  SE3d T;
  CHECK(semlio::gauss_newton(p, T, {.degeneracy_ratio = 0.0, .degeneracy_length_m = 0.0}).ok());
}

}  // namespace test_degeneracy
