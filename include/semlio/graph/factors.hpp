#pragma once
/// \file
/// Factors of the pose graph: prior, between (odometry) and loop closure.
/// Plain value types; the graph stores them in one vector (no heap
/// polymorphism). A factor's information matrix Omega weighs its error as
/// e^T Omega e (chi2, no 1/2); its ordering follows the tangent, translation
/// first ([rho; phi] in 3D, [x y theta] in 2D) — the same as g2o's files.

#include <Eigen/Core>

#include <cmath>
#include <cstdint>

#include <semlio/graph/variable.hpp>

namespace semlio {

/// Index of a node in a PoseGraph, dense from 0 in insertion order.
using NodeId = std::uint32_t;

/// What a factor measures.
enum class FactorKind {
  prior,    ///< absolute pose of node `to`
  between,  ///< odometry: T_from^-1 T_to
  loop,     ///< loop closure: a between with its own information, optionally robust
};

/// One factor on SE(3) or SE(2) poses.
template <GraphVariable Pose>
struct PoseFactor {
  static constexpr int kDim = Variable<Pose>::kDim;
  /// Information matrix (inverse covariance), kDim x kDim, symmetric PSD.
  using Information = Eigen::Matrix<double, kDim, kDim>;

  FactorKind kind = FactorKind::between;              ///< prior, between or loop
  NodeId from = 0;                                    ///< first node (unused for a prior)
  NodeId to = 0;                                      ///< second node (the node of a prior)
  Pose measured{};                                    ///< Z: T_from^-1 T_to, or the prior pose
  Information information = Information::Identity();  ///< Omega
  bool robust = false;                                ///< Huber-weighted (loop closures that may be outliers)
};

/// Huber cost rho(s) of a squared Mahalanobis error s = e^T Omega e, with the
/// threshold delta in units of sqrt(s): rho = s inside, 2 delta sqrt(s) - delta^2 outside.
inline double huber_cost(double s, double delta) {
  if (s <= delta * delta) return s;
  return 2.0 * delta * std::sqrt(s) - delta * delta;
}

/// IRLS weight d rho / d s of huber_cost.
inline double huber_weight(double s, double delta) {
  if (s <= delta * delta) return 1.0;
  return delta / std::sqrt(s);
}

}  // namespace semlio
