#pragma once
/// \file
/// Robust<Kernel, R>: a robust kernel on any residual as iteratively
/// reweighted least squares. With s = ||r||^2 of the current (possibly
/// semantically weighted) residual, the kernel rho(s) is replaced near the
/// current estimate by w * s with w = rho'(s); the term's `weight` is
/// multiplied by w, r and J are left unchanged.
///
/// Widening. A robust kernel needs a start near the answer: from a start
/// 1 m off (the zero-velocity first frame of a moving drive) the terms that
/// fix the offset are all "outliers" to a 0.1 m kernel, weighted ~0.01, and
/// the solve stays where it started (measured: the full preset with robust
/// corners, heavy traffic, 1.04 m short on its first frame for good).
/// set_min_scale_m(s) widens the kernel to scale max(own scale, s) -- the
/// weight of a squared residual q becomes rho'(q / f^2), f = max(1, s /
/// scale); s = infinity gives weight 1 (plain least squares). Odometry
/// widens it fully for the solve of a frame whose prediction has no motion
/// estimate yet (pipeline/odometry.hpp).

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
  { k.scale_m() } -> std::convertible_to<double>;
};

/// A residual whose robust kernel can be widened (file comment).
template <typename R>
concept WidenableResidual = requires(R r, double s) {
  { r.set_min_scale_m(s) } -> std::same_as<bool>;
};

/// Huber: rho(s) = s for sqrt(s) <= delta, 2 delta sqrt(s) - delta^2 beyond.
struct Huber {
  double delta_m = 0.1;  ///< quadratic-to-linear switch [m]
  /// The kernel's scale [m] (what Robust::set_min_scale_m compares with).
  [[nodiscard]] double scale_m() const { return delta_m; }
  /// rho'(s): 1 inside delta, delta / sqrt(s) beyond.
  [[nodiscard]] double weight(double s) const {
    const double a = std::sqrt(s);
    return a <= delta_m ? 1.0 : delta_m / a;
  }
};

/// Cauchy (Lorentzian): rho(s) = c^2 log(1 + s / c^2).
struct Cauchy {
  double c_m = 0.1;  ///< scale [m]
  /// The kernel's scale [m] (what Robust::set_min_scale_m compares with).
  [[nodiscard]] double scale_m() const { return c_m; }
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

  /// Widens the kernel to scale max(kernel scale, s) [m] (file comment);
  /// s = 0 restores it. Returns whether it is now wider than its own scale.
  bool set_min_scale_m(double s) noexcept {
    const double scale = kernel_.scale_m();
    const double f = scale > 0.0 && s > scale ? s / scale : 1.0;
    inverse_factor2_ = 1.0 / (f * f);  // 0 for s = infinity: weight rho'(0) = 1
    return f > 1.0;
  }

  /// The kernel.
  [[nodiscard]] const Kernel& kernel() const noexcept { return kernel_; }
  /// The wrapped residual.
  [[nodiscard]] const R& inner() const noexcept { return inner_; }

 private:
  ResidualTerm<kDim> reweighted(ResidualTerm<kDim> term) const {
    if (term.valid) term.weight *= kernel_.weight(term.r.squaredNorm() * inverse_factor2_);
    return term;
  }

  Kernel kernel_;
  R inner_;
  double inverse_factor2_ = 1.0;  // 1 / f^2 of set_min_scale_m (1: the kernel's own scale)
};

static_assert(Residual<Robust<Huber, PointToPlane>>);
static_assert(Residual<Robust<Cauchy, PointToLine>>);
static_assert(PreparedResidual<Robust<Huber, PointToPlane>>);
static_assert(WidenableResidual<Robust<Cauchy, PointToLine>>);

}  // namespace semlio
