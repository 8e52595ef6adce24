#pragma once
/// \file
/// SO(3), the rotation group, as an owning value type over a unit quaternion.
///
/// Convention (the one used everywhere in semlio, see se3.hpp): right
/// perturbation, R (+) phi = R * exp(phi); Jacobians are named J_out_in.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

namespace semlio {

/// Skew-symmetric matrix of v, so that hat(v) * w == v.cross(w).
template <typename Scalar>
Eigen::Matrix<Scalar, 3, 3> hat(const Eigen::Matrix<Scalar, 3, 1>& v) {
  Eigen::Matrix<Scalar, 3, 3> m;
  m << Scalar(0), -v.z(), v.y(), v.z(), Scalar(0), -v.x(), -v.y(), v.x(), Scalar(0);
  return m;
}

/// Inverse of hat: the vector of a skew-symmetric matrix.
template <typename Scalar>
Eigen::Matrix<Scalar, 3, 1> vee(const Eigen::Matrix<Scalar, 3, 3>& m) {
  return {m(2, 1), m(0, 2), m(1, 0)};
}

/// A 3D rotation. Stored as a unit quaternion; always normalised.
template <typename Scalar>
class SO3 {
 public:
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Quaternion = Eigen::Quaternion<Scalar>;

  /// Below this angle [rad] the closed forms switch to Taylor series.
  static constexpr Scalar kSmallAngle = Scalar(1e-4);

  /// Identity rotation.
  SO3() : q_(Quaternion::Identity()) {}
  /// From a quaternion; it is normalised (it must not be zero).
  explicit SO3(const Quaternion& q) : q_(q.normalized()) {}
  /// From a rotation matrix; the nearest rotation is taken through the quaternion.
  explicit SO3(const Matrix3& R) : q_(Quaternion(R).normalized()) {}

  /// Exponential map: rotation by |phi| about phi/|phi|.
  static SO3 exp(const Vector3& phi) {
    const Scalar theta2 = phi.squaredNorm();
    const Scalar theta = std::sqrt(theta2);
    Scalar w;
    Scalar k;  // sin(theta/2) / theta
    if (theta < kSmallAngle) {
      w = Scalar(1) - theta2 / Scalar(8);
      k = Scalar(0.5) - theta2 / Scalar(48);
    } else {
      w = std::cos(theta / Scalar(2));
      k = std::sin(theta / Scalar(2)) / theta;
    }
    SO3 out;
    out.q_ = Quaternion(w, k * phi.x(), k * phi.y(), k * phi.z()).normalized();
    return out;
  }

  /// Logarithm: the rotation vector phi with |phi| in [0, pi]. Stable near 0
  /// and near pi (atan2 on the quaternion, never acos).
  [[nodiscard]] Vector3 log() const {
    Quaternion q = q_;
    if (q.w() < Scalar(0)) q.coeffs() = -q.coeffs();  // pick the short way round
    const Vector3 v = q.vec();
    const Scalar n = v.norm();
    if (n < kSmallAngle) {
      // theta = 2 atan(n / w) ~ 2 n / w (1 - n^2 / (3 w^2))
      const Scalar w = q.w();
      return (Scalar(2) / w) * (Scalar(1) - n * n / (Scalar(3) * w * w)) * v;
    }
    const Scalar theta = Scalar(2) * std::atan2(n, q.w());
    return (theta / n) * v;
  }

  /// Inverse rotation.
  [[nodiscard]] SO3 inverse() const {
    SO3 out;
    out.q_ = q_.conjugate();
    return out;
  }

  /// Composition: (this * other) applies other first.
  SO3 operator*(const SO3& other) const {
    SO3 out;
    out.q_ = (q_ * other.q_).normalized();
    return out;
  }

  /// Rotates a point.
  Vector3 operator*(const Vector3& p) const { return q_ * p; }

  /// Rotation matrix.
  [[nodiscard]] Matrix3 matrix() const { return q_.toRotationMatrix(); }
  /// Unit quaternion (w >= 0 is not enforced).
  [[nodiscard]] const Quaternion& quaternion() const { return q_; }
  /// Adjoint of SO(3): the rotation matrix itself.
  [[nodiscard]] Matrix3 adjoint() const { return matrix(); }

  /// Rotation angle in [0, pi].
  [[nodiscard]] Scalar angle() const { return log().norm(); }

  /// Same rotation in another scalar type.
  template <typename Other>
  [[nodiscard]] SO3<Other> cast() const {
    return SO3<Other>(q_.template cast<Other>());
  }

  /// Right Jacobian Jr(phi): exp(phi + d) ~ exp(phi) exp(Jr(phi) d).
  static Matrix3 right_jacobian(const Vector3& phi) {
    const Scalar theta2 = phi.squaredNorm();
    const Scalar theta = std::sqrt(theta2);
    const Matrix3 K = hat(phi);
    Scalar a;  // (1 - cos t) / t^2
    Scalar b;  // (t - sin t) / t^3
    if (theta < kSmallAngle) {
      a = Scalar(0.5) - theta2 / Scalar(24);
      b = Scalar(1) / Scalar(6) - theta2 / Scalar(120);
    } else {
      const Scalar s = std::sin(theta / Scalar(2)) / theta;  // no cancellation, unlike 1 - cos
      a = Scalar(2) * s * s;
      b = (theta - std::sin(theta)) / (theta2 * theta);
    }
    return Matrix3::Identity() - a * K + b * K * K;
  }

  /// Inverse of the right Jacobian. Uses cot(theta/2), which stays finite at
  /// theta = pi (the form (1+cos)/(sin) divides 0 by 0 there).
  static Matrix3 right_jacobian_inverse(const Vector3& phi) {
    const Scalar theta2 = phi.squaredNorm();
    const Scalar theta = std::sqrt(theta2);
    const Matrix3 K = hat(phi);
    Scalar c;  // 1/t^2 - cot(t/2) / (2 t)
    if (theta < kSmallAngle) {
      c = Scalar(1) / Scalar(12) + theta2 / Scalar(720);
    } else {
      const Scalar half = theta / Scalar(2);
      c = Scalar(1) / theta2 - std::cos(half) / (Scalar(2) * theta * std::sin(half));
    }
    return Matrix3::Identity() + Scalar(0.5) * K + c * K * K;
  }

  /// Left Jacobian Jl(phi) = Jr(-phi); also the V matrix of the SE(3) exp.
  static Matrix3 left_jacobian(const Vector3& phi) { return right_jacobian(-phi); }
  /// Inverse of the left Jacobian.
  static Matrix3 left_jacobian_inverse(const Vector3& phi) {
    return right_jacobian_inverse(-phi);
  }

 private:
  Quaternion q_;
};

/// Double-precision rotation, the type every solver uses.
using SO3d = SO3<double>;
/// Single-precision rotation, for compact storage.
using SO3f = SO3<float>;

}  // namespace semlio
