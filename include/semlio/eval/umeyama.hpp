#pragma once
/// \file
/// Least-squares alignment of two point sets (Umeyama 1991): the rotation,
/// translation and optionally scale that best map estimated positions onto
/// ground-truth positions. Used by the ATE (eval/ate.hpp).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::eval {

/// Which transform may be fitted before errors are measured.
enum class Alignment {
  kSE3,   ///< rotation + translation (the default of the paper's ATE)
  kSim3,  ///< rotation + translation + one global scale (monocular-style)
  kNone,  ///< no alignment: both trajectories are taken to be in the same frame
};

/// What the alignment could determine; every status still carries a valid
/// least-squares transform (never NaN).
enum class AlignmentStatus {
  kOk,                    ///< unique optimum
  kRotationUndetermined,  ///< fewer than 3 distinct or collinear points: rotation about their line is free
  kScaleUndetermined,     ///< Sim3 requested but the estimate has no spread: scale 1 used
};

/// Human-readable name of an alignment ("se3", "sim3", "none").
inline const char* to_string(Alignment a) noexcept {
  switch (a) {
    case Alignment::kSE3: return "se3";
    case Alignment::kSim3: return "sim3";
    case Alignment::kNone: return "none";
  }
  return "?";
}

/// Human-readable name of an alignment status.
inline const char* to_string(AlignmentStatus s) noexcept {
  switch (s) {
    case AlignmentStatus::kOk: return "ok";
    case AlignmentStatus::kRotationUndetermined: return "rotation_undetermined";
    case AlignmentStatus::kScaleUndetermined: return "scale_undetermined";
  }
  return "?";
}

/// A fitted similarity p_gt ~ scale * R * p_est + t.
struct AlignmentResult {
  SE3d T_gt_est;         ///< rotation R and translation t [m], estimate frame into ground-truth frame
  double scale = 1.0;    ///< global scale (1 unless Sim3)
  AlignmentStatus status = AlignmentStatus::kOk;  ///< what the data determined

  /// Maps an estimated position into the ground-truth frame [m].
  [[nodiscard]] Eigen::Vector3d apply(const Eigen::Vector3d& p_est) const {
    return scale * (T_gt_est.so3() * p_est) + T_gt_est.translation();
  }
  /// Maps an estimated pose into the ground-truth frame (rotation by R,
  /// position by apply()).
  [[nodiscard]] SE3d apply(const SE3d& T_est) const {
    return SE3d(T_gt_est.so3() * T_est.so3(), apply(T_est.translation()));
  }
};

/// Relative singular value below which a direction of the cross-covariance
/// counts as absent (collinear points).
inline constexpr double kUmeyamaRankTolerance = 1e-12;

/// Umeyama's closed form: minimises sum_i |p_gt[i] - (s R p_est[i] + t)|^2
/// over R (and s for kSim3); kNone returns the identity. Throws ValueError
/// when the sets differ in size or are empty. Thread-safe (pure function).
inline AlignmentResult umeyama(const std::vector<Eigen::Vector3d>& p_est, const std::vector<Eigen::Vector3d>& p_gt,
                               Alignment kind) {
  if (p_est.size() != p_gt.size()) {
    throw ValueError("umeyama: estimate has " + std::to_string(p_est.size()) + " points but ground truth has " +
                     std::to_string(p_gt.size()));
  }
  if (p_est.empty()) throw ValueError("umeyama: no points to align (0 given)");
  AlignmentResult out;
  if (kind == Alignment::kNone) return out;

  const auto n = static_cast<double>(p_est.size());
  Eigen::Vector3d mu_est = Eigen::Vector3d::Zero();
  Eigen::Vector3d mu_gt = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p_est.size(); ++i) {
    mu_est += p_est[i];
    mu_gt += p_gt[i];
  }
  mu_est /= n;
  mu_gt /= n;
  // Cross-covariance Sigma = 1/n sum (gt - mu_gt)(est - mu_est)^T and the
  // variance of the estimate (Umeyama's eq. 36-38).
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  double var_est = 0.0;
  for (std::size_t i = 0; i < p_est.size(); ++i) {
    const Eigen::Vector3d de = p_est[i] - mu_est;
    sigma += (p_gt[i] - mu_gt) * de.transpose();
    var_est += de.squaredNorm();
  }
  sigma /= n;
  var_est /= n;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  const Eigen::Vector3d d = svd.singularValues();  // descending
  Eigen::Vector3d s_diag(1.0, 1.0, 1.0);
  if (U.determinant() * V.determinant() < 0.0) s_diag.z() = -1.0;  // a rotation, never a reflection
  const Eigen::Matrix3d R = U * s_diag.asDiagonal() * V.transpose();

  if (!(d.y() > kUmeyamaRankTolerance * d.x())) out.status = AlignmentStatus::kRotationUndetermined;
  if (kind == Alignment::kSim3) {
    if (var_est > 0.0 && d.x() > 0.0) {
      out.scale = d.dot(s_diag) / var_est;
    } else {
      out.status = AlignmentStatus::kScaleUndetermined;
    }
  }
  const SO3d rot(R);
  out.T_gt_est = SE3d(rot, mu_gt - out.scale * (rot * mu_est));
  return out;
}

}  // namespace semlio::eval
