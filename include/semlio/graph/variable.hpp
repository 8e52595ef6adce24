#pragma once
/// \file
/// Node-variable abstraction of the pose graph: every variable type declares
/// its tangent dimension and its retraction (right perturbation). The solver
/// core only sees blocks of `kDim` columns, so further variable kinds
/// (velocity R^3, IMU bias R^6, see METHOD.md step 9) are added by writing a
/// `Variable<T>` specialisation plus the factors that touch them.

#include <Eigen/Core>

#include <concepts>

#include <semlio/graph/pose2.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// Traits of a graph variable: `kDim`, `Tangent` and `retract(x, dx)`.
template <typename T>
struct Variable;

/// SE(3) keyframe pose: tangent [rho; phi], retraction T * exp(dx).
template <>
struct Variable<SE3d> {
  static constexpr int kDim = 6;
  using Tangent = Eigen::Matrix<double, 6, 1>;
  /// Right retraction, semlio's convention (se3.hpp).
  static SE3d retract(const SE3d& x, const Tangent& dx) { return x * SE3d::exp(dx); }
};

/// SE(2) pose: tangent [dx; dy; dtheta], retraction (t + R dt, theta + dtheta).
template <>
struct Variable<Pose2> {
  static constexpr int kDim = 3;
  using Tangent = Eigen::Vector3d;
  /// Right retraction (first-order equal to T * exp(dx)).
  static Pose2 retract(const Pose2& x, const Tangent& dx) {
    return {x.translation() + x.rotation() * dx.head<2>(), x.theta() + dx[2]};
  }
};

/// Euclidean variable of dimension N (velocity, IMU bias): x + dx.
template <int N>
struct Variable<Eigen::Matrix<double, N, 1>> {
  static constexpr int kDim = N;
  using Tangent = Eigen::Matrix<double, N, 1>;
  /// Plain addition.
  static Eigen::Matrix<double, N, 1> retract(const Eigen::Matrix<double, N, 1>& x, const Tangent& dx) { return x + dx; }
};

/// A type usable as a graph node.
template <typename T>
concept GraphVariable = requires(const T& x, const typename Variable<T>::Tangent& dx) {
  { Variable<T>::kDim } -> std::convertible_to<int>;
  { Variable<T>::retract(x, dx) } -> std::convertible_to<T>;
};

static_assert(GraphVariable<SE3d>);
static_assert(GraphVariable<Pose2>);
static_assert(GraphVariable<Eigen::Vector3d>);

}  // namespace semlio
