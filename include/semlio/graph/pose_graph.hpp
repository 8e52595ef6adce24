#pragma once
/// \file
/// Incremental pose graph over keyframe poses (SE(3), or SE(2) for planar
/// benchmarks) with prior, between (odometry) and loop-closure factors,
/// solved by sparse Levenberg-Marquardt on the reduced system (fixed nodes,
/// by default the first one, are removed from the unknowns).
///
/// Contract (GTSAM-like, DESIGN.md): add nodes and factors, then `update()`.
/// - Without a loop closure, `update()` optimises a sliding window: only the
///   `window_size` newest nodes are unknowns, every factor touching them is
///   linearised, and older nodes they connect to are held fixed. Its cost is
///   proportional to the window (adjacency lists, no pass over the graph).
/// - A loop closure (or any new factor / prior touching a node older than the
///   window) makes the next `update()` a full re-solve of the whole graph,
///   warm-started from the current estimate (which the window updates have
///   kept close to the optimum, so few iterations are needed).
/// - `optimize()` always solves the full graph (batch use, g2o files).
/// Degenerate or singular systems (a node without constraints, rank-deficient
/// information) and non-finite errors come back as a status; the estimate is
/// then left unchanged — never an abort, never NaN.
///
/// Extension to IMU states (METHOD.md step 9): the graph is generic over the
/// node type through Variable<T> (dimension + retraction, variable.hpp) and
/// the linear algebra only sees kDim-blocks (block_system.hpp). A keyframe
/// state with velocity and IMU bias becomes a node type with kDim = 15
/// (pose, v, b_g, b_a) whose between_error overload acts on the pose part,
/// plus a preintegration factor kind over two such nodes.
///
/// The error convention is ErrorConvention (between_error.hpp); chi2 is
/// sum e^T Omega e (no 1/2) over the factors, robust ones counted raw.
/// Not thread-safe; a graph is used from one thread at a time.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/graph/between_error.hpp>
#include <semlio/graph/block_system.hpp>
#include <semlio/graph/factors.hpp>
#include <semlio/graph/pose2.hpp>
#include <semlio/graph/variable.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// Settings of the pose-graph solver.
struct PoseGraphConfig {
  int max_iterations = 100;             ///< LM iterations of a full solve
  int window_iterations = 10;           ///< LM iterations of a window update
  std::size_t window_size = 30;         ///< newest nodes free in a window update
  double function_tolerance = 1e-12;    ///< stop when the relative cost decrease is below
  double step_tolerance = 1e-12;        ///< stop when the step norm |dx| is below
  double initial_lambda = 1e-6;         ///< LM damping after the first (Gauss-Newton) step
  double huber_delta = 4.0;             ///< robust loops: Huber threshold on sqrt(e^T Omega e)
  double singular_pivot_ratio = 1e-14;  ///< LDL^T pivot / max pivot below this = singular
  bool fix_first_node = true;           ///< node 0 is held fixed (gauge)
  bool record_trace = false;            ///< fill GraphSolveReport::trace (one entry per LM iteration)
  ErrorConvention convention{};         ///< between-error convention (between_error.hpp)
};

/// How a solve ended.
enum class GraphSolveStatus {
  converged,         ///< a tolerance was met
  max_iterations,    ///< iteration limit reached (estimate improved but not converged)
  singular,          ///< the reduced system is singular; estimate unchanged
  non_finite,        ///< an error or Jacobian was NaN/Inf; estimate unchanged
  nothing_to_solve,  ///< no free node
};

/// Which unknowns a solve had.
enum class GraphSolveMode {
  window,  ///< the newest window_size nodes (incremental update)
  full,    ///< every non-fixed node
};

/// One LM iteration of a solve (optional trace).
struct GraphSolveIteration {
  double chi2 = 0.0;       ///< sum e^T Omega e after the iteration
  double lambda = 0.0;     ///< damping used (0 = Gauss-Newton)
  double step_norm = 0.0;  ///< |dx| of the proposed step
  bool accepted = false;   ///< step taken
};

/// Result of update() / optimize().
struct GraphSolveReport {
  GraphSolveStatus status = GraphSolveStatus::nothing_to_solve;  ///< outcome
  GraphSolveMode mode = GraphSolveMode::full;                    ///< window or full
  int iterations = 0;                                  ///< LM iterations (accepted and rejected steps)
  double initial_chi2 = 0.0;                           ///< sum e^T Omega e over the solved factors, before
  double final_chi2 = 0.0;                             ///< the same after
  std::size_t free_nodes = 0;                          ///< unknown nodes
  std::size_t active_factors = 0;                      ///< factors linearised
  long degenerate_node = -1;                           ///< when singular: a node on the singular pivot (best effort)
  std::vector<GraphSolveIteration> trace;                   ///< per-iteration trace when PoseGraphConfig::record_trace
  /// True when the estimate is usable (converged or iteration limit).
  [[nodiscard]] bool ok() const {
    return status == GraphSolveStatus::converged || status == GraphSolveStatus::max_iterations ||
           status == GraphSolveStatus::nothing_to_solve;
  }
};

/// Readable name of a status.
inline const char* to_string(GraphSolveStatus s) {
  switch (s) {
    case GraphSolveStatus::converged:
      return "converged";
    case GraphSolveStatus::max_iterations:
      return "max_iterations";
    case GraphSolveStatus::singular:
      return "singular";
    case GraphSolveStatus::non_finite:
      return "non_finite";
    case GraphSolveStatus::nothing_to_solve:
      return "nothing_to_solve";
  }
  return "?";
}

/// Pose graph over nodes of type Pose (SE3d or Pose2).
template <GraphVariable Pose>
class PoseGraph {
 public:
  using Config = PoseGraphConfig;
  static constexpr int kDim = Variable<Pose>::kDim;
  using Factor = PoseFactor<Pose>;
  using Information = typename Factor::Information;
  using Tangent = typename Variable<Pose>::Tangent;

  /// Empty graph.
  explicit PoseGraph(const Config& config = {}) : config_(config) {
    if (config_.max_iterations < 0 || config_.window_iterations < 0)
      throw ConfigError("PoseGraphConfig: negative iteration limit");
    if (config_.window_size == 0) throw ConfigError("PoseGraphConfig.window_size: must be >= 1");
    if (!(config_.huber_delta > 0.0))
      throw ConfigError("PoseGraphConfig.huber_delta: must be > 0, got " + std::to_string(config_.huber_delta));
  }

  /// Adds a node with its initial estimate; returns its id (0, 1, ...).
  NodeId add_node(const Pose& initial) {
    const auto id = static_cast<NodeId>(poses_.size());
    poses_.push_back(initial);
    fixed_.push_back(config_.fix_first_node && id == 0 ? 1 : 0);
    adjacent_.emplace_back();
    local_.push_back(-1);
    return id;
  }

  /// Holds a node fixed (true) or frees it; the next update() is a full solve.
  void set_fixed(NodeId node, bool fixed) {
    check_node(node, "set_fixed");
    fixed_[node] = fixed ? 1 : 0;
    pending_full_ = true;
  }

  /// Adds a prior on `node`; returns the factor index. Every information
  /// matrix must be finite (else ValueError) and symmetric PSD: an indefinite
  /// one (io::project_to_psd repairs those) makes solves report `singular`.
  std::size_t add_prior(NodeId node, const Pose& measured, const Information& information) {
    return add_factor(Factor{.kind = FactorKind::prior,
                             .from = node,
                             .to = node,
                             .measured = measured,
                             .information = information,
                             .robust = false});
  }

  /// Adds an odometry factor with measurement Z = T_from^-1 T_to.
  std::size_t add_between(NodeId from, NodeId to, const Pose& measured, const Information& information) {
    return add_factor(Factor{.kind = FactorKind::between,
                             .from = from,
                             .to = to,
                             .measured = measured,
                             .information = information,
                             .robust = false});
  }

  /// Adds a loop closure (Huber-weighted when robust); the next update() re-solves fully.
  std::size_t add_loop(NodeId from, NodeId to, const Pose& measured, const Information& information,
                       bool robust = true) {
    return add_factor(Factor{.kind = FactorKind::loop,
                             .from = from,
                             .to = to,
                             .measured = measured,
                             .information = information,
                             .robust = robust});
  }

  /// Incremental solve: window of the newest nodes, or a warm-started full
  /// solve after a loop closure (see the file comment).
  GraphSolveReport update() {
    const std::size_t n = poses_.size();
    if (pending_full_ || n <= config_.window_size) {
      GraphSolveReport report = optimize();
      return report;
    }
    free_.clear();
    for (std::size_t k = n - config_.window_size; k < n; ++k) {
      if (fixed_[k] == 0) free_.push_back(static_cast<NodeId>(k));
    }
    active_.clear();
    for (const NodeId node : free_) active_.insert(active_.end(), adjacent_[node].begin(), adjacent_[node].end());
    std::sort(active_.begin(), active_.end());
    active_.erase(std::unique(active_.begin(), active_.end()), active_.end());
    GraphSolveReport report = solve(config_.window_iterations);
    report.mode = GraphSolveMode::window;
    return report;
  }

  /// Full solve of every non-fixed node, warm-started from the current estimate.
  GraphSolveReport optimize() { return optimize(config_.max_iterations); }

  /// Full solve with an explicit iteration limit.
  GraphSolveReport optimize(int max_iterations) {
    free_.clear();
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      if (fixed_[k] == 0) free_.push_back(static_cast<NodeId>(k));
    }
    active_.resize(factors_.size());
    for (std::size_t f = 0; f < factors_.size(); ++f) active_[f] = static_cast<std::uint32_t>(f);
    GraphSolveReport report = solve(max_iterations);
    report.mode = GraphSolveMode::full;
    if (report.ok()) pending_full_ = false;
    return report;
  }

  /// chi2 = sum e^T Omega e over all factors at the current estimate.
  [[nodiscard]] double chi2() const {
    double sum = 0.0;
    for (const Factor& f : factors_) sum += squared_error(f, poses_[f.from], poses_[f.to]);
    return sum;
  }

  /// Current estimate of a node.
  [[nodiscard]] const Pose& pose(NodeId node) const {
    check_node(node, "pose");
    return poses_[node];
  }
  /// Overwrites a node's estimate; older nodes than the window make the next update() full.
  void set_pose(NodeId node, const Pose& value) {
    check_node(node, "set_pose");
    poses_[node] = value;
    if (!in_window(node)) pending_full_ = true;
  }
  /// All estimates, indexed by NodeId.
  [[nodiscard]] const std::vector<Pose>& poses() const { return poses_; }
  /// All factors in insertion order.
  [[nodiscard]] const std::vector<Factor>& factors() const { return factors_; }
  /// Whether a node is held fixed.
  [[nodiscard]] bool is_fixed(NodeId node) const {
    check_node(node, "is_fixed");
    return fixed_[node] != 0;
  }
  /// Number of nodes.
  [[nodiscard]] std::size_t num_nodes() const { return poses_.size(); }
  /// Number of factors.
  [[nodiscard]] std::size_t num_factors() const { return factors_.size(); }
  /// True when the next update() will be a full solve.
  [[nodiscard]] bool full_solve_pending() const { return pending_full_ || poses_.size() <= config_.window_size; }
  /// Settings.
  [[nodiscard]] const Config& config() const { return config_; }

 private:
  void check_node(NodeId node, const char* what) const {
    if (node >= poses_.size()) {
      throw ValueError(std::string("PoseGraph::") + what + ": node " + std::to_string(node) + " does not exist (" +
                       std::to_string(poses_.size()) + " nodes)");
    }
  }

  [[nodiscard]] bool in_window(NodeId node) const {
    return poses_.size() <= config_.window_size || node >= poses_.size() - config_.window_size;
  }

  std::size_t add_factor(const Factor& f) {
    check_node(f.from, "add factor (from)");
    check_node(f.to, "add factor (to)");
    if (f.kind != FactorKind::prior && f.from == f.to) {
      throw ValueError("PoseGraph: between/loop factor from node " + std::to_string(f.from) + " to itself");
    }
    if (!f.information.allFinite()) {
      throw ValueError("PoseGraph: information matrix of factor " + std::to_string(factors_.size()) + " is not finite");
    }
    const auto index = static_cast<std::uint32_t>(factors_.size());
    factors_.push_back(f);
    adjacent_[f.to].push_back(index);
    if (f.kind != FactorKind::prior) adjacent_[f.from].push_back(index);
    if (f.kind == FactorKind::loop || !in_window(f.from) || !in_window(f.to)) pending_full_ = true;
    return index;
  }

  // Error and optional Jacobians of a factor at the given poses.
  Eigen::Matrix<double, kDim, 1> error(const Factor& f, const Pose& a, const Pose& b,
                                       Eigen::Matrix<double, kDim, kDim>* J_a,
                                       Eigen::Matrix<double, kDim, kDim>* J_b) const {
    if (f.kind == FactorKind::prior) {
      // A prior has no `from` node, but linearize() reads J_a for every
      // factor: zero it rather than leave it unwritten (an uninitialised
      // read; clang 14 at -O1 and up turned it into a non-finite status).
      if (J_a != nullptr) J_a->setZero();
      return between_error(f.measured, Pose(), b, config_.convention, nullptr, J_b);
    }
    return between_error(f.measured, a, b, config_.convention, J_a, J_b);
  }

  [[nodiscard]] double squared_error(const Factor& f, const Pose& a, const Pose& b) const {
    const Eigen::Matrix<double, kDim, 1> e = error(f, a, b, nullptr, nullptr);
    return e.dot(f.information * e);
  }

  [[nodiscard]] double robust_cost(const Factor& f, double s) const {
    return f.robust ? huber_cost(s, config_.huber_delta) : s;
  }

  [[nodiscard]] const Pose& current(NodeId node) const {
    const int l = local_[node];
    return l >= 0 ? candidate_[static_cast<std::size_t>(l)] : poses_[node];
  }

  // Cost (robust) and raw chi2 of the active factors with `use_candidate`.
  bool evaluate(bool use_candidate, double& cost, double& chi2) const {
    cost = 0.0;
    chi2 = 0.0;
    for (const std::uint32_t fi : active_) {
      const Factor& f = factors_[fi];
      const double s = use_candidate ? squared_error(f, current(f.from), current(f.to))
                                     : squared_error(f, poses_[f.from], poses_[f.to]);
      cost += robust_cost(f, s);
      chi2 += s;
    }
    return std::isfinite(cost) && std::isfinite(chi2);
  }

  void build_pattern() {
    system_.begin_pattern(free_.size());
    for (const std::uint32_t fi : active_) {
      const Factor& f = factors_[fi];
      const int la = local_[f.from];
      const int lb = local_[f.to];
      if (f.kind != FactorKind::prior && la >= 0 && lb >= 0)
        system_.declare(static_cast<std::size_t>(la), static_cast<std::size_t>(lb));
    }
    system_.end_pattern();
    handles_.resize(active_.size());
    constexpr std::array<int, kDim> kNone = [] {
      std::array<int, kDim> a{};
      a.fill(-1);
      return a;
    }();
    for (std::size_t k = 0; k < active_.size(); ++k) {
      const Factor& f = factors_[active_[k]];
      const int la = f.kind == FactorKind::prior ? -1 : local_[f.from];
      const int lb = local_[f.to];
      auto& h = handles_[k];
      h[0] = la >= 0 ? system_.handle(static_cast<std::size_t>(la), static_cast<std::size_t>(la)) : kNone;
      h[1] = lb >= 0 ? system_.handle(static_cast<std::size_t>(lb), static_cast<std::size_t>(lb)) : kNone;
      h[2] = (la >= 0 && lb >= 0) ? system_.handle(static_cast<std::size_t>(std::max(la, lb)),
                                                   static_cast<std::size_t>(std::min(la, lb)))
                                  : kNone;
    }
  }

  // Builds H and g at poses_ (robust factors IRLS-weighted); false on non-finite.
  bool linearize() {
    using Mat = Eigen::Matrix<double, kDim, kDim>;
    system_.zero();
    Eigen::VectorXd& g = system_.g();
    Mat J_a;
    Mat J_b;
    for (std::size_t k = 0; k < active_.size(); ++k) {
      const Factor& f = factors_[active_[k]];
      const bool prior = f.kind == FactorKind::prior;
      const int la = prior ? -1 : local_[f.from];
      const int lb = local_[f.to];
      const Eigen::Matrix<double, kDim, 1> e = error(f, poses_[f.from], poses_[f.to], &J_a, &J_b);
      if (!e.allFinite() || !J_a.allFinite() || !J_b.allFinite()) return false;
      double w = 1.0;
      if (f.robust) w = huber_weight(e.dot(f.information * e), config_.huber_delta);
      const Mat W = w * f.information;
      const auto& h = handles_[k];
      if (la >= 0) {
        const Mat JtW = J_a.transpose() * W;
        system_.add(h[0], JtW * J_a);
        g.template segment<kDim>(la * kDim) += JtW * e;
      }
      if (lb >= 0) {
        const Mat JtW = J_b.transpose() * W;
        system_.add(h[1], JtW * J_b);
        g.template segment<kDim>(lb * kDim) += JtW * e;
        if (la >= 0) {
          // Lower block: row block max(la, lb), column block min(la, lb).
          if (lb > la) {
            system_.add(h[2], JtW * J_a);
          } else {
            system_.add(h[2], (J_a.transpose() * W * J_b).eval());
          }
        }
      }
    }
    return g.allFinite();
  }

  GraphSolveReport solve(int max_iterations) {
    GraphSolveReport report;
    report.free_nodes = free_.size();
    report.active_factors = active_.size();
    for (std::size_t l = 0; l < free_.size(); ++l) local_[free_[l]] = static_cast<int>(l);
    candidate_.assign(free_.size(), Pose());
    run(max_iterations, report);
    for (const NodeId node : free_) local_[node] = -1;  // O(window) reset
    return report;
  }

  void run(int max_iterations, GraphSolveReport& report) {
    double cost = 0.0;
    double chi2 = 0.0;
    if (!evaluate(false, cost, chi2)) {
      report.status = GraphSolveStatus::non_finite;
      return;
    }
    report.initial_chi2 = chi2;
    report.final_chi2 = chi2;
    if (free_.empty()) {
      report.status = GraphSolveStatus::nothing_to_solve;
      return;
    }
    build_pattern();
    // Half-cost convention inside LM: F = cost / 2, gradient g, Hessian H.
    double lambda = 0.0;  // the first step is pure Gauss-Newton (and checks singularity)
    double nu = 2.0;
    bool relinearize = true;
    Eigen::VectorXd dx;
    report.status = GraphSolveStatus::max_iterations;
    for (int it = 0; it < max_iterations; ++it) {
      if (relinearize) {
        if (!linearize()) {
          report.status = GraphSolveStatus::non_finite;
          return;
        }
        relinearize = false;
      }
      Eigen::Index bad_row = -1;
      const detail::FactorStatus fs = system_.factorize(lambda, config_.singular_pivot_ratio, &bad_row);
      if (fs == detail::FactorStatus::singular) {
        report.status = GraphSolveStatus::singular;
        if (bad_row >= 0) report.degenerate_node = static_cast<long>(free_[static_cast<std::size_t>(bad_row / kDim)]);
        return;
      }
      ++report.iterations;
      if (fs == detail::FactorStatus::failed) {
        lambda *= nu;
        nu *= 2.0;
        continue;
      }
      system_.solve(dx);
      const Eigen::VectorXd& g = system_.g();
      const double predicted = -(g.dot(dx) + 0.5 * system_.quadratic(dx));  // decrease of F
      const double F = 0.5 * cost;
      if (!dx.allFinite()) {
        report.status = GraphSolveStatus::non_finite;
        return;
      }
      if (!(predicted > 0.0)) {
        report.status = GraphSolveStatus::converged;
        break;
      }
      // A step that predicts a negligible decrease is still taken when it
      // does not increase the cost (it polishes the optimum), then we stop.
      const bool last_step = predicted <= config_.function_tolerance * F;
      double x_norm2 = 0.0;
      for (std::size_t l = 0; l < free_.size(); ++l) {
        const Tangent step = dx.template segment<kDim>(static_cast<Eigen::Index>(l) * kDim);
        candidate_[l] = Variable<Pose>::retract(poses_[free_[l]], step);
        x_norm2 += step.squaredNorm();
      }
      double new_cost = 0.0;
      double new_chi2 = 0.0;
      const bool finite = evaluate(true, new_cost, new_chi2);
      const double actual = F - 0.5 * new_cost;
      const double rho = actual / predicted;
      if (config_.record_trace) {
        report.trace.push_back({.chi2 = finite && rho > 0.0 ? new_chi2 : chi2,
                                .lambda = lambda,
                                .step_norm = std::sqrt(x_norm2),
                                .accepted = finite && (rho > 0.0 || (last_step && new_cost <= cost))});
      }
      if (last_step) {
        if (finite && new_cost <= cost) {
          for (std::size_t l = 0; l < free_.size(); ++l) poses_[free_[l]] = candidate_[l];
          cost = new_cost;
          report.final_chi2 = new_chi2;
        }
        report.status = GraphSolveStatus::converged;
        break;
      }
      if (finite && rho > 0.0) {
        for (std::size_t l = 0; l < free_.size(); ++l) poses_[free_[l]] = candidate_[l];
        const double rel = actual / std::max(F, 1e-300);
        cost = new_cost;
        chi2 = new_chi2;
        report.final_chi2 = chi2;
        relinearize = true;
        const double t = 2.0 * rho - 1.0;
        lambda = lambda == 0.0 ? config_.initial_lambda : lambda * std::max(1.0 / 3.0, 1.0 - t * t * t);
        nu = 2.0;
        if (rel < config_.function_tolerance || std::sqrt(x_norm2) < config_.step_tolerance || cost == 0.0) {
          report.status = GraphSolveStatus::converged;
          break;
        }
      } else {
        lambda = lambda == 0.0 ? config_.initial_lambda : lambda * nu;
        nu *= 2.0;
        if (lambda > 1e32) {
          report.status = GraphSolveStatus::converged;  // no decrease possible at numerical precision
          break;
        }
      }
    }
  }

  Config config_;
  std::vector<Pose> poses_;
  std::vector<std::uint8_t> fixed_;
  std::vector<Factor> factors_;
  std::vector<std::vector<std::uint32_t>> adjacent_;  // factors per node
  bool pending_full_ = false;

  // Solver scratch, reused between solves.
  std::vector<int> local_;  // node -> unknown index, -1 when held fixed
  std::vector<NodeId> free_;
  std::vector<std::uint32_t> active_;
  std::vector<Pose> candidate_;
  std::vector<std::array<std::array<int, kDim>, 3>> handles_;
  detail::BlockSystem<kDim> system_;
};

/// 3D keyframe pose graph.
using PoseGraph3d = PoseGraph<SE3d>;
/// 2D pose graph (planar benchmarks).
using PoseGraph2d = PoseGraph<Pose2>;

}  // namespace semlio
