#pragma once
/// \file
/// PointToLine: perpendicular offset of the transformed corner feature from
/// the line through its matched map points (eq. 8; |r| = d_e).
///
/// The residual is 2-D: the offset expressed in two unit axes (e1, e2)
/// orthogonal to the line direction u, so ||r|| = d_e and r is smooth at the
/// line (a scalar distance has a kink there, which Gauss-Newton handles badly).
///
/// Line: by default the PCA line of all kept matches (METHOD: eq. 8 with two
/// points is the special case): centroid c and the covariance's largest
/// eigenvector u (eq. 3-6). Option `two_point`: eq. 8 literally, the line
/// through the first two matches (the two nearest consistent ones).
///
/// Validity (eigenvalues l0 <= l1 <= l2 of the matches' covariance, [m^2]):
///  - extent:    l2 > min_extent_m2 (the points are not all in one spot);
///  - linearity: l1 <= max_linearity_ratio * l2 (LIO-SAM's edge test
///               l2 > 3 l1, i.e. ratio 1/3).
/// A failed check (or fewer than 2 matches) gives an invalid term, never NaN.

#include <Eigen/Core>

#include <cmath>
#include <cstddef>

#include <semlio/concepts.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/residual/point_jacobian.hpp>

namespace semlio {

/// Settings of PointToLine.
struct PointToLineConfig {
  bool two_point = false;                    ///< eq. 8 form (first two matches) instead of the PCA line
  double max_linearity_ratio = 1.0 / 3.0;    ///< l1 / l2 upper bound (LIO-SAM: 1/3)
  double min_extent_m2 = 1e-8;               ///< l2 lower bound [m^2]
};

/// Point-to-line residual, kDim = 2. Stateless apart from its settings.
class PointToLine {
 public:
  static constexpr int kDim = 2;
  using Config = PointToLineConfig;

  /// With the given settings.
  explicit PointToLine(const Config& config = {}) : config_(config) {}

  /// r = E^T (T p_scan - c), E = [e1 e2] orthonormal, orthogonal to the line
  /// direction; J = E^T [R, -R hat(p_scan)] (right perturbation).
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    ResidualTerm<kDim> term;
    Eigen::Vector3d u;
    Eigen::Vector3d c;
    if (!line(matches, u, c)) return term;
    // A fixed, deterministic basis of the plane orthogonal to u.
    const Eigen::Vector3d e1 = detail::line_orthogonal_unit(u);
    const Eigen::Vector3d e2 = u.cross(e1);
    Eigen::Matrix<double, 2, 3> Et;
    Et.row(0) = e1.transpose();
    Et.row(1) = e2.transpose();
    const Eigen::Matrix3d R = T_map_scan.rotation();
    const Eigen::Vector3d p_map = R * feature.p_scan + T_map_scan.translation();
    term.r = Et * (p_map - c);
    term.J_r_xi = Et * detail::moved_point_jacobian(R, feature.p_scan);
    term.valid = term.r.allFinite() && term.J_r_xi.allFinite();
    if (!term.valid) term = ResidualTerm<kDim>{};
    return term;
  }

  /// The line (unit direction u, point c) of the matches; false when invalid.
  bool line(const MatchedPoints& m, Eigen::Vector3d& u, Eigen::Vector3d& c) const {
    if (m.count < 2) return false;
    const LocalShape shape = fit_local_shape(static_cast<std::size_t>(m.count),
                                             [&](std::size_t i) -> const Eigen::Vector3d& { return m.p_map[i]; });
    if (!shape.valid) return false;
    const Eigen::Vector3d& l = shape.eigenvalues;
    if (!(l(2) > config_.min_extent_m2)) return false;
    if (!(l(1) <= config_.max_linearity_ratio * l(2))) return false;
    if (!config_.two_point) {
      u = shape.direction;
      c = shape.mean;
      return true;
    }
    // Eq. 8: the line through the first two matches.
    const Eigen::Vector3d d = m.p_map[0] - m.p_map[1];
    const double len = d.norm();
    if (!(len * len > config_.min_extent_m2)) return false;
    u = d / len;
    c = m.p_map[0];
    return true;
  }

  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
};

static_assert(Residual<PointToLine>);

}  // namespace semlio
