#pragma once
/// \file
/// A fixed-lag (sliding-window) smoother over navigation states: the back end
/// of the lidar-inertial odometry (METHOD.md step 9: "velocity and bias states
/// join the keyframe nodes, and preintegrated IMU factors join the graph").
///
/// Nodes are NavState + ImuBias (15-dim tangent, imu/imu_factor.hpp: pose
/// [rho; phi] with right perturbation, world velocity, gyro and accel bias).
/// Factors:
/// - prior: Gaussian on a whole node, cost d^T H d + 2 b^T d with d = x (-) x_lin
///   (a plain prior has b = 0 and H = its information);
/// - pose: the front end's T_world_imu with a 6x6 information, error
///   log(Z^-1 T) ([rho; phi]);
/// - IMU: the preintegrated residual (eq. 45 of Forster et al.) with the
///   inverse of the preintegration covariance, plus the bias random walk
///   b_j - b_i with the inverse of its covariance over the window.
/// The cost is the sum of squared Mahalanobis errors (no 1/2), minimised by
/// Levenberg-Marquardt on the dense normal equations: a window of W states has
/// 15 W unknowns (150 for the default W = 10), so dense is both simplest and fast.
///
/// Window (documented simplification of full smoothing): once more than
/// `window_size` states are held, optimize() marginalises the oldest ones by
/// the Schur complement of the factors touching them, linearised at the
/// current estimate; the result is a prior (H, b, x_lin) on the next state
/// (first-estimate Jacobians are not kept fixed afterwards, so the marginal
/// prior is relinearised like any other factor — slightly inconsistent, as in
/// most fixed-lag smoothers, and harmless at the window sizes used here).
/// Factors that touch a marginalised state and a state other than its
/// successor are dropped (the lidar-inertial odometry never adds such).
///
/// Degenerate problems (no prior on the first state and nothing else fixing
/// the gauge, a singular system, non-finite values) come back as a status;
/// states are then left unchanged and never become NaN. Not thread-safe.

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/graph/dense_kernels.hpp>
#include <semlio/imu/imu_factor.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// Settings of InertialGraph.
struct InertialGraphConfig {
  std::size_t window_size = 10;       ///< states kept after optimize(); older ones are marginalised (>= 2)
  int max_iterations = 10;            ///< LM iterations per optimize()
  double lm_initial_lambda = 1e-6;    ///< initial damping, relative to diag(H)
  double step_tolerance = 1e-9;       ///< converged when |dx|^2 is below this (mixed units, tiny)
  double singular_pivot_ratio = 1e-14;  ///< an LDL^T pivot <= this * the largest: singular
  double min_variance = 1e-14;        ///< floor of IMU / bias-walk variances (noise-free configs)
};

/// Outcome of InertialGraph::optimize().
enum class InertialSolveStatus {
  kConverged,         ///< step below tolerance
  kMaxIterations,     ///< iteration cap reached; states hold the best estimate
  kEmpty,             ///< no states
  kSingular,          ///< the system is rank-deficient (e.g. no prior); states unchanged
  kNumericalFailure,  ///< non-finite values; states unchanged
};

/// Name of a status.
constexpr const char* to_string(InertialSolveStatus s) noexcept {
  switch (s) {
    case InertialSolveStatus::kConverged: return "converged";
    case InertialSolveStatus::kMaxIterations: return "max_iterations";
    case InertialSolveStatus::kEmpty: return "empty";
    case InertialSolveStatus::kSingular: return "singular";
    case InertialSolveStatus::kNumericalFailure: return "numerical_failure";
  }
  return "unknown";
}

/// Report of one optimize() call.
struct InertialSolveReport {
  InertialSolveStatus status = InertialSolveStatus::kEmpty;  ///< outcome
  int iterations = 0;                                       ///< accepted LM steps
  double initial_cost = 0.0;                                ///< cost before
  double final_cost = 0.0;                                  ///< cost after
  std::size_t marginalized = 0;                             ///< states marginalised after the solve
  /// True when the states were updated from the data.
  [[nodiscard]] bool ok() const noexcept {
    return status == InertialSolveStatus::kConverged || status == InertialSolveStatus::kMaxIterations;
  }
};

/// One node: the IMU's navigation state and bias at a time.
struct InertialNode {
  double stamp_s = 0.0;  ///< time (IMU clock) [s]
  NavState state;        ///< pose and velocity in the world (graph) frame
  ImuBias bias;          ///< IMU bias
};

/// Sliding-window smoother over InertialNodes (see the file comment).
class InertialGraph {
 public:
  using Config = InertialGraphConfig;
  /// Id of a state: dense from 0 in insertion order, never reused.
  using Id = std::size_t;

  /// Validates the settings (ConfigError names the field).
  explicit InertialGraph(const Config& config = {}) : config_(config) {
    if (config_.window_size < 2) {
      throw ConfigError("InertialGraphConfig.window_size must be >= 2, got " + std::to_string(config_.window_size));
    }
    if (config_.max_iterations < 1) {
      throw ConfigError("InertialGraphConfig.max_iterations must be >= 1, got " +
                        std::to_string(config_.max_iterations));
    }
  }

  /// Adds a state with its initial guess and returns its id.
  Id add_state(double stamp_s, const NavState& guess, const ImuBias& bias_guess) {
    nodes_.push_back({stamp_s, guess, bias_guess});
    return first_id_ + nodes_.size() - 1;
  }

  /// Gaussian prior on a whole state: information (15x15, navigation tangent).
  void add_prior(Id id, const NavState& x, const ImuBias& b, const Matrix15d& information) {
    check(id, "add_prior");
    priors_.push_back({id, x, b, symmetric(information), Vector15d::Zero()});
  }

  /// The front end's pose of the IMU, T_world_imu, with a 6x6 information
  /// ([rho; phi] order, right-perturbation tangent of the IMU pose).
  void add_pose(Id id, const SE3d& T_world_imu, const Eigen::Matrix<double, 6, 6>& information) {
    check(id, "add_pose");
    poses_.push_back({id, T_world_imu, symmetric(information)});
  }

  /// Preintegrated IMU factor from state i to state j (i < j), plus the bias
  /// random-walk factor over the same window.
  void add_imu(Id i, Id j, const ImuPreintegration& pim) {
    check(i, "add_imu");
    check(j, "add_imu");
    if (!(i < j)) throw ValueError("InertialGraph::add_imu: state " + std::to_string(i) + " is not before " + std::to_string(j));
    Eigen::MatrixXd cov = pim.covariance();
    cov.diagonal().array() += config_.min_variance;
    Eigen::MatrixXd bias_cov = pim.bias_walk_covariance();
    bias_cov.diagonal().array() += config_.min_variance;
    Imu f{i, j, pim, detail::inverse_spd(cov, 0.0), detail::inverse_spd(bias_cov, 0.0)};
    detail::symmetrize(f.information);
    detail::symmetrize(f.bias_information);
    imus_.push_back(f);
  }

  /// Runs LM, then marginalises states beyond the window. On kSingular /
  /// kNumericalFailure the states are unchanged (and nothing is marginalised).
  InertialSolveReport optimize() {
    InertialSolveReport rep;
    if (nodes_.empty()) return rep;
    const auto n = static_cast<Eigen::Index>(15 * nodes_.size());
    Eigen::MatrixXd H(n, n);
    Eigen::VectorXd g(n);
    double cost = linearize(nodes_, H, g, false);
    rep.initial_cost = cost;
    rep.final_cost = cost;
    if (!std::isfinite(cost) || !H.allFinite() || !g.allFinite()) {
      rep.status = InertialSolveStatus::kNumericalFailure;
      return rep;
    }
    {
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
      const Eigen::VectorXd d = ldlt.vectorD().cwiseAbs();
      if (ldlt.info() != Eigen::Success || !d.allFinite() ||
          d.minCoeff() <= config_.singular_pivot_ratio * d.maxCoeff()) {
        rep.status = InertialSolveStatus::kSingular;
        return rep;
      }
    }
    double lambda = config_.lm_initial_lambda;
    rep.status = InertialSolveStatus::kMaxIterations;
    std::vector<InertialNode> trial;
    for (int it = 0; it < config_.max_iterations; ++it) {
      Eigen::MatrixXd A = H;
      for (Eigen::Index k = 0; k < n; ++k) A(k, k) += lambda * std::clamp(H(k, k), 1e-6, 1e32);
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
      const Eigen::VectorXd dx = ldlt.solve(-g);
      if (ldlt.info() != Eigen::Success || !dx.allFinite()) {
        lambda *= 10.0;
        if (lambda > 1e12) break;
        continue;
      }
      trial = nodes_;
      for (std::size_t k = 0; k < trial.size(); ++k) {
        retract(trial[k].state, trial[k].bias, dx.segment<15>(static_cast<Eigen::Index>(15 * k)));
      }
      Eigen::MatrixXd H_new(n, n);
      Eigen::VectorXd g_new(n);
      const double new_cost = linearize(trial, H_new, g_new, false);
      if (std::isfinite(new_cost) && new_cost <= cost) {
        nodes_.swap(trial);
        H.swap(H_new);
        g.swap(g_new);
        cost = new_cost;
        ++rep.iterations;
        lambda = std::max(lambda * 0.1, 1e-12);
        if (dx.squaredNorm() < config_.step_tolerance) {
          rep.status = InertialSolveStatus::kConverged;
          break;
        }
      } else {
        lambda *= 10.0;
        if (lambda > 1e12) {
          rep.status = InertialSolveStatus::kConverged;  // no descent left: at a minimum
          break;
        }
      }
    }
    rep.final_cost = cost;
    while (nodes_.size() > config_.window_size) {
      marginalize_oldest();
      ++rep.marginalized;
    }
    return rep;
  }

  /// Number of states held.
  [[nodiscard]] std::size_t size() const noexcept { return nodes_.size(); }
  /// True when no state is held.
  [[nodiscard]] bool empty() const noexcept { return nodes_.empty(); }
  /// Id of the oldest state held.
  [[nodiscard]] Id first_id() const noexcept { return first_id_; }
  /// Id of the newest state (precondition: !empty()).
  [[nodiscard]] Id last_id() const noexcept { return first_id_ + nodes_.size() - 1; }
  /// True when `id` is held (not marginalised, not in the future).
  [[nodiscard]] bool contains(Id id) const noexcept { return id >= first_id_ && id < first_id_ + nodes_.size(); }
  /// A state held (ValueError otherwise).
  [[nodiscard]] const InertialNode& node(Id id) const {
    check(id, "node");
    return nodes_[id - first_id_];
  }
  /// Marginal covariance of a state (15x15, navigation tangent) from the
  /// current linearisation; zero when the system is singular.
  [[nodiscard]] Matrix15d covariance(Id id) const {
    check(id, "covariance");
    const auto n = static_cast<Eigen::Index>(15 * nodes_.size());
    Eigen::MatrixXd H(n, n);
    Eigen::VectorXd g(n);
    linearize(nodes_, H, g, false);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
    if (ldlt.info() != Eigen::Success) return Matrix15d::Zero();
    const auto k = static_cast<Eigen::Index>(15 * (id - first_id_));
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, 15);
    for (Eigen::Index r = 0; r < 15; ++r) E(k + r, r) = 1.0;
    const Eigen::MatrixXd X = ldlt.solve(E);
    Matrix15d c = X.block(k, 0, 15, 15);
    if (!c.allFinite()) return Matrix15d::Zero();
    detail::symmetrize(c);
    return c;
  }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  struct Prior {
    Id id;
    NavState x_lin;
    ImuBias b_lin;
    Matrix15d H;
    Vector15d b;
  };
  struct Pose {
    Id id;
    SE3d T_world_imu;
    Eigen::Matrix<double, 6, 6> information;
  };
  struct Imu {
    Id i;
    Id j;
    ImuPreintegration pim;
    Matrix9d information;
    Eigen::Matrix<double, 6, 6> bias_information;
  };

  void check(Id id, const char* who) const {
    if (!contains(id)) {
      throw ValueError(std::string("InertialGraph::") + who + ": state " + std::to_string(id) +
                       " is not in the window [" + std::to_string(first_id_) + ", " +
                       std::to_string(first_id_ + nodes_.size()) + ")");
    }
  }

  // 0.5 (m + m^T) of a square matrix (any fixed size, through the one dynamic kernel).
  template <typename M>
  static M symmetric(const M& m) {
    M out = m;
    detail::symmetrize(out);
    return out;
  }

  // Adds J_a^T W J_b blocks and J_a^T W r segments of one factor (residual
  // dimension R = W.rows(), Jacobians R x 15) into the dense system.
  static void accumulate(Eigen::MatrixXd& H, Eigen::VectorXd& g, Eigen::Index a, const detail::DenseIn& Ja,
                         Eigen::Index b, const detail::DenseIn& Jb, const detail::DenseIn& W,
                         const detail::DenseIn& Wr) {
    detail::add_at_w_b(H.block(a, a, 15, 15), Ja, W, Ja);
    detail::add_at_v(g.segment(a, 15), Ja, Wr);
    Matrix15d Hab = Matrix15d::Zero();
    detail::add_at_w_b(Hab, Ja, W, Jb);
    H.block(a, b, 15, 15) += Hab;  // the two off-diagonal blocks stay exact transposes
    detail::add_transposed(H.block(b, a, 15, 15), Hab);
    detail::add_at_w_b(H.block(b, b, 15, 15), Jb, W, Jb);
    detail::add_at_v(g.segment(b, 15), Jb, Wr);
  }

  // Builds H and g over `nodes` (the window, or a trial copy of it); returns the
  // cost. only_first: only the factors touching the oldest state.
  double linearize(const std::vector<InertialNode>& nodes, Eigen::MatrixXd& H, Eigen::VectorXd& g,
                   bool only_first) const {
    H.setZero();
    g.setZero();
    double cost = 0.0;
    const auto at = [&](Id id) { return static_cast<Eigen::Index>(15 * (id - first_id_)); };
    const auto node = [&](Id id) -> const InertialNode& { return nodes[id - first_id_]; };
    for (const Prior& p : priors_) {
      if (only_first && p.id != first_id_) continue;
      const InertialNode& x = node(p.id);
      Matrix15d J;
      const Vector15d d = nav_difference(x.state, x.bias, p.x_lin, p.b_lin, &J);
      Vector15d Hd;
      detail::set_a_b(Hd, p.H, d);
      cost += detail::dot(d, Hd) + 2.0 * detail::dot(p.b, d);
      detail::add_at_w_b(H.block(at(p.id), at(p.id), 15, 15), J, p.H, J);
      Hd += p.b;
      detail::add_at_v(g.segment(at(p.id), 15), J, Hd);
    }
    for (const Pose& p : poses_) {
      if (only_first && p.id != first_id_) continue;
      const InertialNode& x = node(p.id);
      const Eigen::Matrix<double, 6, 1> e = (p.T_world_imu.inverse() * x.state.pose()).log();
      const Eigen::Matrix<double, 6, 6> Je = SE3d::right_jacobian_inverse(e);
      Eigen::Matrix<double, 6, 1> We;
      detail::set_a_b(We, p.information, e);
      cost += detail::dot(e, We);
      detail::add_at_w_b(H.block(at(p.id), at(p.id), 6, 6), Je, p.information, Je);
      detail::add_at_v(g.segment(at(p.id), 6), Je, We);
    }
    for (const Imu& f : imus_) {
      if (only_first && f.i != first_id_) continue;
      const InertialNode& xi = node(f.i);
      const InertialNode& xj = node(f.j);
      Matrix9x15d Ji;
      Matrix9x15d Jj;
      const Vector9d r = imu_factor_error(f.pim, xi.state, xi.bias, xj.state, &Ji, &Jj);
      Vector9d Wr;
      detail::set_a_b(Wr, f.information, r);
      cost += detail::dot(r, Wr);
      accumulate(H, g, at(f.i), Ji, at(f.j), Jj, f.information, Wr);
      Matrix6x15d Bi;
      Matrix6x15d Bj;
      const Eigen::Matrix<double, 6, 1> rb = bias_walk_error(xi.bias, xj.bias, &Bi, &Bj);
      Eigen::Matrix<double, 6, 1> Wrb;
      detail::set_a_b(Wrb, f.bias_information, rb);
      cost += detail::dot(rb, Wrb);
      accumulate(H, g, at(f.i), Bi, at(f.j), Bj, f.bias_information, Wrb);
    }
    return cost;
  }

  // Schur complement of the oldest state over the factors that touch it: a
  // prior (H, b) on its successor, linearised at the current estimate.
  void marginalize_oldest() {
    const Id old = first_id_;
    const Id next = old + 1;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(15 * nodes_.size()),
                                              static_cast<Eigen::Index>(15 * nodes_.size()));
    Eigen::VectorXd g = Eigen::VectorXd::Zero(H.rows());
    linearize(nodes_, H, g, true);
    // H00 = its block, H01 = the coupling block (H is assembled exactly
    // symmetric, so H10 = H01^T); Hm = H11 - H01^T H00^+ H01, bm = g1 - H01^T H00^+ g0.
    Eigen::MatrixXd H00 = H.topLeftCorner(15, 15);
    detail::symmetrize(H00);
    const Eigen::MatrixXd H00_inv = detail::inverse_spd(H00, 1e-12);
    const Eigen::MatrixXd H01 = H.block(0, 15, 15, 15);
    Matrix15d Hm = H.block(15, 15, 15, 15);
    detail::add_at_w_b(Hm, H01, H00_inv, H01, -1.0);
    Vector15d bm = g.segment(15, 15);
    detail::add_at_w_b(bm, H01, H00_inv, g.head(15), -1.0);
    detail::symmetrize(Hm);
    // Drop the factors on the old state; the marginal prior replaces them.
    std::erase_if(priors_, [old](const Prior& p) { return p.id == old; });
    std::erase_if(poses_, [old](const Pose& p) { return p.id == old; });
    std::erase_if(imus_, [old](const Imu& f) { return f.i == old || f.j == old; });
    const InertialNode& x = nodes_[1];
    if (Hm.allFinite() && bm.allFinite()) priors_.push_back({next, x.state, x.bias, Hm, bm});
    nodes_.erase(nodes_.begin());
    ++first_id_;
  }

  Config config_;
  std::vector<InertialNode> nodes_;
  Id first_id_ = 0;
  std::vector<Prior> priors_;
  std::vector<Pose> poses_;
  std::vector<Imu> imus_;
};

}  // namespace semlio
