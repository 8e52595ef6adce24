#pragma once
/// \file
/// Hand-written Gauss-Newton (optionally Levenberg-Marquardt damped) on SE(3)
/// with right perturbation, re-association between iterations and
/// degeneracy-aware solution remapping (Zhang, Kaess, Singh, ICRA 2016 — the
/// scheme LOAM and LIO-SAM use). Minimises eq. 13 of the paper in its squared
/// form (METHOD.md: every LOAM-family solver squares).

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <concepts>

#include <semlio/lie/se3.hpp>
#include <semlio/solve/normal_equations.hpp>

namespace semlio {

/// A least-squares problem over one pose T (e.g. T_map_scan). `linearize`
/// fills the normal equations at T for the current correspondences.
template <typename P>
concept LeastSquaresProblem = requires(const P& p, const SE3d& T, NormalEquations& eq) {
  { p.linearize(T, eq) } -> std::same_as<void>;
};

/// A problem that can refresh its correspondences at a new pose estimate.
template <typename P>
concept ReassociatingProblem = LeastSquaresProblem<P> && requires(P& p, const SE3d& T) {
  { p.associate(T) } -> std::same_as<void>;
};

/// Settings of gauss_newton(); the defaults follow LIO-SAM's scan-to-map solver.
struct GaussNewtonConfig {
  int max_iterations = 30;                 ///< hard cap on iterations
  int reassociate_every = 1;               ///< re-associate every n-th iteration (1 = every)
  bool levenberg_marquardt = false;        ///< damp with lambda * diag(H), accept/reject steps
  double lm_initial_lambda = 1e-4;         ///< initial LM damping (relative to diag(H))
  double translation_tolerance_m = 5e-4;    ///< 0.05 cm, as LIO-SAM; converged when the step is below both tolerances
  double rotation_tolerance_rad = 8.726646e-4;   ///< 0.05 deg, as LIO-SAM
  double degeneracy_threshold = 100.0;     ///< eigenvalues of H below this are degenerate directions
  bool remap_degenerate = true;            ///< project steps away from degenerate directions
  std::size_t min_residuals = 10;          ///< fewer residuals: status kTooFewResiduals, pose unchanged
};

/// Outcome of a solve.
enum class SolveStatus {
  kConverged,         ///< step below tolerance
  kMaxIterations,     ///< stopped at the iteration cap; pose is the last accepted estimate
  kTooFewResiduals,   ///< not enough residuals to constrain 6 DoF; pose unchanged
  kNumericalFailure,  ///< non-finite system; pose unchanged
};

/// Human-readable name of a status.
constexpr const char* to_string(SolveStatus s) noexcept {
  switch (s) {
    case SolveStatus::kConverged: return "converged";
    case SolveStatus::kMaxIterations: return "max_iterations";
    case SolveStatus::kTooFewResiduals: return "too_few_residuals";
    case SolveStatus::kNumericalFailure: return "numerical_failure";
  }
  return "unknown";
}

/// What gauss_newton() did.
struct SolveReport {
  SolveStatus status = SolveStatus::kTooFewResiduals;
  int iterations = 0;                       ///< linear solves performed
  double initial_cost = 0.0;                ///< cost at the initial pose and first association
  double final_cost = 0.0;                  ///< cost at the final pose (last association)
  std::size_t num_residuals = 0;            ///< residuals in the final linearisation
  Eigen::Matrix<double, 6, 1> eigenvalues = Eigen::Matrix<double, 6, 1>::Zero();  ///< of H at the first iteration, ascending
  Eigen::Matrix<double, 6, 6> eigenvectors = Eigen::Matrix<double, 6, 6>::Zero(); ///< columns match eigenvalues
  int degenerate_directions = 0;            ///< eigenvalues below the threshold
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();  ///< J^T W J at the final pose: an information matrix
  /// True when some direction of the pose was not constrained by the data.
  [[nodiscard]] bool degenerate() const noexcept { return degenerate_directions > 0; }
  /// True when the pose was updated from data (converged or hit the cap).
  [[nodiscard]] bool ok() const noexcept {
    return status == SolveStatus::kConverged || status == SolveStatus::kMaxIterations;
  }
};

namespace detail {

inline bool all_finite(const NormalEquations& eq) {
  return eq.H.allFinite() && eq.b.allFinite() && std::isfinite(eq.cost);
}

}  // namespace detail

/// Minimises the problem's cost over T (in place) by Gauss-Newton with right
/// perturbation T <- T * exp(dx). On kTooFewResiduals / kNumericalFailure T is
/// left unchanged; the result never contains NaN.
template <LeastSquaresProblem Problem>
SolveReport gauss_newton(Problem& problem, SE3d& T, const GaussNewtonConfig& config = {}) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  SolveReport report;
  const SE3d T_initial = T;
  NormalEquations eq;
  Matrix6 projection = Matrix6::Identity();
  double lambda = config.lm_initial_lambda;

  const auto fail = [&](SolveStatus status) {
    T = T_initial;
    report.status = status;
    return report;
  };

  for (int iteration = 0; iteration < config.max_iterations; ++iteration) {
    if constexpr (ReassociatingProblem<Problem>) {
      if (config.reassociate_every > 0 && iteration % config.reassociate_every == 0) {
        problem.associate(T);
      }
    }
    eq.reset();
    problem.linearize(T, eq);
    report.num_residuals = eq.num_residuals;
    if (eq.num_residuals < config.min_residuals) return fail(SolveStatus::kTooFewResiduals);
    if (!detail::all_finite(eq)) return fail(SolveStatus::kNumericalFailure);
    if (iteration == 0) {
      report.initial_cost = eq.cost;
      // Degeneracy analysis on the first system, as LOAM/LIO-SAM: directions
      // whose eigenvalue is below the threshold get no update at all.
      const Eigen::SelfAdjointEigenSolver<Matrix6> es(eq.H);
      report.eigenvalues = es.eigenvalues();
      report.eigenvectors = es.eigenvectors();
      Matrix6 V_f = es.eigenvectors().transpose();  // rows = eigenvectors
      Matrix6 V_u = V_f;
      for (int k = 0; k < 6; ++k) {
        if (report.eigenvalues[k] < config.degeneracy_threshold) {
          ++report.degenerate_directions;
          V_u.row(k).setZero();
        }
      }
      if (config.remap_degenerate && report.degenerate_directions > 0) {
        projection = V_f.transpose() * V_u;  // V_f is orthonormal: V_f^-1 = V_f^T
      }
    }
    report.final_cost = eq.cost;
    report.hessian = eq.H;

    Matrix6 A = eq.H;
    if (config.levenberg_marquardt) A.diagonal() += lambda * eq.H.diagonal();
    // LDLT on the (possibly singular) system; remapping removes the
    // unconstrained directions of the step afterwards.
    const Eigen::LDLT<Matrix6> ldlt(A);
    Vector6 dx = ldlt.solve(-eq.b);
    if (!dx.allFinite()) {
      // Singular system: fall back to the pseudo-inverse through eigenvectors.
      const Eigen::SelfAdjointEigenSolver<Matrix6> es(A);
      Vector6 inv = Vector6::Zero();
      const double floor = 1e-12 * std::max(1.0, es.eigenvalues().cwiseAbs().maxCoeff());
      for (int k = 0; k < 6; ++k) {
        if (es.eigenvalues()[k] > floor) inv[k] = 1.0 / es.eigenvalues()[k];
      }
      dx = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose() * (-eq.b);
    }
    dx = projection * dx;
    report.iterations = iteration + 1;
    if (!dx.allFinite()) return fail(SolveStatus::kNumericalFailure);

    const SE3d T_candidate = T * SE3d::exp(dx);
    if (config.levenberg_marquardt) {
      NormalEquations trial;
      problem.linearize(T_candidate, trial);
      if (trial.num_residuals >= config.min_residuals && detail::all_finite(trial) &&
          trial.cost <= eq.cost) {
        T = T_candidate;
        lambda = std::max(lambda * 0.3, 1e-9);
      } else {
        lambda = std::min(lambda * 10.0, 1e6);
        continue;  // rejected: retry with more damping
      }
    } else {
      T = T_candidate;
    }

    if (dx.head<3>().norm() < config.translation_tolerance_m &&
        dx.tail<3>().norm() < config.rotation_tolerance_rad) {
      eq.reset();
      problem.linearize(T, eq);
      if (eq.num_residuals >= config.min_residuals && detail::all_finite(eq)) {
        report.final_cost = eq.cost;
        report.hessian = eq.H;
        report.num_residuals = eq.num_residuals;
      }
      report.status = SolveStatus::kConverged;
      return report;
    }
  }
  report.status = SolveStatus::kMaxIterations;
  return report;
}

}  // namespace semlio
