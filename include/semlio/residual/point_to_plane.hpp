#pragma once
/// \file
/// PointToPlane: signed distance of the transformed surface feature to the
/// plane through its matched map points (eq. 9; |r| = d_s).
///
/// Plane: by default the least-squares plane through all kept matches (METHOD:
/// eq. 9 with three points is the special case): centroid c and the
/// covariance's smallest eigenvector n (eq. 3-6). Option `three_point`: eq. 9
/// literally, the plane through the first non-collinear triple of the matches
/// in their chosen order.
///
/// Validity (eigenvalues l0 <= l1 <= l2 of the matches' covariance, [m^2]):
///  - spread:    l1 > min_spread_m2 and l1 >= min_spread_ratio * l2 -- the
///               points span two directions (not all in one spot, not on a line);
///  - planarity: l0 <= max_planarity_ratio * l1 -- the thickness across the
///               plane is small against its width (0.1: rms thickness below
///               ~0.32x the rms width), rejecting vegetation-like clutter.
/// A failed check (or fewer than 3 matches) gives an invalid term, never NaN.

#include <Eigen/Core>

#include <cmath>
#include <cstddef>

#include <semlio/concepts.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/residual/point_jacobian.hpp>

namespace semlio {

/// Settings of PointToPlane.
struct PointToPlaneConfig {
  bool three_point = false;          ///< eq. 9 form (first non-collinear triple) instead of the LS plane
  double max_planarity_ratio = 0.1;  ///< l0 / l1 upper bound
  double min_spread_ratio = 0.01;    ///< l1 / l2 lower bound (not collinear)
  double min_spread_m2 = 1e-8;       ///< l1 lower bound [m^2] (not all in one spot)
  double min_triangle_sine = 0.1;    ///< three_point: |(u-v)x(u-w)| >= this * |u-v| |u-w|
};

/// Point-to-plane residual, kDim = 1. Stateless apart from its settings.
class PointToPlane {
 public:
  static constexpr int kDim = 1;
  using Config = PointToPlaneConfig;

  /// With the given settings.
  explicit PointToPlane(const Config& config = {}) : config_(config) {}

  /// The plane of one match set (PreparedResidual): reusable at any pose
  /// while the matches stay the same.
  struct Model {
    Eigen::Vector3d n = Eigen::Vector3d::UnitZ();  ///< unit normal
    Eigen::Vector3d c = Eigen::Vector3d::Zero();   ///< point on the plane [m, map frame]
    bool valid = false;                            ///< false: the checks failed, no residual
  };

  /// The plane through the matches (the checks of the file comment).
  [[nodiscard]] Model prepare(const MatchedPoints& matches) const {
    Model model;
    model.valid = plane(matches, model.n, model.c);
    return model;
  }

  /// r = n . (T p_scan - c); J = n^T [R, -R hat(p_scan)] (right perturbation).
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    return evaluate(feature, matches, prepare(matches), T_map_scan);
  }

  /// As evaluate(feature, matches, T_map_scan) with the plane already fitted
  /// (model = prepare(matches)).
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& /*matches*/,
                                            const Model& model, const SE3d& T_map_scan) const {
    ResidualTerm<kDim> term;
    if (!model.valid) return term;
    const Eigen::Matrix3d R = T_map_scan.rotation();
    const Eigen::Vector3d p_map = R * feature.p_scan + T_map_scan.translation();
    term.r(0) = model.n.dot(p_map - model.c);
    term.J_r_xi = model.n.transpose() * detail::moved_point_jacobian(R, feature.p_scan);
    term.valid = term.r.allFinite() && term.J_r_xi.allFinite();
    if (!term.valid) term = ResidualTerm<kDim>{};
    return term;
  }

  /// The plane (unit normal n, point c) of the matches; false when invalid.
  bool plane(const MatchedPoints& m, Eigen::Vector3d& n, Eigen::Vector3d& c) const {
    if (m.count < 3) return false;
    // fit_local_shape's normal, eigenvalues and mean, without the other vectors.
    const LocalAxisShape shape = fit_local_shape_axis(
        static_cast<std::size_t>(m.count), [&](std::size_t i) -> const Eigen::Vector3d& { return m.p_map[i]; },
        EigenEnd::kSmallest);
    if (!shape.valid) return false;
    const Eigen::Vector3d& l = shape.eigenvalues;
    if (!(l(1) > config_.min_spread_m2 && l(1) >= config_.min_spread_ratio * l(2))) return false;
    if (!(l(0) <= config_.max_planarity_ratio * l(1))) return false;
    if (!config_.three_point) {
      n = shape.axis;
      c = shape.mean;
      return true;
    }
    // Eq. 9: the first non-collinear triple (u, v, w) in the matches' order.
    const auto count = static_cast<std::size_t>(m.count);
    for (std::size_t a = 0; a < count; ++a) {
      for (std::size_t b = a + 1; b < count; ++b) {
        for (std::size_t k = b + 1; k < count; ++k) {
          const Eigen::Vector3d uv = m.p_map[a] - m.p_map[b];
          const Eigen::Vector3d uw = m.p_map[a] - m.p_map[k];
          const Eigen::Vector3d cross = uv.cross(uw);
          const double area = cross.norm();
          if (area > 0.0 && area >= config_.min_triangle_sine * uv.norm() * uw.norm()) {
            n = cross / area;
            c = m.p_map[a];
            return true;
          }
        }
      }
    }
    return false;
  }

  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
};

static_assert(PreparedResidual<PointToPlane>);

}  // namespace semlio
