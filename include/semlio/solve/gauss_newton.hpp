#pragma once
/// \file
/// Hand-written Gauss-Newton (optionally Levenberg-Marquardt damped) on SE(3)
/// with right perturbation, re-association between iterations and
/// degeneracy-aware solution remapping (Zhang, Kaess, Singh, ICRA 2016 — the
/// scheme LOAM and LIO-SAM use). Minimises eq. 13 of the paper in its squared
/// form (METHOD.md: every LOAM-family solver squares).
///
/// When the degeneracy analysis runs. LOAM and LIO-SAM analyse only the
/// first system of a solve (iterCount == 0) and keep its projection for every
/// later iteration: the projection then cannot flip between iterations, and
/// at the usual start (an IMU or constant-velocity prediction a few cm off)
/// the first association is already the final one up to a few points. From a
/// far-off start (registration from identity, a zero-velocity first frame)
/// the first association is not representative: a direction can look
/// unconstrained only because the features that fix it are still outside the
/// association gate, and freezing it then keeps it at the start for the whole
/// solve. With `reanalyse_degeneracy` the analysis is therefore repeated on
/// the first system after every re-association, i.e. whenever the residual
/// set changes; register_scan() (RegistrationConfig) turns it on. The default
/// stays LOAM / LIO-SAM's (first iteration only) for starts near the answer
/// -- odometry's prediction, a loop candidate's guess -- because there the
/// freeze is a safeguard: re-analysed, a loop verification on the `aliased`
/// world slid along its weak direction into the look-alike block and
/// accepted 5 false loops, and the lidar-inertial front end on a short
/// simulated drive slipped along the road (tests/loop, tests/imu). A problem
/// that never re-associates is analysed once either way.
///
/// What counts as degenerate (the flag: SolveReport::degenerate_directions).
/// A direction is degenerate when the data constrain it weakly compared with
/// how they constrain the pose as a whole -- a property of the geometry,
/// not of how many residuals there are or of their weights. The test runs on
/// the normalised information H_n = S^-1/2 H S^-1/2, S = diag(s I3, s L^2 I3),
/// s the mean diagonal of H's translational block, L = `degeneracy_length_m`
/// (1 m): duplicating every residual or scaling every weight by c scales H
/// and S alike and leaves H_n (and the flag) unchanged. Degenerate: an
/// eigenvalue mu of H_n below `degeneracy_ratio`. What mu means: for a
/// translation, its information over the mean translational information
/// (point-to-plane terms have unit translational Jacobians, so this is the
/// share of the normals along it; 0..3); for a rotation, the mean squared
/// lever arm of the data about its axis in units of L^2 (0 for the roll of
/// a round tunnel, the yaw of a flat field, the rotation about a single
/// wall's normal; 20-300 m^2 on real KITTI). Because rotations come out
/// orders of magnitude above translations, the smallest eigenvalues are in
/// effect those of the translational Schur complement: how well a
/// translation is fixed once the rotation is solved. The rotational block is
/// deliberately not normalised by its own mean: in a street the roll's lever
/// arms (street width, wall height) are a few metres against tens of metres
/// for pitch and yaw, and per-block normalisation called the roll of 15 of
/// the 21 real snippet frames the weakest direction.
///
/// Why not LIO-SAM's absolute test (eigenvalue of H < 100) for the flag: H
/// grows with the number of residuals and with the squared semantic and
/// robust weights (<= 1), so the same geometry is flagged or not depending
/// on the preset: on the main job's simulated drive (scripts/demo.sh) it
/// flags `full` on 112 of 300 frames, `baseline` on 8. The absolute
/// threshold shapes only the *step* during the iterations (stage 1 of
/// gauss_newton(): LIO-SAM's remapping, or damping) as a safeguard against
/// directions with almost no information; it does not set the flag, and the
/// flag does not change a lidar-only solution (semlio_kitti without --imu).
/// Consumers of the flag: LIO reset and
/// information along flagged directions (pipeline/lidar_inertial.hpp), loop
/// rejection (loop/loop_verifier.hpp), the odometry status.
///
/// The threshold, from data: the smallest mu per solved frame (from each
/// frame's final SolveReport::hessian in semlio_kitti runs, labels from the
/// geometric segmenter on the real scans and predicted on the simulated
/// ones; scripts/degeneracy_table.sh prints the flag counts), `baseline` /
/// `full`:
///   real KITTI raw snippet_22 (21 frames)      0.54-0.72 / 0.29-0.60
///   real KITTI raw drive 0009 (50 frames)      0.29-0.57 / 0.15-0.43
///   simulated urban drive, demo (299 frames)   0.30-0.64 / 0.13-0.54
///   simulated highway, lidar only (149 frames) 0.09-0.17 / 0.03-0.10
/// with the weakest direction along the road (x) on all highway frames.
/// `full` (normal-consistency matches, semantic weights) sees less along
/// the road than `baseline` in every scene: that is the information, not
/// the scale, and no threshold makes the highway counts equal. 0.12 flags no
/// real or urban frame of either preset and the highway's along-road
/// direction on 149 of 149 (`full`) and 95 of 149 (`baseline`) frames;
/// 0.15 would flag 9 urban `full` frames and 1 real one. The synthetic cases
/// are tests/solve/test_degeneracy.cpp: corridor (axis), cylindrical tunnel
/// (axis and roll about it), single wall (its two in-plane translations and
/// the rotation about its normal), open field with ground only (x, y, yaw),
/// and the invariance to duplicated residuals and scaled weights. The test
/// judges the final system only (gauss_newton(): stage 2); set
/// degeneracy_ratio to 0 for LIO-SAM's absolute test alone (then also the flag).

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <string>

#include <semlio/core/error.hpp>
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
  int reassociate_every = 1;               ///< re-associate every n-th iteration (1 = every), and before declaring convergence
  bool levenberg_marquardt = false;        ///< damp with lambda * diag(H), accept/reject steps
  double lm_initial_lambda = 1e-4;         ///< initial LM damping (relative to diag(H))
  double translation_tolerance_m = 5e-4;    ///< 0.05 cm, as LIO-SAM; converged when the step is below both tolerances
  double rotation_tolerance_rad = 8.726646e-4;   ///< 0.05 deg, as LIO-SAM
  double degeneracy_threshold = 100.0;     ///< eigenvalues of H below this get no (or a damped) step during the iterations (LIO-SAM); the flag only when degeneracy_ratio is 0
  double degeneracy_ratio = 0.12;          ///< degenerate (the flag): eigenvalue of the normalised information below this (0 = LIO-SAM's absolute test instead); see file comment
  double degeneracy_length_m = 1.0;        ///< the normalised test weighs a rotation by the displacement it gives at this distance [m] (file comment)
  bool remap_degenerate = true;            ///< project steps away from degenerate directions
  bool reanalyse_degeneracy = false;       ///< repeat the analysis after every re-association (default: first iteration only, as LIO-SAM; registration from far off turns it on)
  bool reset_weak_directions = false;      ///< put the weak directions (weak_reset_ratio) back at the start (see gauss_newton())
  /// With reset_weak_directions: directions whose normalised eigenvalue is
  /// below max(this, degeneracy_ratio) are put back at the start. A start
  /// that is a measured prediction (the LIO's IMU) is better than a weak
  /// lidar solution well above the point where the flag calls a direction
  /// unconstrained; 0.25 is the share of the translational information below
  /// which the reset held directions before the flag was normalised (it
  /// keeps tests/imu/test_lidar_inertial.cpp's distorted-drive start-up
  /// at the constant-velocity prediction along the road).
  double weak_reset_ratio = 0.25;
  /// Damp degenerate directions instead of freezing them: their eigenvalues
  /// are raised to degeneracy_threshold (a prior of that information at the
  /// current pose), so a weak direction takes a shortened step instead of
  /// none (see degeneracy_projection()). Off: LIO-SAM's remapping. Not
  /// applied with reset_weak_directions: a start that is a measured
  /// prediction (the LIO's IMU) keeps degenerate directions at it too, as
  /// damping would let them drift from it by a shortened step every frame
  /// (simulated highway LIO with robust corners: 10.4 m ATE damped, 1.8 m
  /// frozen).
  bool damp_degenerate = false;
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
  /// Information of H along each column of `eigenvectors` (v^T H v) at the
  /// last analysis: with degeneracy_ratio > 0 (the final system) the columns
  /// follow the normalised eigenvalues; with the absolute test alone they
  /// are H's eigenvectors and these its eigenvalues, ascending.
  Eigen::Matrix<double, 6, 1> eigenvalues = Eigen::Matrix<double, 6, 1>::Zero();
  /// Orthonormal directions in the tangent [rho; phi]: the degenerate ones
  /// first, then the others, each group from weakest (normalised) up. Column
  /// 0 is the weakest direction of the pose.
  Eigen::Matrix<double, 6, 6> eigenvectors = Eigen::Matrix<double, 6, 6>::Zero();
  /// Eigenvalues mu of the normalised information (file comment: for a
  /// translation its share of the translational information, 0..3; for a
  /// rotation the mean squared lever arm about its axis over
  /// degeneracy_length_m^2; 0 for an unconstrained direction), in the order
  /// of the columns of `eigenvectors`.
  /// The flag compares them with degeneracy_ratio. With the absolute test
  /// alone: the normalised information along each column.
  Eigen::Matrix<double, 6, 1> normalized_eigenvalues = Eigen::Matrix<double, 6, 1>::Zero();
  int degenerate_directions = 0;            ///< degenerate directions at the last analysis (the first columns)
  int initial_degenerate_directions = 0;    ///< degenerate eigenvalues at the first analysis (the start's association)
  int analyses = 0;                         ///< degeneracy analyses performed
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

/// The scales S of the normalised information (file comment), as a vector
/// (s, s, s, s L^2, s L^2, s L^2): s the mean diagonal of H's translational
/// block, L = config.degeneracy_length_m. Without translational information
/// (s <= 0: no residual has a translational Jacobian) s is taken from the
/// rotational block, and 1 when that is empty too (H = 0).
inline Eigen::Matrix<double, 6, 1> information_scales(const Eigen::Matrix<double, 6, 6>& H,
                                                      const GaussNewtonConfig& config) {
  const double length2 = config.degeneracy_length_m * config.degeneracy_length_m;
  double t = H.diagonal().head<3>().mean();
  if (!(t > 0.0)) t = H.diagonal().tail<3>().mean() / length2;
  if (!(t > 0.0) || !std::isfinite(t)) t = 1.0;
  Eigen::Matrix<double, 6, 1> s;
  s << Eigen::Vector3d::Constant(t), Eigen::Vector3d::Constant(t * length2);
  return s;
}

/// Fills the report's columns from candidate directions `dirs` (tangent
/// coordinates, any scale, in report order) and their normalised
/// eigenvalues `mu`: Gram-Schmidt (twice, for round-off) makes the
/// directions orthonormal while the first k columns keep the span of the
/// first k directions (for a block-diagonal H they are orthogonal already);
/// `eigenvalues` gets v^T H v along each.
inline void fill_directions(const Eigen::Matrix<double, 6, 6>& H, const Eigen::Matrix<double, 6, 6>& dirs,
                            const Eigen::Matrix<double, 6, 1>& mu, SolveReport& report) {
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<double, 6, 1> v = dirs.col(k);
    for (int pass = 0; pass < 2; ++pass) {
      for (int j = 0; j < k; ++j) v -= report.eigenvectors.col(j).dot(v) * report.eigenvectors.col(j);
    }
    v.normalize();
    report.eigenvectors.col(k) = v;
    report.eigenvalues[k] = v.dot(H * v);
    report.normalized_eigenvalues[k] = mu[k];
  }
}

/// Degeneracy analysis of H: fills the report's eigenvalues, eigenvectors,
/// normalised eigenvalues and degenerate count, and returns the projection
/// (Zhang, Kaess, Singh 2016) that removes the degenerate directions from a
/// step (identity when none is degenerate or remapping is off). With
/// config.degeneracy_ratio > 0 the test is the normalised one (file
/// comment), else LIO-SAM's absolute test on H's eigenvalues.
inline Eigen::Matrix<double, 6, 6> degeneracy_projection(const Eigen::Matrix<double, 6, 6>& H,
                                                         const GaussNewtonConfig& config, SolveReport& report) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  ++report.analyses;
  const Vector6 scales = information_scales(H, config);
  const bool normalised = config.degeneracy_ratio > 0.0;
  // The eigen-decomposition the test runs on: of H_n = S^-1/2 H S^-1/2
  // (normalised) or of H (absolute).
  const Vector6 s_inv_sqrt = scales.cwiseSqrt().cwiseInverse();
  // (The absolute path decomposes H itself, as before: bit for bit the
  // steps LIO-SAM's test gave.)
  const Matrix6 Hn = s_inv_sqrt.asDiagonal() * H * s_inv_sqrt.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6> es(normalised ? Matrix6(0.5 * (Hn + Hn.transpose())) : H);
  const double limit = normalised ? config.degeneracy_ratio : config.degeneracy_threshold;
  // Report the degenerate directions first (each group ascending), so the
  // first degenerate_directions columns are exactly the degenerate ones.
  Matrix6 dirs = Matrix6::Zero();
  Vector6 values = Vector6::Zero();
  report.degenerate_directions = 0;
  int out = 0;
  for (const bool take_weak : {true, false}) {
    for (int k = 0; k < 6; ++k) {
      const double l = es.eigenvalues()[k];
      if ((l < limit) != take_weak) continue;
      // A direction u of H_n is the tangent direction S^-1/2 u (it reaches
      // the generalised Rayleigh quotient v^T H v / v^T S v = mu).
      dirs.col(out) = normalised ? Vector6(s_inv_sqrt.cwiseProduct(es.eigenvectors().col(k))) : Vector6(es.eigenvectors().col(k));
      values[out] = l;
      if (take_weak) ++report.degenerate_directions;
      ++out;
    }
  }
  if (normalised) {
    fill_directions(H, dirs, values, report);
  } else {
    // H's own eigenpairs, as LIO-SAM (bit for bit what the step uses).
    for (int k = 0; k < 6; ++k) {
      const Vector6 v = dirs.col(k);
      report.eigenvectors.col(k) = v;
      report.eigenvalues[k] = values[k];
      report.normalized_eigenvalues[k] = values[k] / v.dot(scales.cwiseProduct(v));
    }
  }
  if (!config.remap_degenerate || report.degenerate_directions == 0) return Matrix6::Identity();
  // Zhang et al.: dx <- V_f^-1 V_u dx, V_u = V_f with the degenerate rows
  // zeroed; with orthonormal columns the product is I - sum v v^T over them.
  Matrix6 P = Matrix6::Identity();
  for (int k = 0; k < report.degenerate_directions; ++k) {
    P -= report.eigenvectors.col(k) * report.eigenvectors.col(k).transpose();
  }
  return P;
}

/// With `damp_degenerate`: the information to add to H so that each
/// degenerate direction of the last analysis (report's first columns) has
/// eigenvalue max(l, degeneracy_threshold): sum (threshold - l) v v^T, zero
/// for directions weak only by the ratio test (above the threshold). The
/// step along such a direction is then -v.b / threshold instead of 0 (or of
/// -v.b / l, which is what makes an undamped weak direction wander): from a
/// far-off start (registration from identity) the direction moves, the next
/// association can find the features that constrain it, and the analysis
/// after it no longer calls it degenerate; a direction the data really do not
/// constrain has v.b ~ 0 and stays put.
inline Eigen::Matrix<double, 6, 6> degeneracy_damping(const GaussNewtonConfig& config, const SolveReport& report) {
  Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
  for (int k = 0; k < report.degenerate_directions; ++k) {
    const double add = config.degeneracy_threshold - std::max(report.eigenvalues[k], 0.0);
    if (add > 0.0) D += add * report.eigenvectors.col(k) * report.eigenvectors.col(k).transpose();
  }
  return D;
}

}  // namespace detail

namespace detail {

/// The Gauss-Newton iterations of gauss_newton(). With `locked` the step
/// projection is fixed to *locked (no analysis); otherwise the degeneracy is
/// analysed (with `config`'s tests) on the first system and after every
/// re-association. Accumulates into `report`; T may be left anywhere on
/// failure (the caller restores it).
template <LeastSquaresProblem Problem>
SolveStatus iterate(Problem& problem, SE3d& T, const GaussNewtonConfig& config, SolveReport& report,
                    const Eigen::Matrix<double, 6, 6>* locked) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  NormalEquations eq;
  Matrix6 projection = locked != nullptr ? *locked : Matrix6::Identity();
  Matrix6 damping = Matrix6::Zero();  // damp_degenerate: information added along degenerate directions
  double lambda = config.lm_initial_lambda;
  const bool first_run = report.analyses == 0 && locked == nullptr;
  const auto fail = [](SolveStatus status) { return status; };

  bool refresh = false;  // re-associate now, whatever the schedule (see the convergence test)
  for (int iteration = 0; iteration < config.max_iterations; ++iteration) {
    bool associated = false;  // the residual set may have changed
    if constexpr (ReassociatingProblem<Problem>) {
      if (config.reassociate_every > 0 && (refresh || iteration % config.reassociate_every == 0)) {
        problem.associate(T);
        associated = true;
        refresh = false;
      }
    }
    eq.reset();
    problem.linearize(T, eq);
    report.num_residuals = eq.num_residuals;
    if (eq.num_residuals < config.min_residuals) return fail(SolveStatus::kTooFewResiduals);
    if (!detail::all_finite(eq)) return fail(SolveStatus::kNumericalFailure);
    if (iteration == 0 && first_run) report.initial_cost = eq.cost;
    // Degeneracy analysis (file comment): directions found degenerate get no
    // update until the next analysis.
    if (locked == nullptr && (iteration == 0 || (associated && config.reanalyse_degeneracy))) {
      projection = degeneracy_projection(eq.H, config, report);
      if (iteration == 0 && first_run) report.initial_degenerate_directions = report.degenerate_directions;
      if (config.damp_degenerate && config.remap_degenerate && !config.reset_weak_directions) {
        damping = degeneracy_damping(config, report);
        projection = Matrix6::Identity();
      }
    }
    report.final_cost = eq.cost;
    report.hessian = eq.H;

    Matrix6 A = eq.H + damping;
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
    ++report.iterations;
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
      if constexpr (ReassociatingProblem<Problem>) {
        // A small step from correspondences chosen at an earlier pose only
        // says those correspondences are fitted: re-associate, then decide.
        // (Stopping there made reassociate_every = 2 converge on the
        // prediction's matches: ~5x the ATE on the main job's drive.)
        if (!associated && config.reassociate_every > 0) {
          refresh = true;
          continue;
        }
      }
      eq.reset();
      problem.linearize(T, eq);
      if (eq.num_residuals >= config.min_residuals && detail::all_finite(eq)) {
        report.final_cost = eq.cost;
        report.hessian = eq.H;
        report.num_residuals = eq.num_residuals;
      }
      return SolveStatus::kConverged;
    }
  }
  return SolveStatus::kMaxIterations;
}

}  // namespace detail

/// Minimises the problem's cost over T (in place) by Gauss-Newton with right
/// perturbation T <- T * exp(dx). On kTooFewResiduals / kNumericalFailure T is
/// left unchanged; the result never contains NaN. Throws ConfigError when
/// the normalised test is on (degeneracy_ratio > 0) with a
/// degeneracy_length_m that is not a finite positive length.
///
/// Two stages. (1) Iterations with LIO-SAM's absolute degeneracy test,
/// re-analysed after every re-association (file comment); it shapes the
/// steps only. (2) The normalised test (`degeneracy_ratio`) on the final
/// system sets the flag: weak directions are
/// reported (first columns of eigenvectors); with `reset_weak_directions`
/// the solution is also put back at the start along them (the start being
/// the prediction) and the other directions are re-solved with that
/// projection fixed. The relative test is not used during stage 1: from a
/// far-off start (identity, the zero-velocity first frame of a drive) the
/// features along the offset are outside the association gate, so that
/// direction looks weak until the solve gets there, and freezing it would
/// keep it at the start for good (measured: the simulated urban drive's
/// lidar-only front end stuck at standstill, KITTI t_err 38 %). The reset
/// is off by default because the ratio also flags some accurate solutions
/// (the KITTI pair with surfaces only, 1.5 cm from the plane ICP; a
/// simulated street pair registered from identity with NormalConsistency
/// and robust corners, 0.24 cm from the truth), which a reset would throw
/// away; on the simulated
/// highway with a correct prediction it keeps every frame within 1 cm.
template <LeastSquaresProblem Problem>
SolveReport gauss_newton(Problem& problem, SE3d& T, const GaussNewtonConfig& config = {}) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  if (config.degeneracy_ratio > 0.0 &&
      !(std::isfinite(config.degeneracy_length_m) && config.degeneracy_length_m > 0.0)) {
    throw ConfigError("GaussNewtonConfig.degeneracy_length_m = " + std::to_string(config.degeneracy_length_m) +
                      ", expected a finite length > 0 [m]");
  }
  SolveReport report;
  const SE3d T_initial = T;
  GaussNewtonConfig absolute = config;
  absolute.degeneracy_ratio = 0.0;
  report.status = detail::iterate(problem, T, absolute, report, nullptr);
  if (!report.ok()) {
    T = T_initial;
    return report;
  }
  if (!(config.degeneracy_ratio > 0.0)) return report;

  // Stage 2: the normalised test on the final system (its Hessian is in the
  // report) sets the flag.
  detail::degeneracy_projection(report.hessian, config, report);
  if (!config.remap_degenerate || !config.reset_weak_directions) return report;
  // The reset's own analysis (weak_reset_ratio); the report keeps the flag's.
  GaussNewtonConfig reset_config = config;
  reset_config.degeneracy_ratio = std::max(config.degeneracy_ratio, config.weak_reset_ratio);
  SolveReport weak = report;
  const Matrix6 P = detail::degeneracy_projection(report.hessian, reset_config, weak);
  // Re-solve only when a weak direction was not already held by stage 1
  // (information above the absolute threshold: it took full steps there).
  bool stepped = false;
  for (int k = 0; k < weak.degenerate_directions; ++k) {
    stepped = stepped || !(weak.eigenvalues[k] < config.degeneracy_threshold);
  }
  if (!stepped) return report;
  SE3d T_reset = T_initial * SE3d::exp(P * (T_initial.inverse() * T).log());
  SolveReport polish = report;
  polish.status = detail::iterate(problem, T_reset, config, polish, &P);
  if (!polish.ok() || !T_reset.matrix().allFinite()) return report;  // keep the stage-1 solution
  T = T_reset;
  return polish;
}

}  // namespace semlio
