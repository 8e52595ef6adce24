#pragma once
/// \file
/// Incremental keyframe graph with inertial states (METHOD.md step 9:
/// "velocity and bias states join the keyframe nodes, and preintegrated IMU
/// factors join the graph"): the lidar-inertial counterpart of PoseGraph<SE3d>
/// with the same contract -- add nodes and factors, then `update()`.
///
/// Nodes: keyframes of the IMU, NavState + ImuBias at an IMU time, in the
/// 15-dim navigation tangent of imu/imu_factor.hpp ([rho; phi] right
/// perturbation of T_world_imu, world velocity, gyro bias, accel bias).
/// Factors:
/// - prior on a whole node (15x15 information; zero rows = no information);
/// - between (lidar odometry) and loop closures on the pose part, measured
///   between the SENSOR poses T_world_sensor = T_world_imu * T_imu_sensor
///   (config.T_imu_sensor, e.g. the lidar extrinsic), with the between error
///   and convention of graph/between_error.hpp (as PoseGraph); loops may be
///   Huber-weighted;
/// - preintegrated IMU factor (Forster eq. 45, imu_factor_error) with the
///   inverse preintegration covariance, plus the bias random walk with the
///   inverse of its covariance over the interval.
/// chi2 = sum e^T Omega e over the factors (robust ones counted raw).
///
/// Solve: sparse Levenberg-Marquardt on 15-blocks (block_system.hpp, Eigen
/// SimplicialLDLT). As PoseGraph: without a loop, `update()` frees only the
/// `window_size` newest nodes (older ones they connect to are held at their
/// estimate); a loop, or a factor reaching older than the window, makes the
/// next `update()` a full solve warm-started from the current estimate.
/// No node is fixed: the gauge comes from the priors (a keyframe graph puts
/// one on its first node); without them the system is singular, reported as
/// a status with the estimate unchanged -- never an abort, never NaN.
///
/// Gauge with IMU factors (4 DoF). Gravity is a constant of the world frame,
/// so the IMU factors see the trajectory's roll and pitch: only position and
/// the rotation about gravity are unobservable. A first-node prior built with
/// gravity_gauge_information() holds just those; the graph then rotates the
/// whole trajectory about horizontal axes until it agrees with the factors'
/// gravity, i.e. it estimates the gravity direction. Before any IMU factor
/// that prior leaves roll and pitch free (singular): a caller holds all 6 DoF
/// until the first IMU factor, then relaxes the prior (set_prior_information).
/// A window update holds the older nodes and so cannot turn the trajectory:
/// the gravity direction is (re-)estimated by full solves only (while the
/// graph fits in the window, and after loops).
/// Not thread-safe.

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
#include <semlio/graph/dense_kernels.hpp>
#include <semlio/graph/factors.hpp>
#include <semlio/graph/pose_graph.hpp>
#include <semlio/imu/imu_factor.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// Settings of KeyframeInertialGraph (defaults as PoseGraphConfig where shared).
struct KeyframeInertialGraphConfig {
  int max_iterations = 50;              ///< LM iterations of a full solve
  int window_iterations = 10;           ///< LM iterations of a window update
  std::size_t window_size = 30;         ///< newest nodes free in a window update (>= 1)
  double function_tolerance = 1e-12;    ///< stop when the relative cost decrease is below
  double step_tolerance = 1e-12;        ///< stop when |dx| is below (mixed units)
  double initial_lambda = 1e-6;         ///< LM damping after the first (Gauss-Newton) step, relative to diag(H)
  double huber_delta = 4.0;             ///< robust loops: Huber threshold on sqrt(e^T Omega e)
  double singular_pivot_ratio = 1e-14;  ///< LDL^T pivot / max pivot below this = singular
  double min_variance = 1e-14;          ///< floor of IMU and bias-walk variances (noise-free configs)
  /// Multiplies the IMU and bias-walk information: 1 = the preintegration's
  /// white-noise covariance; < 1 leaves room for what it does not model (an
  /// estimated gravity direction and bias, states taken from a front end).
  double imu_information_scale = 1.0;
  SE3d T_imu_sensor = SE3d();           ///< sensor (lidar) -> IMU extrinsic of between / loop measurements
  ErrorConvention convention{};         ///< between-error convention (between_error.hpp)
};

/// Information (6x6, the [rho; phi] right perturbation of T_world_imu) of a
/// pose prior that holds the position (sigma_m, isotropic) and the rotation
/// about the gravity axis (sigma_yaw_rad) and nothing of roll and pitch: the
/// 4-DoF gauge of an inertial graph (file comment). `R_world_imu` is the
/// prior's rotation, `gravity_world` any nonzero vector along gravity.
/// The prior's residual is ~ the right perturbation: T = T_ref exp(xi) moves
/// the position by R rho (so rho's information is isotropic as the world's)
/// and rotates by phi about BODY axes, i.e. by theta = R phi about world
/// axes. Holding theta along the gravity direction u, theta^T (u u^T /
/// sigma^2) theta, is phi^T (R^T u)(R^T u)^T phi / sigma^2. ValueError on a
/// zero or non-finite gravity or a non-positive sigma.
inline Eigen::Matrix<double, 6, 6> gravity_gauge_information(const SO3d& R_world_imu,
                                                             const Eigen::Vector3d& gravity_world,
                                                             double sigma_m, double sigma_yaw_rad) {
  if (!gravity_world.allFinite() || !(gravity_world.norm() > 0.0)) {
    throw ValueError("gravity_gauge_information: gravity must be finite and nonzero");
  }
  if (!(sigma_m > 0.0) || !(sigma_yaw_rad > 0.0) || !std::isfinite(sigma_m) || !std::isfinite(sigma_yaw_rad)) {
    throw ValueError("gravity_gauge_information: sigmas must be finite and > 0, got " + std::to_string(sigma_m) +
                     " m, " + std::to_string(sigma_yaw_rad) + " rad");
  }
  const Eigen::Vector3d u_imu = R_world_imu.inverse() * gravity_world.normalized();
  Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
  info.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / (sigma_m * sigma_m);
  info.bottomRightCorner<3, 3>() = u_imu * u_imu.transpose() / (sigma_yaw_rad * sigma_yaw_rad);
  return info;
}

/// One node: the IMU's navigation state and bias at a keyframe.
struct KeyframeInertialNode {
  double stamp_s = 0.0;  ///< IMU time [s]
  NavState state;        ///< pose and velocity of the IMU in the world (graph) frame
  ImuBias bias;          ///< IMU bias
};

/// One preintegrated IMU factor of a KeyframeInertialGraph (for diagnostics).
struct KeyframeImuFactor {
  NodeId from = 0;         ///< node i
  NodeId to = 0;           ///< node j
  ImuPreintegration pim;   ///< preintegration over [t_i, t_j] (its gravity, linearisation bias and covariance)
};

/// Keyframe graph over inertial states (see the file comment).
class KeyframeInertialGraph {
 public:
  using Config = KeyframeInertialGraphConfig;
  /// 6x6 information of a pose-part factor ([rho; phi] of the sensor pose).
  using Information6 = Eigen::Matrix<double, 6, 6>;

  /// Empty graph; ConfigError on a bad setting.
  explicit KeyframeInertialGraph(const Config& config = {}) : config_(config) {
    if (config_.max_iterations < 0 || config_.window_iterations < 0)
      throw ConfigError("KeyframeInertialGraphConfig: negative iteration limit");
    if (config_.window_size == 0) throw ConfigError("KeyframeInertialGraphConfig.window_size: must be >= 1");
    if (!(config_.huber_delta > 0.0))
      throw ConfigError("KeyframeInertialGraphConfig.huber_delta: must be > 0, got " +
                        std::to_string(config_.huber_delta));
    if (!(config_.imu_information_scale > 0.0) || !std::isfinite(config_.imu_information_scale))
      throw ConfigError("KeyframeInertialGraphConfig.imu_information_scale: must be finite and > 0, got " +
                        std::to_string(config_.imu_information_scale));
    if (!config_.T_imu_sensor.matrix().allFinite())
      throw ConfigError("KeyframeInertialGraphConfig.T_imu_sensor: not finite");
  }

  /// Adds a node with its initial estimate; returns its id (0, 1, ...).
  NodeId add_node(double stamp_s, const NavState& state, const ImuBias& bias) {
    const auto id = static_cast<NodeId>(nodes_.size());
    nodes_.push_back({stamp_s, state, bias});
    adjacent_.emplace_back();
    local_.push_back(-1);
    return id;
  }

  /// Prior on a whole node (information 15x15, navigation tangent, finite).
  std::size_t add_prior(NodeId node, const NavState& state, const ImuBias& bias, const Matrix15d& information) {
    check_node(node, "add_prior");
    check_finite(information.allFinite(), "add_prior");
    priors_.push_back({node, state, bias, 0.5 * (information + information.transpose())});
    return add_factor(Kind::prior, priors_.size() - 1, node, node);
  }

  /// Replaces the information of prior `factor` (as add_prior returned it;
  /// ValueError for another factor or non-finite information), e.g. to relax
  /// a first node's 6-DoF gauge to 4 DoF once IMU factors exist. The next
  /// update() is full when the node is outside the window.
  void set_prior_information(std::size_t factor, const Matrix15d& information) {
    if (factor >= factors_.size() || factors_[factor].kind != Kind::prior) {
      throw ValueError("KeyframeInertialGraph::set_prior_information: factor " + std::to_string(factor) +
                       " is not a prior");
    }
    if (!information.allFinite()) {
      throw ValueError("KeyframeInertialGraph::set_prior_information: information of factor " +
                       std::to_string(factor) + " is not finite");
    }
    priors_[factors_[factor].index].information = 0.5 * (information + information.transpose());
    if (!in_window(factors_[factor].to)) pending_full_ = true;
  }

  /// Lidar-odometry factor: Z = T_from^-1 T_to of the sensor poses.
  std::size_t add_between(NodeId from, NodeId to, const SE3d& measured, const Information6& information) {
    return add_pose_factor(from, to, measured, information, false, false);
  }

  /// Loop closure between sensor poses (Huber-weighted when robust); the next update() is full.
  std::size_t add_loop(NodeId from, NodeId to, const SE3d& measured, const Information6& information,
                       bool robust = true) {
    return add_pose_factor(from, to, measured, information, true, robust);
  }

  /// Preintegrated IMU factor from node i to node j (i < j; `pim` integrated
  /// over their interval), plus the bias random walk over it.
  std::size_t add_imu(NodeId i, NodeId j, const ImuPreintegration& pim) {
    check_node(i, "add_imu");
    check_node(j, "add_imu");
    if (!(i < j)) throw ValueError("KeyframeInertialGraph::add_imu: node " + std::to_string(i) + " is not before " + std::to_string(j));
    Matrix9d cov = pim.covariance();
    cov.diagonal().array() += config_.min_variance;
    Eigen::Matrix<double, 6, 6> bias_cov = pim.bias_walk_covariance();
    bias_cov.diagonal().array() += config_.min_variance;
    Imu f{{i, j, pim}, config_.imu_information_scale * cov.inverse(), config_.imu_information_scale * bias_cov.inverse()};
    f.information = 0.5 * (f.information + f.information.transpose()).eval();
    check_finite(f.information.allFinite() && f.bias_information.allFinite(), "add_imu");
    imus_.push_back(f);
    return add_factor(Kind::imu, imus_.size() - 1, i, j);
  }

  /// Incremental solve: the newest window, or a warm-started full solve
  /// after a loop (see the file comment).
  GraphSolveReport update() {
    const std::size_t n = nodes_.size();
    if (pending_full_ || n <= config_.window_size) return optimize();
    free_.clear();
    for (std::size_t k = n - config_.window_size; k < n; ++k) free_.push_back(static_cast<NodeId>(k));
    active_.clear();
    for (const NodeId node : free_) active_.insert(active_.end(), adjacent_[node].begin(), adjacent_[node].end());
    std::sort(active_.begin(), active_.end());
    active_.erase(std::unique(active_.begin(), active_.end()), active_.end());
    GraphSolveReport report = solve(config_.window_iterations);
    report.mode = GraphSolveMode::window;
    return report;
  }

  /// Full solve of every node, warm-started from the current estimate.
  GraphSolveReport optimize() {
    free_.clear();
    for (std::size_t k = 0; k < nodes_.size(); ++k) free_.push_back(static_cast<NodeId>(k));
    active_.resize(factors_.size());
    for (std::size_t f = 0; f < factors_.size(); ++f) active_[f] = static_cast<std::uint32_t>(f);
    GraphSolveReport report = solve(config_.max_iterations);
    report.mode = GraphSolveMode::full;
    if (report.ok()) pending_full_ = false;
    return report;
  }

  /// chi2 = sum e^T Omega e over all factors at the current estimate.
  [[nodiscard]] double chi2() const {
    double sum = 0.0;
    for (const FactorRef& f : factors_) sum += squared_error(f, nodes_);
    return sum;
  }

  /// A node's current estimate (ValueError for an unknown id).
  [[nodiscard]] const KeyframeInertialNode& node(NodeId id) const {
    check_node(id, "node");
    return nodes_[id];
  }
  /// Sensor pose T_world_sensor = T_world_imu * T_imu_sensor of a node.
  [[nodiscard]] SE3d pose(NodeId id) const { return node(id).state.pose() * config_.T_imu_sensor; }
  /// Number of nodes.
  [[nodiscard]] std::size_t num_nodes() const noexcept { return nodes_.size(); }
  /// Number of factors (an IMU factor with its bias walk counts once).
  [[nodiscard]] std::size_t num_factors() const noexcept { return factors_.size(); }
  /// Number of IMU factors.
  [[nodiscard]] std::size_t num_imu_factors() const noexcept { return imus_.size(); }
  /// IMU factor k (0 <= k < num_imu_factors(), in the order added; ValueError otherwise).
  [[nodiscard]] const KeyframeImuFactor& imu_factor(std::size_t k) const {
    check_index(k, imus_.size(), "imu_factor", "IMU factors");
    return imus_[k].factor;
  }
  /// Number of pose factors (betweens and loops).
  [[nodiscard]] std::size_t num_pose_factors() const noexcept { return poses_.size(); }
  /// Measured relative pose of pose factor k (in the order added; ValueError otherwise).
  [[nodiscard]] const SE3d& pose_measurement(std::size_t k) const {
    check_index(k, poses_.size(), "pose_measurement", "pose factors");
    return poses_[k].measured;
  }
  /// True when the next update() will be a full solve.
  [[nodiscard]] bool full_solve_pending() const noexcept { return pending_full_ || nodes_.size() <= config_.window_size; }
  /// Settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  enum class Kind : std::uint8_t { prior, pose, imu };
  struct FactorRef {
    Kind kind;
    std::uint32_t index;  // into priors_ / poses_ / imus_
    NodeId from;
    NodeId to;
  };
  struct Prior {
    NodeId node;
    NavState state;
    ImuBias bias;
    Matrix15d information;
  };
  struct PoseFactor {
    SE3d measured;
    Information6 information;
    bool robust;
  };
  struct Imu {
    KeyframeImuFactor factor;
    Matrix9d information;
    Eigen::Matrix<double, 6, 6> bias_information;
  };
  using Handles = std::array<std::array<int, 15>, 3>;

  void check_node(NodeId node, const char* what) const {
    if (node >= nodes_.size()) {
      throw ValueError(std::string("KeyframeInertialGraph::") + what + ": node " + std::to_string(node) +
                       " does not exist (" + std::to_string(nodes_.size()) + " nodes)");
    }
  }
  static void check_index(std::size_t k, std::size_t n, const char* accessor, const char* what) {
    if (k >= n) {
      throw ValueError(std::string("KeyframeInertialGraph::") + accessor + ": " + std::to_string(k) + " of " +
                       std::to_string(n) + " " + what);
    }
  }
  void check_finite(bool finite, const char* what) const {
    if (!finite) {
      throw ValueError(std::string("KeyframeInertialGraph::") + what + ": information of factor " +
                       std::to_string(factors_.size()) + " is not finite");
    }
  }

  [[nodiscard]] bool in_window(NodeId node) const {
    return nodes_.size() <= config_.window_size || node >= nodes_.size() - config_.window_size;
  }

  std::size_t add_pose_factor(NodeId from, NodeId to, const SE3d& measured, const Information6& information,
                              bool loop, bool robust_loop) {
    check_node(from, "add_between");
    check_node(to, "add_between");
    if (from == to) throw ValueError("KeyframeInertialGraph: between/loop factor from node " + std::to_string(from) + " to itself");
    check_finite(information.allFinite() && measured.matrix().allFinite(), "add_between");
    poses_.push_back({measured, 0.5 * (information + information.transpose()), robust_loop});
    if (loop) pending_full_ = true;
    return add_factor(Kind::pose, poses_.size() - 1, from, to);
  }

  std::size_t add_factor(Kind kind, std::size_t index, NodeId from, NodeId to) {
    const auto f = static_cast<std::uint32_t>(factors_.size());
    factors_.push_back({kind, static_cast<std::uint32_t>(index), from, to});
    adjacent_[to].push_back(f);
    if (from != to) adjacent_[from].push_back(f);
    if (!in_window(from) || !in_window(to)) pending_full_ = true;
    return f;
  }

  // Whitened pieces of one factor: residual r (R), Jacobians (R x 15) w.r.t.
  // the navigation tangents of `from` and `to`, weight W (R x R).
  template <int R>
  struct Linear {
    Eigen::Matrix<double, R, 1> r;
    Eigen::Matrix<double, R, 15> J_from;
    Eigen::Matrix<double, R, 15> J_to;
    Eigen::Matrix<double, R, R> W;
  };

  // Pose-part error between sensor poses; its Jacobians w.r.t. the IMU
  // tangents: T_sensor exp(xi_s) = T_imu exp(xi) T_imu_sensor gives
  // xi_s = Ad(T_sensor_imu) xi.
  Linear<6> pose_linear(const PoseFactor& p, const KeyframeInertialNode& a, const KeyframeInertialNode& b) const {
    Linear<6> l;
    Eigen::Matrix<double, 6, 6> Ja;
    Eigen::Matrix<double, 6, 6> Jb;
    const SE3d& X = config_.T_imu_sensor;
    l.r = between_error(p.measured, a.state.pose() * X, b.state.pose() * X, config_.convention, &Ja, &Jb);
    const Eigen::Matrix<double, 6, 6> Ad = X.inverse().adjoint();
    l.J_from.setZero();
    l.J_to.setZero();
    l.J_from.leftCols<6>() = Ja * Ad;
    l.J_to.leftCols<6>() = Jb * Ad;
    l.W = p.information;
    return l;
  }

  [[nodiscard]] double squared_error(const FactorRef& f, const std::vector<KeyframeInertialNode>& x) const {
    switch (f.kind) {
      case Kind::prior: {
        const Prior& p = priors_[f.index];
        const Vector15d d = nav_difference(x[f.to].state, x[f.to].bias, p.state, p.bias);
        return d.dot(p.information * d);
      }
      case Kind::pose: {
        const PoseFactor& p = poses_[f.index];
        const SE3d& X = config_.T_imu_sensor;
        const Eigen::Matrix<double, 6, 1> e =
            between_error(p.measured, x[f.from].state.pose() * X, x[f.to].state.pose() * X, config_.convention);
        return e.dot(p.information * e);
      }
      case Kind::imu: {
        const Imu& m = imus_[f.index];
        const Vector9d r = imu_factor_error(m.factor.pim, x[f.from].state, x[f.from].bias, x[f.to].state);
        const Eigen::Matrix<double, 6, 1> rb = bias_walk_error(x[f.from].bias, x[f.to].bias);
        return r.dot(m.information * r) + rb.dot(m.bias_information * rb);
      }
    }
    return 0.0;
  }

  [[nodiscard]] bool is_robust(const FactorRef& f) const { return f.kind == Kind::pose && poses_[f.index].robust; }

  // Robust cost and raw chi2 of the active factors at `x`; false when not finite.
  bool evaluate(const std::vector<KeyframeInertialNode>& x, double& cost, double& chi2) const {
    cost = 0.0;
    chi2 = 0.0;
    for (const std::uint32_t fi : active_) {
      const double s = squared_error(factors_[fi], x);
      cost += is_robust(factors_[fi]) ? huber_cost(s, config_.huber_delta) : s;
      chi2 += s;
    }
    return std::isfinite(cost) && std::isfinite(chi2);
  }

  void build_pattern() {
    system_.begin_pattern(free_.size());
    for (const std::uint32_t fi : active_) {
      const FactorRef& f = factors_[fi];
      const int la = local_[f.from];
      const int lb = local_[f.to];
      if (f.from != f.to && la >= 0 && lb >= 0) system_.declare(static_cast<std::size_t>(la), static_cast<std::size_t>(lb));
    }
    system_.end_pattern();
    handles_.resize(active_.size());
    std::array<int, 15> none{};
    none.fill(-1);
    for (std::size_t k = 0; k < active_.size(); ++k) {
      const FactorRef& f = factors_[active_[k]];
      const int la = f.from == f.to ? -1 : local_[f.from];
      const int lb = local_[f.to];
      const auto u = [](int l) { return static_cast<std::size_t>(l); };
      handles_[k][0] = la >= 0 ? system_.handle(u(la), u(la)) : none;
      handles_[k][1] = lb >= 0 ? system_.handle(u(lb), u(lb)) : none;
      handles_[k][2] = la >= 0 && lb >= 0 ? system_.handle(u(std::max(la, lb)), u(std::min(la, lb))) : none;
    }
  }

  // Adds one factor's J^T W J blocks and J^T W r (IRLS weight w) to the
  // system. The products go through graph/dense_kernels.hpp: as fixed-size
  // Eigen expressions (15x15 from R x 15, three R) each was its own GEMM
  // instantiation, ~3 s of GCC 12 front end in every TU that includes this
  // header.
  template <int R>
  void accumulate(const Linear<R>& l, double w, int la, int lb, const Handles& h) {
    using Block = Eigen::Matrix<double, 15, 15>;
    Eigen::VectorXd& g = system_.g();
    Eigen::Matrix<double, R, 1> Wr;
    detail::set_a_b(Wr, l.W, l.r);
    Wr *= w;
    Block block;
    const auto add = [&](const std::array<int, 15>& handle, const Eigen::Matrix<double, R, 15>& A,
                         const Eigen::Matrix<double, R, 15>& B) {
      block.setZero();
      detail::add_at_w_b(block, A, l.W, B, w);
      system_.add(handle, block);
    };
    if (la >= 0) {
      add(h[0], l.J_from, l.J_from);
      detail::add_at_v(g.segment<15>(la * 15), l.J_from, Wr);
    }
    if (lb >= 0) {
      add(h[1], l.J_to, l.J_to);
      detail::add_at_v(g.segment<15>(lb * 15), l.J_to, Wr);
      // Lower block: row block max(la, lb), column block min(la, lb).
      if (la >= 0) {
        if (lb > la) {
          add(h[2], l.J_to, l.J_from);
        } else {
          add(h[2], l.J_from, l.J_to);
        }
      }
    }
  }

  // Builds H and g at nodes_ (robust factors IRLS-weighted); false on non-finite.
  bool linearize() {
    system_.zero();
    for (std::size_t k = 0; k < active_.size(); ++k) {
      const FactorRef& f = factors_[active_[k]];
      const int la = f.from == f.to ? -1 : local_[f.from];
      const int lb = local_[f.to];
      const KeyframeInertialNode& a = nodes_[f.from];
      const KeyframeInertialNode& b = nodes_[f.to];
      if (f.kind == Kind::prior) {
        const Prior& p = priors_[f.index];
        Linear<15> l;
        l.r = nav_difference(b.state, b.bias, p.state, p.bias, &l.J_to);
        l.J_from.setZero();
        l.W = p.information;
        if (!l.r.allFinite() || !l.J_to.allFinite()) return false;
        accumulate(l, 1.0, -1, lb, handles_[k]);
      } else if (f.kind == Kind::pose) {
        const PoseFactor& p = poses_[f.index];
        const Linear<6> l = pose_linear(p, a, b);
        if (!l.r.allFinite() || !l.J_from.allFinite() || !l.J_to.allFinite()) return false;
        const double w = p.robust ? huber_weight(l.r.dot(p.information * l.r), config_.huber_delta) : 1.0;
        accumulate(l, w, la, lb, handles_[k]);
      } else {
        const Imu& m = imus_[f.index];
        Linear<9> l;
        l.r = imu_factor_error(m.factor.pim, a.state, a.bias, b.state, &l.J_from, &l.J_to);
        l.W = m.information;
        Linear<6> lb_walk;
        Matrix6x15d Bi;
        Matrix6x15d Bj;
        lb_walk.r = bias_walk_error(a.bias, b.bias, &Bi, &Bj);
        lb_walk.J_from = Bi;
        lb_walk.J_to = Bj;
        lb_walk.W = m.bias_information;
        if (!l.r.allFinite() || !l.J_from.allFinite() || !l.J_to.allFinite()) return false;
        accumulate(l, 1.0, la, lb, handles_[k]);
        accumulate(lb_walk, 1.0, la, lb, handles_[k]);
      }
    }
    return system_.g().allFinite();
  }

  GraphSolveReport solve(int max_iterations) {
    GraphSolveReport report;
    report.free_nodes = free_.size();
    report.active_factors = active_.size();
    for (std::size_t l = 0; l < free_.size(); ++l) local_[free_[l]] = static_cast<int>(l);
    run(max_iterations, report);
    for (const NodeId node : free_) local_[node] = -1;
    return report;
  }

  // Levenberg-Marquardt with accept / reject on the actual cost (the first
  // step is Gauss-Newton and checks the pivots: singular -> status).
  void run(int max_iterations, GraphSolveReport& report) {
    double cost = 0.0;
    double chi2 = 0.0;
    if (!evaluate(nodes_, cost, chi2)) {
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
    double lambda = 0.0;
    bool relinearize = true;
    Eigen::VectorXd dx;
    report.status = GraphSolveStatus::max_iterations;
    for (int it = 0; it < max_iterations; ++it) {
      if (relinearize && !linearize()) {
        report.status = GraphSolveStatus::non_finite;
        return;
      }
      relinearize = false;
      Eigen::Index bad_row = -1;
      const detail::FactorStatus fs = system_.factorize(lambda, config_.singular_pivot_ratio, &bad_row);
      if (fs == detail::FactorStatus::singular) {
        report.status = GraphSolveStatus::singular;
        if (bad_row >= 0) report.degenerate_node = static_cast<long>(free_[static_cast<std::size_t>(bad_row / 15)]);
        return;
      }
      ++report.iterations;
      if (fs == detail::FactorStatus::ok) system_.solve(dx);
      if (fs == detail::FactorStatus::failed || !dx.allFinite()) {
        lambda = std::max(lambda * 10.0, config_.initial_lambda);
        if (lambda > 1e12) break;
        continue;
      }
      trial_ = nodes_;
      for (std::size_t l = 0; l < free_.size(); ++l) {
        KeyframeInertialNode& x = trial_[free_[l]];
        retract(x.state, x.bias, dx.segment<15>(static_cast<Eigen::Index>(l) * 15));
      }
      double new_cost = 0.0;
      double new_chi2 = 0.0;
      if (evaluate(trial_, new_cost, new_chi2) && new_cost <= cost) {
        const double rel = (cost - new_cost) / std::max(cost, 1e-300);
        nodes_.swap(trial_);
        cost = new_cost;
        report.final_chi2 = new_chi2;
        relinearize = true;
        lambda = lambda == 0.0 ? 0.0 : std::max(lambda * 0.1, 1e-12);
        if (rel < config_.function_tolerance || dx.norm() < config_.step_tolerance || cost == 0.0) {
          report.status = GraphSolveStatus::converged;
          break;
        }
      } else {
        lambda = lambda == 0.0 ? config_.initial_lambda : lambda * 10.0;
        if (lambda > 1e12) {
          report.status = GraphSolveStatus::converged;  // no decrease left at numerical precision
          break;
        }
      }
    }
  }

  Config config_;
  std::vector<KeyframeInertialNode> nodes_;
  std::vector<FactorRef> factors_;
  std::vector<Prior> priors_;
  std::vector<PoseFactor> poses_;
  std::vector<Imu> imus_;
  std::vector<std::vector<std::uint32_t>> adjacent_;  // factors per node
  bool pending_full_ = false;

  // Solver scratch, reused between solves.
  std::vector<int> local_;  // node -> unknown index, -1 when held
  std::vector<NodeId> free_;
  std::vector<std::uint32_t> active_;
  std::vector<KeyframeInertialNode> trial_;
  std::vector<Handles> handles_;
  detail::BlockSystem<15> system_;
};

}  // namespace semlio
