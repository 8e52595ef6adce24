#pragma once
/// \file
/// SemanticWeighted<R>: the semantic consistency weight of eq. 10-12 on any
/// residual. w = (number of kept matches whose label equals the feature's) / N
/// (METHOD.md); the weighted residual is w * r, so a least-squares solver's
/// cost holds w^2 ||r||^2 (eq. 13 written with the square every LOAM-family
/// solver uses). The Jacobian scales by the same constant w.

#include <cstddef>

#include <semlio/concepts.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>

namespace semlio {

/// Eq. 10-12: fraction of the matches whose label equals `label`; 0 without matches.
inline double semantic_weight(Class label, const MatchedPoints& matches) {
  if (matches.count <= 0) return 0.0;
  int same = 0;
  for (int k = 0; k < matches.count; ++k) {
    if (matches.labels[static_cast<std::size_t>(k)] == label) ++same;  // eq. 10
  }
  return static_cast<double>(same) / static_cast<double>(matches.count);
}

/// Residual R with r and J multiplied by the semantic weight (eq. 11-12).
/// A term with weight 0 stays valid (it is a residual that counts for nothing).
/// A PreparedResidual when R is one (the weight needs only the labels).
template <Residual R>
class SemanticWeighted {
 public:
  static constexpr int kDim = R::kDim;
  /// R's fit of a match set (an empty type when R has none).
  using Model = detail::ModelOf<R>;

  /// Wraps inner.
  explicit SemanticWeighted(R inner = R{}) : inner_(inner) {}

  /// inner's term with r <- w r and J <- w J.
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    return weighted(feature, matches, inner_.evaluate(feature, matches, T_map_scan));
  }

  /// inner's fit of the matches.
  [[nodiscard]] Model prepare(const MatchedPoints& matches) const
    requires PreparedResidual<R>
  {
    return inner_.prepare(matches);
  }

  /// As evaluate(feature, matches, T_map_scan) with model = prepare(matches).
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const Model& model, const SE3d& T_map_scan) const
    requires PreparedResidual<R>
  {
    return weighted(feature, matches, inner_.evaluate(feature, matches, model, T_map_scan));
  }

  /// Forwards a robust inner residual's widening (residual/robust.hpp).
  bool set_min_scale_m(double s)
    requires requires(R& r) { r.set_min_scale_m(s); }
  {
    return inner_.set_min_scale_m(s);
  }

  /// The wrapped residual.
  [[nodiscard]] const R& inner() const noexcept { return inner_; }

 private:
  static ResidualTerm<kDim> weighted(const FeaturePoint& feature, const MatchedPoints& matches,
                                     ResidualTerm<kDim> term) {
    if (!term.valid) return term;
    const double w = semantic_weight(feature.label, matches);
    term.r *= w;
    term.J_r_xi *= w;
    return term;
  }

  R inner_;
};

static_assert(Residual<SemanticWeighted<PointToPlane>>);
static_assert(Residual<SemanticWeighted<PointToLine>>);
static_assert(PreparedResidual<SemanticWeighted<PointToPlane>>);
static_assert(PreparedResidual<SemanticWeighted<PointToLine>>);

}  // namespace semlio
