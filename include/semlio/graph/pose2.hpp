#pragma once
/// \file
/// SE(2) pose for planar pose graphs (the 2D g2o benchmarks).
///
/// Same conventions as SE3d: `T_a_b` maps points from b into a, and the
/// perturbation used by the solver is on the right: T (+) [dt; dtheta] moves
/// the translation by R * dt and the heading by dtheta (first-order equal to
/// T * exp([dt; dtheta])).

#include <Eigen/Core>

#include <cmath>
#include <numbers>

namespace semlio {

/// Wraps an angle [rad] into (-pi, pi].
inline double wrap_angle_rad(double a_rad) {
  const double two_pi = 2.0 * std::numbers::pi;
  double r = std::remainder(a_rad, two_pi);  // in [-pi, pi]
  if (r <= -std::numbers::pi) r += two_pi;
  return r;
}

/// A planar rigid transform: p' = R(theta) p + t.
class Pose2 {
 public:
  /// Identity.
  Pose2() = default;
  /// From translation [m] and heading [rad].
  Pose2(const Eigen::Vector2d& t_m, double theta_rad) : t_(t_m), theta_(wrap_angle_rad(theta_rad)) {}
  /// From x, y [m] and heading [rad].
  Pose2(double x_m, double y_m, double theta_rad) : Pose2(Eigen::Vector2d(x_m, y_m), theta_rad) {}

  /// Translation [m].
  [[nodiscard]] const Eigen::Vector2d& translation() const { return t_; }
  /// Heading [rad] in (-pi, pi].
  [[nodiscard]] double theta() const { return theta_; }
  /// 2x2 rotation matrix.
  [[nodiscard]] Eigen::Matrix2d rotation() const {
    const double c = std::cos(theta_);
    const double s = std::sin(theta_);
    Eigen::Matrix2d R;
    R << c, -s, s, c;
    return R;
  }

  /// Composition: T_a_b * T_b_c = T_a_c.
  Pose2 operator*(const Pose2& other) const { return {rotation() * other.t_ + t_, theta_ + other.theta_}; }
  /// Applies the transform to a point.
  Eigen::Vector2d operator*(const Eigen::Vector2d& p) const { return rotation() * p + t_; }
  /// Inverse transform.
  [[nodiscard]] Pose2 inverse() const { return {-(rotation().transpose() * t_), -theta_}; }

 private:
  Eigen::Vector2d t_ = Eigen::Vector2d::Zero();
  double theta_ = 0.0;
};

}  // namespace semlio
