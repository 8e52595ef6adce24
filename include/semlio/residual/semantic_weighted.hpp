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
template <Residual R>
class SemanticWeighted {
 public:
  static constexpr int kDim = R::kDim;

  /// Wraps inner.
  explicit SemanticWeighted(R inner = R{}) : inner_(inner) {}

  /// inner's term with r <- w r and J <- w J.
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    ResidualTerm<kDim> term = inner_.evaluate(feature, matches, T_map_scan);
    if (!term.valid) return term;
    const double w = semantic_weight(feature.label, matches);
    term.r *= w;
    term.J_r_xi *= w;
    return term;
  }

  /// The wrapped residual.
  [[nodiscard]] const R& inner() const noexcept { return inner_; }

 private:
  R inner_;
};

static_assert(Residual<SemanticWeighted<PointToPlane>>);
static_assert(Residual<SemanticWeighted<PointToLine>>);

}  // namespace semlio
