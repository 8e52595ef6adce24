// SO(3): exp/log, small and near-pi angles, Jacobians against central
// differences, group axioms. Random points come from a fixed seed.
#include <catch2/catch.hpp>

#include <semlio/lie/so3.hpp>
#include <semlio_test/lie_random.hpp>

#include <cmath>
#include <numbers>
#include <vector>

namespace test_so3 {  // one namespace per test file: the area compiles as one TU

using semlio::SO3;
using semlio::SO3d;
using semlio::SO3f;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

namespace {

constexpr double kPi = std::numbers::pi;

// Per-scalar tolerances of the generic suite.
template <typename Scalar>
struct Tol;
template <>
struct Tol<double> {
  static constexpr double kRoundTrip = 1e-12;
  static constexpr double kGroup = 1e-12;
};
template <>
struct Tol<float> {
  static constexpr double kRoundTrip = 2e-5;
  static constexpr double kGroup = 2e-6;
};

// Rodrigues' formula, written independently of the class under test.
Mat3 rodrigues(const Vec3& phi) {
  const double t = phi.norm();
  if (t == 0.0) return Mat3::Identity();
  const Vec3 a = phi / t;
  const Mat3 K = semlio::hat(a);
  return Mat3::Identity() + std::sin(t) * K + (1.0 - std::cos(t)) * K * K;
}

// Column k of Jr by central differences: log(exp(phi)^-1 exp(phi + h e_k)) / h.
Mat3 numeric_right_jacobian(const Vec3& phi, double h = 1e-6) {
  Mat3 J;
  const SO3d Rinv = SO3d::exp(phi).inverse();
  for (int k = 0; k < 3; ++k) {
    const Vec3 d = h * Vec3::Unit(k);
    J.col(k) = ((Rinv * SO3d::exp(phi + d)).log() - (Rinv * SO3d::exp(phi - d)).log()) / (2.0 * h);
  }
  return J;
}

// Column k of Jl by central differences: log(exp(phi + h e_k) exp(phi)^-1) / h.
Mat3 numeric_left_jacobian(const Vec3& phi, double h = 1e-6) {
  Mat3 J;
  const SO3d Rinv = SO3d::exp(phi).inverse();
  for (int k = 0; k < 3; ++k) {
    const Vec3 d = h * Vec3::Unit(k);
    J.col(k) = ((SO3d::exp(phi + d) * Rinv).log() - (SO3d::exp(phi - d) * Rinv).log()) / (2.0 * h);
  }
  return J;
}

// Same rotation up to the sign of the axis: both rotation vectors of angle pi.
bool same_axis_up_to_sign(const Vec3& a, const Vec3& b, double tol) {
  return (a - b).norm() < tol || (a + b).norm() < tol;
}

}  // namespace

TEMPLATE_TEST_CASE("SO3 exp/log round trip at random points", "[lie]", float, double) {
  using S = TestType;
  using V = Eigen::Matrix<S, 3, 1>;
  semlio_test::LieRandom rng(1);
  for (int i = 0; i < 500; ++i) {
    const Vec3 phi = rng.rotation_vector(0.0, kPi - 1e-2);
    const V phi_s = phi.cast<S>();
    const SO3<S> R = SO3<S>::exp(phi_s);
    CHECK((R.log() - phi_s).template cast<double>().norm() < Tol<S>::kRoundTrip);
    CHECK((SO3<S>::exp(R.log()).matrix() - R.matrix()).template cast<double>().norm() < Tol<S>::kRoundTrip);
    // exp agrees with Rodrigues' formula computed in double.
    CHECK((R.matrix().template cast<double>() - rodrigues(phi_s.template cast<double>())).norm() <
          Tol<S>::kRoundTrip);
  }
}

TEMPLATE_TEST_CASE("SO3 group axioms: inverse, compose, act on points, hat/vee", "[lie]", float, double) {
  using S = TestType;
  using V = Eigen::Matrix<S, 3, 1>;
  using M = Eigen::Matrix<S, 3, 3>;
  semlio_test::LieRandom rng(2);
  for (int i = 0; i < 200; ++i) {
    const SO3<S> A = SO3<S>::exp(rng.rotation_vector(0.0, kPi).cast<S>());
    const SO3<S> B = SO3<S>::exp(rng.rotation_vector(0.0, kPi).cast<S>());
    const V p = rng.box(10.0).cast<S>();
    const double scale = 10.0;
    // Identity and inverse.
    CHECK(((A * A.inverse()).matrix() - M::Identity()).template cast<double>().norm() < Tol<S>::kGroup);
    CHECK(((A.inverse() * A).matrix() - M::Identity()).template cast<double>().norm() < Tol<S>::kGroup);
    CHECK((A.inverse().matrix() - A.matrix().transpose()).template cast<double>().norm() < Tol<S>::kGroup);
    // Composition applies the right factor first, and matches matrix products.
    CHECK(((A * B) * p - A * (B * p)).template cast<double>().norm() < scale * Tol<S>::kGroup * 4);
    CHECK(((A * B).matrix() - A.matrix() * B.matrix()).template cast<double>().norm() < Tol<S>::kGroup * 4);
    CHECK((A * p - A.matrix() * p).template cast<double>().norm() < scale * Tol<S>::kGroup * 4);
    // Rotations preserve length; matrices are orthonormal with det +1.
    CHECK(std::abs(static_cast<double>((A * p).norm() - p.norm())) < scale * Tol<S>::kGroup * 4);
    CHECK(std::abs(static_cast<double>(A.matrix().determinant()) - 1.0) < Tol<S>::kGroup * 4);
    // Adjoint of SO(3): A exp(phi) A^-1 = exp(A phi).
    const V phi = rng.rotation_vector(0.0, 2.0).cast<S>();
    CHECK(((A * SO3<S>::exp(phi) * A.inverse()).matrix() - SO3<S>::exp(A.adjoint() * phi).matrix())
              .template cast<double>()
              .norm() < Tol<S>::kGroup * 4);
    // hat/vee.
    const V w = rng.box(3.0).cast<S>();
    CHECK((semlio::hat(p) * w - p.cross(w)).template cast<double>().norm() < scale * Tol<S>::kGroup * 4);
    CHECK((semlio::vee(semlio::hat(p)) - p).template cast<double>().norm() == 0.0);
    // Angle is |log|.
    CHECK(std::abs(static_cast<double>(A.angle() - A.log().norm())) < Tol<S>::kGroup);
  }
}

TEST_CASE("SO3 constructors normalise quaternions and read rotation matrices", "[lie]") {
  const Eigen::Quaterniond q(2.0, 0.4, -0.2, 1.0);  // not unit
  const SO3d R(q);
  CHECK(std::abs(R.quaternion().norm() - 1.0) < 1e-15);
  CHECK((R.matrix() - q.normalized().toRotationMatrix()).norm() < 1e-15);
  const SO3d R2(R.matrix());
  CHECK((R2.matrix() - R.matrix()).norm() < 1e-14);
  CHECK(SO3d().log().norm() == 0.0);
  CHECK((SO3d().matrix() - Mat3::Identity()).norm() == 0.0);
}

TEST_CASE("SO3 exp/log near zero: 1e-9, 1e-6 and both sides of the 1e-4 switch", "[lie]") {
  semlio_test::LieRandom rng(3);
  const double boundary = SO3d::kSmallAngle;
  const std::vector<double> angles{0.0,  1e-12, 1e-9, 1e-6, 1e-5, boundary * (1.0 - 1e-9), boundary,
                                   boundary * (1.0 + 1e-9), 2e-4, 1e-3};
  for (const double theta : angles) {
    for (int i = 0; i < 20; ++i) {
      const Vec3 phi = theta * rng.direction();
      const SO3d R = SO3d::exp(phi);
      INFO("theta = " << theta);
      // Relative accuracy of the round trip (the rotation vector is tiny).
      CHECK((R.log() - phi).norm() <= 1e-14 * std::max(theta, 1e-300) + 1e-300);
      // exp agrees with the second-order expansion (error O(theta^3)).
      const Mat3 K = semlio::hat(phi);
      CHECK((R.matrix() - (Mat3::Identity() + K + 0.5 * K * K)).norm() < theta * theta * theta + 1e-16);
      // Jacobians agree with their series I -/+ K/2 + K^2/6 (or /12).
      CHECK((SO3d::right_jacobian(phi) - (Mat3::Identity() - 0.5 * K + K * K / 6.0)).norm() <
            theta * theta * theta + 1e-16);
      CHECK((SO3d::right_jacobian_inverse(phi) - (Mat3::Identity() + 0.5 * K + K * K / 12.0)).norm() <
            theta * theta * theta + 1e-16);
    }
  }
}

TEST_CASE("SO3 Taylor and closed-form branches agree across the small-angle switch", "[lie]") {
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  const double b = SO3d::kSmallAngle;
  const Vec3 below = b * (1.0 - 1e-9) * axis;
  const Vec3 above = b * (1.0 + 1e-9) * axis;
  CHECK((SO3d::exp(below).matrix() - SO3d::exp(above).matrix()).norm() < 1e-12);
  CHECK((SO3d::exp(below).log() - SO3d::exp(above).log()).norm() < 1e-12);
  CHECK((SO3d::right_jacobian(below) - SO3d::right_jacobian(above)).norm() < 1e-12);
  CHECK((SO3d::right_jacobian_inverse(below) - SO3d::right_jacobian_inverse(above)).norm() < 1e-12);
}

TEST_CASE("SO3 log near pi: pi - 1e-6 about random axes", "[lie]") {
  semlio_test::LieRandom rng(4);
  for (const double theta : {kPi - 1e-3, kPi - 1e-6, kPi - 1e-9}) {
    for (int i = 0; i < 50; ++i) {
      const Vec3 axis = rng.direction();
      const SO3d R = SO3d::exp(theta * axis);
      const Vec3 phi = R.log();
      INFO("theta = pi - " << kPi - theta);
      CHECK(std::abs(phi.norm() - theta) < 1e-12);
      CHECK((phi - theta * axis).norm() < 1e-9);
      CHECK((SO3d::exp(phi).matrix() - R.matrix()).norm() < 1e-12);
      CHECK((R.matrix() - rodrigues(theta * axis)).norm() < 1e-12);
    }
  }
}

TEST_CASE("SO3 log at exactly pi returns angle pi and the axis up to sign", "[lie]") {
  semlio_test::LieRandom rng(5);
  std::vector<Vec3> axes{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ(), Vec3(1, 1, 1).normalized(),
                         Vec3(1, -2, 0.5).normalized()};
  for (int i = 0; i < 20; ++i) axes.push_back(rng.direction());
  for (const Vec3& axis : axes) {
    INFO("axis " << axis.transpose());
    // Build the rotation both from the exponential and from the exact matrix
    // 2 a a^T - I (rotation by pi about a).
    const SO3d from_exp = SO3d::exp(kPi * axis);
    const SO3d from_matrix(Mat3(2.0 * axis * axis.transpose() - Mat3::Identity()));
    for (const SO3d& R : {from_exp, from_matrix}) {
      const Vec3 phi = R.log();
      CHECK(std::abs(phi.norm() - kPi) < 1e-12);
      CHECK(same_axis_up_to_sign(phi / phi.norm(), axis, 1e-9));
      CHECK((SO3d::exp(phi).matrix() - R.matrix()).norm() < 1e-12);
      CHECK(std::abs(R.angle() - kPi) < 1e-12);
    }
  }
}

TEST_CASE("SO3 right Jacobian matches central differences at random points", "[lie]") {
  semlio_test::LieRandom rng(6);
  for (int i = 0; i < 300; ++i) {
    // Stay away from pi where log wraps and a difference step crosses it.
    const Vec3 phi = rng.rotation_vector(0.0, kPi - 1e-2);
    INFO("phi = " << phi.transpose());
    CHECK((SO3d::right_jacobian(phi) - numeric_right_jacobian(phi)).norm() < 1e-8);
    CHECK((SO3d::left_jacobian(phi) - numeric_left_jacobian(phi)).norm() < 1e-8);
    // Jr^-1 by central differences of log(exp(phi) exp(d)).
    Mat3 Jinv_num;
    const SO3d R = SO3d::exp(phi);
    for (int k = 0; k < 3; ++k) {
      const Vec3 d = 1e-6 * Vec3::Unit(k);
      Jinv_num.col(k) = ((R * SO3d::exp(d)).log() - (R * SO3d::exp(-d)).log()) / 2e-6;
    }
    CHECK((SO3d::right_jacobian_inverse(phi) - Jinv_num).norm() < 1e-8);
  }
  // Small angles, where the Taylor branch is used.
  for (const double theta : {1e-9, 1e-6, 5e-5, 1e-4, 2e-4}) {
    const Vec3 phi = theta * rng.direction();
    CHECK((SO3d::right_jacobian(phi) - numeric_right_jacobian(phi)).norm() < 1e-8);
  }
}

TEST_CASE("SO3 right Jacobian inverse inverts it, also near 0 and near pi", "[lie]") {
  semlio_test::LieRandom rng(7);
  std::vector<Vec3> points;
  for (int i = 0; i < 300; ++i) points.push_back(rng.rotation_vector(0.0, kPi));
  for (const double theta : {0.0, 1e-9, 1e-6, 1e-4, 2e-4, kPi - 1e-6, kPi}) points.push_back(theta * rng.direction());
  for (const Vec3& phi : points) {
    INFO("phi = " << phi.transpose());
    CHECK((SO3d::right_jacobian_inverse(phi) * SO3d::right_jacobian(phi) - Mat3::Identity()).norm() < 1e-12);
    CHECK((SO3d::right_jacobian(phi) * SO3d::right_jacobian_inverse(phi) - Mat3::Identity()).norm() < 1e-12);
    CHECK((SO3d::left_jacobian_inverse(phi) * SO3d::left_jacobian(phi) - Mat3::Identity()).norm() < 1e-12);
  }
}

TEST_CASE("SO3 left and right Jacobians: Jl(phi) = Jr(-phi) = exp(phi) Jr(phi)", "[lie]") {
  semlio_test::LieRandom rng(8);
  for (int i = 0; i < 200; ++i) {
    const Vec3 phi = rng.rotation_vector(0.0, kPi);
    const Mat3 Jr = SO3d::right_jacobian(phi);
    CHECK((SO3d::left_jacobian(phi) - SO3d::right_jacobian(-phi)).norm() < 1e-14);
    CHECK((SO3d::left_jacobian(phi) - SO3d::exp(phi).matrix() * Jr).norm() < 1e-12);
    CHECK((SO3d::left_jacobian(phi) - Jr.transpose()).norm() < 1e-12);
  }
}

TEST_CASE("SO3 float right Jacobian is accurate just above the small-angle switch", "[lie]") {
  // Float has 24-bit mantissas; (1 - cos t) / t^2 cancels catastrophically at
  // t ~ 1e-4, so the Jacobian must stay within float precision of the double
  // one everywhere. Demonstrates a precision defect reported to the lead.
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  for (const double theta : {5e-5, 1.5e-4, 2e-4, 5e-4, 1e-3, 1e-2, 0.1, 1.0}) {
    INFO("theta = " << theta);
    const Vec3 phi = theta * axis;
    const Mat3 Jf = SO3f::right_jacobian(phi.cast<float>()).cast<double>();
    CHECK((Jf - SO3d::right_jacobian(phi)).cwiseAbs().maxCoeff() < 1e-6);
  }
}

TEST_CASE("SO3 float and double agree and convert with cast", "[lie]") {
  const Vec3 phi(0.4, -1.2, 0.7);
  const SO3d Rd = SO3d::exp(phi);
  const SO3f Rf = SO3f::exp(phi.cast<float>());
  CHECK((Rf.matrix().cast<double>() - Rd.matrix()).norm() < 1e-6);
  CHECK((Rd.cast<float>().matrix() - Rf.matrix()).norm() < 1e-6F);
  CHECK((Rf.cast<double>().log() - phi).norm() < 1e-6);
}

}  // namespace test_so3
