#pragma once
/// \file
/// Robust<Kernel, R>: a robust kernel on any residual as iteratively
/// reweighted least squares. With s = ||r||^2 of the current (possibly
/// semantically weighted) residual, the kernel rho(s) is replaced near the
/// current estimate by w * s with w = rho'(s); the term's `weight` is
/// multiplied by w, r and J are left unchanged.

#include <cmath>
#include <concepts>

#include <semlio/concepts.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>

namespace semlio {

/// A robust kernel: IRLS weight rho'(s) for squared residual s [m^2], in (0, 1].
template <typename K>
concept RobustKernel = requires(const K k, double s) {
  { k.weight(s) } -> std::convertible_to<double>;
};

/// Huber: rho(s) = s for sqrt(s) <= delta, 2 delta sqrt(s) - delta^2 beyond.
struct Huber {
  double delta_m = 0.1;  ///< quadratic-to-linear switch [m]
  /// rho'(s): 1 inside delta, delta / sqrt(s) beyond.
  [[nodiscard]] double weight(double s) const {
    const double a = std::sqrt(s);
    return a <= delta_m ? 1.0 : delta_m / a;
  }
};

/// Cauchy (Lorentzian): rho(s) = c^2 log(1 + s / c^2).
struct Cauchy {
  double c_m = 0.1;  ///< scale [m]
  /// rho'(s) = 1 / (1 + s / c^2).
  [[nodiscard]] double weight(double s) const { return 1.0 / (1.0 + s / (c_m * c_m)); }
};

static_assert(RobustKernel<Huber>);
static_assert(RobustKernel<Cauchy>);

/// Residual R with the IRLS weight of Kernel applied to its squared cost.
template <RobustKernel Kernel, Residual R>
class Robust {
 public:
  static constexpr int kDim = R::kDim;

  /// Wraps inner with kernel.
  explicit Robust(Kernel kernel = Kernel{}, R inner = R{}) : kernel_(kernel), inner_(inner) {}

  /// R's fit of a match set (an empty type when R has none).
  using Model = detail::ModelOf<R>;

  /// inner's term with weight <- weight * rho'(||r||^2).
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    return reweighted(inner_.evaluate(feature, matches, T_map_scan));
  }

  /// inner's fit of the matches (when R is a PreparedResidual).
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
    return reweighted(inner_.evaluate(feature, matches, model, T_map_scan));
  }

  /// The kernel.
  [[nodiscard]] const Kernel& kernel() const noexcept { return kernel_; }
  /// The wrapped residual.
  [[nodiscard]] const R& inner() const noexcept { return inner_; }

 private:
  ResidualTerm<kDim> reweighted(ResidualTerm<kDim> term) const {
    if (term.valid) term.weight *= kernel_.weight(term.r.squaredNorm());
    return term;
  }

  Kernel kernel_;
  R inner_;
};

static_assert(Residual<Robust<Huber, PointToPlane>>);
static_assert(Residual<Robust<Cauchy, PointToLine>>);
static_assert(PreparedResidual<Robust<Huber, PointToPlane>>);

}  // namespace semlio
