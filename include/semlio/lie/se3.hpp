#pragma once
/// \file
/// SE(3), rigid-body motions, as an owning value type.
///
/// THE convention of semlio, stated once:
/// - `T_a_b` maps points from frame b into frame a: p_a = T_a_b * p_b, so
///   T_a_c = T_a_b * T_b_c.
/// - Tangent vectors are xi = [rho; phi] (translation part first, then
///   rotation), 6x1.
/// - Perturbations are on the right: T (+) xi = T * exp(xi). Every Jacobian
///   J_out_xi in semlio is with respect to this right perturbation.
/// - exp([rho; phi]) = (exp(phi), Jl(phi) * rho).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

#include <semlio/lie/so3.hpp>

namespace semlio {

/// A rigid-body transform: rotation then translation, p' = R p + t.
template <typename Scalar>
class SE3 {
 public:
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Vector6 = Eigen::Matrix<Scalar, 6, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;
  using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;
  using Quaternion = Eigen::Quaternion<Scalar>;

  /// Identity transform.
  SE3() : t_(Vector3::Zero()) {}
  /// From rotation and translation.
  SE3(const SO3<Scalar>& R, const Vector3& t) : R_(R), t_(t) {}
  /// From a quaternion (normalised) and translation.
  SE3(const Quaternion& q, const Vector3& t) : R_(q), t_(t) {}
  /// From a homogeneous 4x4 matrix; the rotation block is re-orthonormalised
  /// through the quaternion (callers validate orthonormality first).
  explicit SE3(const Matrix4& T) : R_(Matrix3(T.template topLeftCorner<3, 3>())), t_(T.template topRightCorner<3, 1>()) {}

  /// Exponential map of xi = [rho; phi].
  static SE3 exp(const Vector6& xi) {
    const Vector3 rho = xi.template head<3>();
    const Vector3 phi = xi.template tail<3>();
    return SE3(SO3<Scalar>::exp(phi), SO3<Scalar>::left_jacobian(phi) * rho);
  }

  /// Logarithm: xi = [rho; phi] with |phi| in [0, pi].
  [[nodiscard]] Vector6 log() const {
    const Vector3 phi = R_.log();
    Vector6 xi;
    xi.template head<3>() = SO3<Scalar>::left_jacobian_inverse(phi) * t_;
    xi.template tail<3>() = phi;
    return xi;
  }

  /// Inverse transform.
  [[nodiscard]] SE3 inverse() const {
    const SO3<Scalar> Rinv = R_.inverse();
    return SE3(Rinv, -(Rinv * t_));
  }

  /// Composition: (T_a_b * T_b_c) = T_a_c.
  SE3 operator*(const SE3& other) const { return SE3(R_ * other.R_, R_ * other.t_ + t_); }

  /// Applies the transform to a point.
  Vector3 operator*(const Vector3& p) const { return R_ * p + t_; }

  /// Rotation part.
  [[nodiscard]] const SO3<Scalar>& so3() const { return R_; }
  /// Rotation matrix.
  [[nodiscard]] Matrix3 rotation() const { return R_.matrix(); }
  /// Translation part.
  [[nodiscard]] const Vector3& translation() const { return t_; }
  /// Mutable translation part.
  Vector3& translation() { return t_; }

  /// Homogeneous 4x4 matrix.
  [[nodiscard]] Matrix4 matrix() const {
    Matrix4 T = Matrix4::Identity();
    T.template topLeftCorner<3, 3>() = R_.matrix();
    T.template topRightCorner<3, 1>() = t_;
    return T;
  }

  /// Adjoint for [rho; phi] ordering: Ad = [[R, t^ R], [0, R]], so that
  /// T * exp(xi) = exp(Ad * xi) * T.
  [[nodiscard]] Matrix6 adjoint() const {
    const Matrix3 R = R_.matrix();
    Matrix6 Ad = Matrix6::Zero();
    Ad.template topLeftCorner<3, 3>() = R;
    Ad.template topRightCorner<3, 3>() = hat(t_) * R;
    Ad.template bottomRightCorner<3, 3>() = R;
    return Ad;
  }

  /// Same transform in another scalar type.
  template <typename Other>
  [[nodiscard]] SE3<Other> cast() const {
    return SE3<Other>(R_.template cast<Other>(), t_.template cast<Other>());
  }

  /// Right Jacobian of SE(3): exp(xi + d) ~ exp(xi) exp(Jr(xi) d).
  static Matrix6 right_jacobian(const Vector6& xi) {
    const Vector3 rho = xi.template head<3>();
    const Vector3 phi = xi.template tail<3>();
    const Matrix3 Jr = SO3<Scalar>::right_jacobian(phi);
    Matrix6 J = Matrix6::Zero();
    J.template topLeftCorner<3, 3>() = Jr;
    J.template bottomRightCorner<3, 3>() = Jr;
    J.template topRightCorner<3, 3>() = q_block(-rho, -phi);  // Q_r(xi) = Q_l(-xi)
    return J;
  }

  /// Inverse of the right Jacobian of SE(3).
  static Matrix6 right_jacobian_inverse(const Vector6& xi) {
    const Vector3 rho = xi.template head<3>();
    const Vector3 phi = xi.template tail<3>();
    const Matrix3 Jr_inv = SO3<Scalar>::right_jacobian_inverse(phi);
    Matrix6 J = Matrix6::Zero();
    J.template topLeftCorner<3, 3>() = Jr_inv;
    J.template bottomRightCorner<3, 3>() = Jr_inv;
    J.template topRightCorner<3, 3>() = -Jr_inv * q_block(-rho, -phi) * Jr_inv;
    return J;
  }

  /// Left Jacobian of SE(3): Jl(xi) = Jr(-xi).
  static Matrix6 left_jacobian(const Vector6& xi) { return right_jacobian(-xi); }

 private:
  // Barfoot's Q(rho, phi), the off-diagonal block of the SE(3) left Jacobian
  // ("State Estimation for Robotics", eq. 7.86), with Taylor coefficients
  // below kSmallAngle.
  static Matrix3 q_block(const Vector3& rho, const Vector3& phi) {
    const Scalar theta2 = phi.squaredNorm();
    const Scalar theta = std::sqrt(theta2);
    const Matrix3 P = hat(phi);
    const Matrix3 Rh = hat(rho);
    Scalar c1;  // (t - sin t) / t^3
    Scalar c2;  // (t^2 + 2 cos t - 2) / (2 t^4)
    Scalar c3;  // (2 t - 3 sin t + t cos t) / (2 t^5)
    // The closed forms cancel catastrophically (c2 loses ~eps/t^4), so the
    // series (through t^4) is used up to a larger, precision-dependent angle.
    const Scalar series_below = sizeof(Scalar) <= 4 ? Scalar(0.3) : Scalar(0.02);
    if (theta < series_below) {
      const Scalar theta4 = theta2 * theta2;
      c1 = Scalar(1) / Scalar(6) - theta2 / Scalar(120) + theta4 / Scalar(5040);
      c2 = Scalar(1) / Scalar(24) - theta2 / Scalar(720) + theta4 / Scalar(40320);
      c3 = Scalar(1) / Scalar(120) - theta2 / Scalar(2520) + theta4 / Scalar(120960);
    } else {
      const Scalar s = std::sin(theta);
      const Scalar c = std::cos(theta);
      c1 = (theta - s) / (theta2 * theta);
      c2 = (theta2 + Scalar(2) * c - Scalar(2)) / (Scalar(2) * theta2 * theta2);
      c3 = (Scalar(2) * theta - Scalar(3) * s + theta * c) / (Scalar(2) * theta2 * theta2 * theta);
    }
    const Matrix3 PR = P * Rh;
    const Matrix3 RP = Rh * P;
    const Matrix3 PRP = PR * P;
    return Scalar(0.5) * Rh + c1 * (PR + RP + PRP) + c2 * (P * PR + RP * P - Scalar(3) * PRP) +
           c3 * (PRP * P + P * PRP);
  }

  SO3<Scalar> R_;
  Vector3 t_;
};

/// Double-precision transform, the type every solver and reader uses.
using SE3d = SE3<double>;
/// Single-precision transform, for compact storage.
using SE3f = SE3<float>;

}  // namespace semlio
