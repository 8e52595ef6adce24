#pragma once
/// \file
/// Smooth vehicle trajectories for the simulator: a route polyline becomes a
/// curvature-continuous 3D path (corners rounded, then a uniform quintic
/// B-spline through points resampled at equal arclength), and a speed profile
/// built from smooth-step transitions between constant-speed plateaus
/// (slowing in curves to a lateral-acceleration limit, accelerating and
/// braking within limits, optional stops).
///
/// Smoothness: the path is C4 in its parameter and the time law C3, so the
/// position is C3 in time (C2 is what the IMU model needs) and the angular
/// velocity C1. Orientation: yaw follows the path tangent, pitch the slope
/// (nose up uphill), roll is body roll proportional to the lateral
/// acceleration (outward in turns). All derivatives are exact derivatives of
/// the pose function (truncated Taylor arithmetic), so integrating them
/// reproduces pose(t).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

namespace semlio::sim {

/// Motion limits and shape of a simulated drive. Defaults: urban driving at
/// ~40 km/h; for a highway use cruise_speed_mps = 25 (90 km/h).
struct TrajectoryConfig {
  double cruise_speed_mps = 11.0;          ///< speed on straights [m/s] (11 m/s = 39.6 km/h)
  double max_lateral_accel_mps2 = 2.5;     ///< speed in curves is limited to sqrt(a_lat / curvature)
  double max_accel_mps2 = 1.5;             ///< peak longitudinal acceleration [m/s^2]
  double max_decel_mps2 = 2.0;             ///< peak braking deceleration [m/s^2]
  double max_jerk_mps3 = 1.0;              ///< peak longitudinal jerk [m/s^3] (comfortable driving)
  double turn_radius_m = 10.0;             ///< route corners are rounded with this radius (urban 90 deg turns)
  double min_blend_length_m = 10.0;        ///< gentle corners / grade changes blend over at least this length each side
  double control_spacing_m = 1.0;          ///< B-spline control point spacing along the path [m]
  double dense_route_segment_m = 10.0;     ///< routes whose median segment is shorter are sampled curves: smoothed over 2 segments
  double roll_per_lateral_accel = 0.006;   ///< body roll [rad] per m/s^2 lateral acceleration (0.34 deg per m/s^2, ~3.4 deg/g)
  std::vector<double> stop_at_arclength_m; ///< stop (speed 0) at these arclengths along the path [m]
  double stop_duration_s = 5.0;            ///< how long each stop lasts [s]
  bool start_at_rest = true;               ///< start with speed 0 (else at the cruise/curve speed)
  bool end_at_rest = true;                 ///< end with speed 0 (else at the cruise/curve speed)
};

/// Everything about the vehicle at one time, in one evaluation.
struct KinematicState {
  SE3d T_world_body;                        ///< pose: body x forward, y left, z up; world z up
  Eigen::Vector3d velocity_world_mps;       ///< d/dt of the body origin, world frame
  Eigen::Vector3d acceleration_world_mps2;  ///< d2/dt2 of the body origin, world frame
  Eigen::Vector3d angular_velocity_body_radps;       ///< omega with dR/dt = R hat(omega)
  Eigen::Vector3d angular_acceleration_body_radps2;  ///< d/dt of omega (body frame)
};

namespace detail {

/// Truncated Taylor series of order N in time: c[k] = f^(k)(t0) / k!.
/// Arithmetic on these is exact up to order N (coefficient k of a result
/// depends only on coefficients <= k of the operands).
template <int N>
struct Jet {
  std::array<double, N + 1> c{};

  /// k-th time derivative.
  [[nodiscard]] double derivative(int k) const {
    double f = 1.0;
    for (int i = 2; i <= k; ++i) f *= static_cast<double>(i);
    return c[static_cast<std::size_t>(k)] * f;
  }
};

template <int N>
Jet<N> operator+(const Jet<N>& a, const Jet<N>& b) {
  Jet<N> r;
  for (std::size_t k = 0; k <= N; ++k) r.c[k] = a.c[k] + b.c[k];
  return r;
}
template <int N>
Jet<N> operator-(const Jet<N>& a, const Jet<N>& b) {
  Jet<N> r;
  for (std::size_t k = 0; k <= N; ++k) r.c[k] = a.c[k] - b.c[k];
  return r;
}
template <int N>
Jet<N> operator-(const Jet<N>& a) {
  Jet<N> r;
  for (std::size_t k = 0; k <= N; ++k) r.c[k] = -a.c[k];
  return r;
}
template <int N>
Jet<N> operator*(const Jet<N>& a, const Jet<N>& b) {
  Jet<N> r;
  for (std::size_t k = 0; k <= N; ++k) {
    double s = 0.0;
    for (std::size_t i = 0; i <= k; ++i) s += a.c[i] * b.c[k - i];
    r.c[k] = s;
  }
  return r;
}
template <int N>
Jet<N> operator*(double s, const Jet<N>& a) {
  Jet<N> r;
  for (std::size_t k = 0; k <= N; ++k) r.c[k] = s * a.c[k];
  return r;
}

/// f(x(t)) from g[k] = f^(k)(x0) / k!, k = 0..N (Horner in x - x0).
template <int N>
Jet<N> compose(const std::array<double, N + 1>& g, const Jet<N>& x) {
  Jet<N> delta = x;
  delta.c[0] = 0.0;
  Jet<N> r;
  r.c[0] = g[N];
  for (int k = N - 1; k >= 0; --k) {
    r = r * delta;
    r.c[0] += g[static_cast<std::size_t>(k)];
  }
  return r;
}

template <int N>
Jet<N> sin(const Jet<N>& x) {
  std::array<double, N + 1> g{};
  const double s = std::sin(x.c[0]);
  const double co = std::cos(x.c[0]);
  double fact = 1.0;
  for (int k = 0; k <= N; ++k) {
    if (k > 0) fact *= static_cast<double>(k);
    const double d = (k % 4 == 0) ? s : (k % 4 == 1) ? co : (k % 4 == 2) ? -s : -co;
    g[static_cast<std::size_t>(k)] = d / fact;
  }
  return compose<N>(g, x);
}

template <int N>
Jet<N> cos(const Jet<N>& x) {
  std::array<double, N + 1> g{};
  const double s = std::sin(x.c[0]);
  const double co = std::cos(x.c[0]);
  double fact = 1.0;
  for (int k = 0; k <= N; ++k) {
    if (k > 0) fact *= static_cast<double>(k);
    const double d = (k % 4 == 0) ? co : (k % 4 == 1) ? -s : (k % 4 == 2) ? -co : s;
    g[static_cast<std::size_t>(k)] = d / fact;
  }
  return compose<N>(g, x);
}

/// 1 / x (x0 != 0).
template <int N>
Jet<N> inv(const Jet<N>& x) {
  std::array<double, N + 1> g{};
  const double r = 1.0 / x.c[0];
  double p = r;
  for (int k = 0; k <= N; ++k) {
    g[static_cast<std::size_t>(k)] = (k % 2 == 0) ? p : -p;
    p *= r;
  }
  return compose<N>(g, x);
}

/// sqrt(x) (x0 > 0).
template <int N>
Jet<N> sqrt(const Jet<N>& x) {
  std::array<double, N + 1> g{};
  const double x0 = x.c[0];
  // f^(k)/k! = binom(1/2, k) x0^(1/2 - k)
  double binom = 1.0;
  double p = std::sqrt(x0);
  for (int k = 0; k <= N; ++k) {
    g[static_cast<std::size_t>(k)] = binom * p;
    binom *= (0.5 - static_cast<double>(k)) / static_cast<double>(k + 1);
    p /= x0;
  }
  return compose<N>(g, x);
}

/// Time derivative; the top coefficient is unknown and set to 0 (harmless:
/// results built from it are only used to order N-1, e.g. by integrate()).
template <int N>
Jet<N> derivative(const Jet<N>& x) {
  Jet<N> r;
  for (std::size_t k = 0; k < N; ++k) r.c[k] = static_cast<double>(k + 1) * x.c[k + 1];
  return r;
}

/// atan2(y, x) as a jet: value from std::atan2, higher orders by integrating
/// d/dt atan2 = (x y' - y x') / (x^2 + y^2).
template <int N>
Jet<N> atan2(const Jet<N>& y, const Jet<N>& x) {
  const Jet<N> rate = (x * derivative(y) - y * derivative(x)) * inv(x * x + y * y);
  Jet<N> r;
  r.c[0] = std::atan2(y.c[0], x.c[0]);
  for (std::size_t k = 0; k < N; ++k) r.c[k + 1] = rate.c[k] / static_cast<double>(k + 1);
  return r;
}

/// Polynomial coefficients (in the local parameter x in [0,1)) of the six
/// uniform quintic B-spline blending functions: weight of control point i+j is
/// sum_k M[j][k] x^k. From the cardinal B-spline
/// N(y) = (1/120) sum_m (-1)^m C(6,m) (y - m)_+^5 at y = x + 5 - j.
inline constexpr std::array<std::array<double, 6>, 6> quintic_basis() {
  constexpr std::array<double, 7> c6{1, 6, 15, 20, 15, 6, 1};
  constexpr std::array<double, 6> c5{1, 5, 10, 10, 5, 1};
  std::array<std::array<double, 6>, 6> M{};
  for (int j = 0; j < 6; ++j) {
    for (int m = 0; m <= 5 - j; ++m) {
      const double a = static_cast<double>(5 - j - m);
      const double sign = (m % 2 == 0) ? 1.0 : -1.0;
      for (int k = 0; k <= 5; ++k) {
        double ap = 1.0;
        for (int e = 0; e < 5 - k; ++e) ap *= a;
        M[static_cast<std::size_t>(j)][static_cast<std::size_t>(k)] +=
            sign * c6[static_cast<std::size_t>(m)] * c5[static_cast<std::size_t>(k)] * ap / 120.0;
      }
    }
  }
  return M;
}

/// Uniform quintic B-spline over control points, parameterised by nominal
/// arclength sigma = spacing * (u - 1) so that sigma = k * spacing sits at
/// resampled point k (exactly on straights, within (spacing*curvature)^2/6 in
/// curves).
class QuinticPath {
 public:
  QuinticPath() = default;

  /// Points q_k at sigma = k * spacing (at least 2), equally spaced along the route.
  QuinticPath(const std::vector<Eigen::Vector3d>& q, double spacing_m) : h_(spacing_m) {
    const std::size_t n = q.size();
    ctrl_.reserve(n + 6);
    // Padding: quadratic extrapolation through the three end points (linear
    // with two), so a path that starts in a curve keeps its curvature.
    auto extrapolate = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double m) {
      if (n < 3) return Eigen::Vector3d(a + m * (a - b));
      return Eigen::Vector3d(a * (m + 1.0) * (m + 2.0) / 2.0 - b * m * (m + 2.0) + c * m * (m + 1.0) / 2.0);
    };
    const Eigen::Vector3d& q2 = q[std::min<std::size_t>(2, n - 1)];
    const Eigen::Vector3d& r2 = q[n - 1 - std::min<std::size_t>(2, n - 1)];
    for (int m = 3; m >= 1; --m) ctrl_.push_back(extrapolate(q[0], q[1], q2, static_cast<double>(m)));
    for (const auto& p : q) ctrl_.push_back(p);
    for (int m = 1; m <= 3; ++m) ctrl_.push_back(extrapolate(q[n - 1], q[n - 2], r2, static_cast<double>(m)));
    segments_ = n;  // valid segment indices 0..n (u in [1, n])
    length_m_ = static_cast<double>(n - 1) * h_;
  }

  /// Nominal arclength of the whole path [m].
  [[nodiscard]] double length_m() const { return length_m_; }

  /// Derivatives 0..D (D <= 5) of the position with respect to sigma.
  template <int D>
  void evaluate(double sigma_m, std::array<Eigen::Vector3d, D + 1>& out) const {
    static constexpr std::array<std::array<double, 6>, 6> M = quintic_basis();
    const double u = std::clamp(sigma_m, 0.0, length_m_) / h_ + 1.0;
    const auto i = std::min(static_cast<std::size_t>(std::floor(u)), segments_);
    const double x = u - static_cast<double>(i);
    std::array<double, 6> xp{};
    xp[0] = 1.0;
    for (std::size_t k = 1; k < 6; ++k) xp[k] = xp[k - 1] * x;
    double hpow = 1.0;
    for (int d = 0; d <= D; ++d) {
      Eigen::Vector3d acc = Eigen::Vector3d::Zero();
      for (std::size_t j = 0; j < 6; ++j) {
        double w = 0.0;
        for (int k = d; k <= 5; ++k) {
          double ff = 1.0;  // k! / (k - d)!
          for (int e = 0; e < d; ++e) ff *= static_cast<double>(k - e);
          w += M[j][static_cast<std::size_t>(k)] * ff * xp[static_cast<std::size_t>(k - d)];
        }
        acc += w * ctrl_[i + j];
      }
      out[static_cast<std::size_t>(d)] = acc / hpow;
      hpow *= h_;
    }
  }

 private:
  std::vector<Eigen::Vector3d> ctrl_;
  std::size_t segments_ = 0;
  double h_ = 1.0;
  double length_m_ = 0.0;
};

/// Moving average with half-width r samples; the window shrinks
/// symmetrically near the ends so the end points stay fixed.
inline std::vector<Eigen::Vector3d> box_filter(const std::vector<Eigen::Vector3d>& q, std::size_t r) {
  const std::size_t n = q.size();
  std::vector<Eigen::Vector3d> prefix(n + 1, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + q[i];
  std::vector<Eigen::Vector3d> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t rk = std::min({r, k, n - 1 - k});
    out[k] = (prefix[k + rk + 1] - prefix[k - rk]) / static_cast<double>(2 * rk + 1);
  }
  return out;
}

/// Heading at fraction f of a raised-cosine corner turning by alpha:
/// theta = alpha (f - sin(2 pi f) / (2 pi)).
inline double corner_heading(double alpha, double f) {
  return alpha * (f - std::sin(2.0 * std::numbers::pi * f) / (2.0 * std::numbers::pi));
}

/// Distance from the corner vertex to either end of a raised-cosine corner of
/// unit length turning by alpha (symmetric, so both tangents are equal).
inline double corner_tangent_length(double alpha) {
  constexpr int kSteps = 2000;
  double y = 0.0;
  for (int k = 0; k < kSteps; ++k) {
    y += std::sin(corner_heading(alpha, (static_cast<double>(k) + 0.5) / kSteps)) / kSteps;
  }
  return y / std::sin(alpha);
}

/// One piece of the time law: speed moves from v0 to v1 along the quintic
/// smooth step h(x) = 10x^3 - 15x^4 + 6x^5 (accel and jerk vanish at both
/// ends, so pieces join C3); constant speed (or a dwell) when v0 == v1.
struct TimePiece {
  double t0_s;
  double duration_s;
  double s0_m;
  double v0_mps;
  double v1_mps;
};

/// Peak acceleration of the smooth step over its mean: max h' = 30/16.
inline constexpr double kSmoothStepPeak = 1.875;

/// Derivatives 0..4 of sigma(t) inside one piece at local time tau.
inline std::array<double, 5> time_law(const TimePiece& p, double tau) {
  std::array<double, 5> s{};
  const double dv = p.v1_mps - p.v0_mps;
  if (dv == 0.0 || p.duration_s <= 0.0) {
    s[0] = p.s0_m + p.v0_mps * tau;
    s[1] = p.v0_mps;
    return s;
  }
  const double T = p.duration_s;
  const double x = std::clamp(tau / T, 0.0, 1.0);
  const double x2 = x * x;
  const double x3 = x2 * x;
  const double H = x2 * x2 * (2.5 - 3.0 * x + x2);
  const double h = x3 * (10.0 - 15.0 * x + 6.0 * x2);
  const double h1 = 30.0 * x2 * (1.0 - x) * (1.0 - x);
  const double h2 = 60.0 * x - 180.0 * x2 + 120.0 * x3;
  const double h3 = 60.0 - 360.0 * x + 360.0 * x2;
  s[0] = p.s0_m + p.v0_mps * tau + dv * T * H;
  s[1] = p.v0_mps + dv * h;
  s[2] = dv * h1 / T;
  s[3] = dv * h2 / (T * T);
  s[4] = dv * h3 / (T * T * T);
  return s;
}

/// A stretch of path driven at constant speed v (a point when a == b).
struct Plateau {
  double a;        ///< start arclength [m]
  double b;        ///< end arclength [m]
  double v;        ///< speed [m/s]
  double dwell_s;  ///< time standing still at b (stops) [s]
  int zone;  ///< curve zone it lies in, -1 = none
};

/// Peak jerk of the smooth step: max |h''| = 10 / sqrt(3).
inline constexpr double kSmoothStepJerk = 5.773502691896258;

/// Duration of a smooth-step speed change by dv at peak acceleration `rate`
/// and peak jerk `jerk`.
inline double transition_duration(double dv, double rate, double jerk) {
  const double a = std::abs(dv);
  return std::max(kSmoothStepPeak * a / rate, std::sqrt(kSmoothStepJerk * a / jerk));
}

/// Distance a smooth-step speed change v0 -> v1 covers.
inline double transition_distance(double v0, double v1, double rate, double jerk) {
  return 0.5 * (v0 + v1) * transition_duration(v1 - v0, rate, jerk);
}

/// Largest v in [lo, hi] with dist(v) <= limit, for dist increasing in v
/// (bisection; returns lo when even lo does not fit).
template <typename Dist>
double largest_fitting(double lo, double hi, double limit, Dist dist) {
  if (dist(hi) <= limit) return hi;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (dist(mid) <= limit) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return lo;
}

}  // namespace detail

/// A smooth drive along a route. Immutable after construction; all queries are
/// const and thread-safe. Times outside [0, duration_s()] are clamped (the
/// vehicle holds its end pose). A default-constructed Trajectory stands still
/// at the identity pose with duration 0. Cost: pose() ~1 us, state() ~5 us; for
/// per-point motion distortion evaluate per column and interpolate.
class Trajectory {
 public:
  using Config = TrajectoryConfig;

  /// Builds the drive along `route_points_world` (at least 2 distinct points,
  /// world frame, z up): sparse corner points (each corner rounded, see
  /// turn_radius_m) or a densely sampled curve (smoothed, see
  /// dense_route_segment_m). The path starts at the first point; it ends
  /// within ~spacing^2 * curvature of the last. A hairpin (turn near 180
  /// degrees at one vertex) is turned half-way down its segments: give
  /// U-turns as two corners. Throws ConfigError for limits <= 0, ValueError
  /// for non-finite or too few distinct points.
  static Trajectory through(const std::vector<Eigen::Vector3d>& route_points_world,
                            const TrajectoryConfig& config) {
    validate(config);
    Trajectory tr;
    tr.config_ = config;
    tr.build_path(route_points_world);
    tr.build_time_law();
    return tr;
  }

  /// Total duration of the drive [s].
  [[nodiscard]] double duration_s() const { return duration_s_; }
  /// Length of the path [m] (nominal arclength, the stop positions' unit).
  [[nodiscard]] double length_m() const { return path_.length_m(); }

  /// T_world_body at time t: body x forward, y left, z up.
  [[nodiscard]] SE3d pose(double t_s) const {
    const auto j = eval<0>(t_s);
    return SE3d(rotation(j.yaw.c[0], j.pitch.c[0], j.roll.c[0]),
                Eigen::Vector3d(j.p[0].c[0], j.p[1].c[0], j.p[2].c[0]));
  }
  /// Velocity of the body origin in the world frame [m/s].
  [[nodiscard]] Eigen::Vector3d velocity_world_mps(double t_s) const {
    const auto j = eval<1>(t_s);
    return {j.p[0].c[1], j.p[1].c[1], j.p[2].c[1]};
  }
  /// Acceleration of the body origin in the world frame [m/s^2] (no gravity).
  [[nodiscard]] Eigen::Vector3d acceleration_world_mps2(double t_s) const {
    const auto j = eval<2>(t_s);
    return {2.0 * j.p[0].c[2], 2.0 * j.p[1].c[2], 2.0 * j.p[2].c[2]};
  }
  /// Angular velocity in the body frame [rad/s]: dR/dt = R hat(omega).
  [[nodiscard]] Eigen::Vector3d angular_velocity_body_radps(double t_s) const {
    const auto w = omega(eval<1>(t_s));
    return {w[0].c[0], w[1].c[0], w[2].c[0]};
  }
  /// Time derivative of angular_velocity_body_radps [rad/s^2].
  [[nodiscard]] Eigen::Vector3d angular_acceleration_body_radps2(double t_s) const {
    const auto w = omega(eval<2>(t_s));
    return {w[0].c[1], w[1].c[1], w[2].c[1]};
  }
  /// Pose and all derivatives at once (one path evaluation).
  [[nodiscard]] KinematicState state(double t_s) const {
    const auto j = eval<2>(t_s);
    const auto w = omega(j);
    KinematicState s;
    s.T_world_body = SE3d(rotation(j.yaw.c[0], j.pitch.c[0], j.roll.c[0]),
                          Eigen::Vector3d(j.p[0].c[0], j.p[1].c[0], j.p[2].c[0]));
    s.velocity_world_mps = {j.p[0].c[1], j.p[1].c[1], j.p[2].c[1]};
    s.acceleration_world_mps2 = {2.0 * j.p[0].c[2], 2.0 * j.p[1].c[2], 2.0 * j.p[2].c[2]};
    s.angular_velocity_body_radps = {w[0].c[0], w[1].c[0], w[2].c[0]};
    s.angular_acceleration_body_radps2 = {w[0].c[1], w[1].c[1], w[2].c[1]};
    return s;
  }
  /// Distance driven along the path at time t [m].
  [[nodiscard]] double arclength_m(double t_s) const { return sigma(t_s)[0]; }
  /// Planned speed along the path at time t [m/s] (equals |velocity| on
  /// straights, within ~1% in tight turns).
  [[nodiscard]] double planned_speed_mps(double t_s) const { return sigma(t_s)[1]; }
  /// Position on the path at a nominal arclength [m] (world frame).
  [[nodiscard]] Eigen::Vector3d position_at_arclength(double s_m) const {
    std::array<Eigen::Vector3d, 1> d;
    path_.evaluate<0>(s_m, d);
    return d[0];
  }
  /// The configuration this drive was built with.
  [[nodiscard]] const TrajectoryConfig& config() const { return config_; }

 private:
  template <int N>
  struct Jets {
    std::array<detail::Jet<N>, 3> p;
    detail::Jet<N> yaw, pitch, roll;
  };

  static void validate(const TrajectoryConfig& c) {
    auto positive = [](double v, const char* field) {
      if (!(v > 0.0) || !std::isfinite(v)) {
        throw ConfigError(std::string("TrajectoryConfig.") + field + " must be > 0, got " + std::to_string(v));
      }
    };
    positive(c.cruise_speed_mps, "cruise_speed_mps");
    positive(c.max_lateral_accel_mps2, "max_lateral_accel_mps2");
    positive(c.max_accel_mps2, "max_accel_mps2");
    positive(c.max_decel_mps2, "max_decel_mps2");
    positive(c.max_jerk_mps3, "max_jerk_mps3");
    positive(c.turn_radius_m, "turn_radius_m");
    positive(c.control_spacing_m, "control_spacing_m");
    if (!(c.dense_route_segment_m >= 0.0)) {
      throw ConfigError("TrajectoryConfig.dense_route_segment_m must be >= 0, got " + std::to_string(c.dense_route_segment_m));
    }
    if (!(c.min_blend_length_m >= 0.0)) {
      throw ConfigError("TrajectoryConfig.min_blend_length_m must be >= 0, got " + std::to_string(c.min_blend_length_m));
    }
    if (!(c.stop_duration_s >= 0.0)) {
      throw ConfigError("TrajectoryConfig.stop_duration_s must be >= 0, got " + std::to_string(c.stop_duration_s));
    }
    if (!std::isfinite(c.roll_per_lateral_accel)) {
      throw ConfigError("TrajectoryConfig.roll_per_lateral_accel must be finite");
    }
  }

  static SO3d rotation(double yaw, double pitch, double roll) {
    const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
    return SO3d(q);
  }

  // Round the corners of the route, then resample at equal arclength.
  void build_path(const std::vector<Eigen::Vector3d>& route) {
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t i = 0; i < route.size(); ++i) {
      if (!route[i].allFinite()) {
        throw ValueError("Trajectory::through: route point " + std::to_string(i) + " is not finite");
      }
      if (pts.empty() || (route[i] - pts.back()).norm() > 1e-6) pts.push_back(route[i]);
    }
    if (pts.size() < 2) {
      throw ValueError("Trajectory::through: route needs at least 2 distinct points, got " +
                       std::to_string(pts.size()));
    }
    const double h = config_.control_spacing_m;
    std::vector<Eigen::Vector3d> dense;
    dense.push_back(pts.front());
    for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
      const Eigen::Vector3d in = pts[i] - pts[i - 1];
      const Eigen::Vector3d out = pts[i + 1] - pts[i];
      const Eigen::Vector3d d1 = in.normalized();
      const Eigen::Vector3d d2 = out.normalized();
      const double cos_a = std::clamp(d1.dot(d2), -1.0, 1.0);
      const double alpha = std::min(std::acos(cos_a), std::numbers::pi - 1e-3);
      if (alpha < 1e-9) {
        dense.push_back(pts[i]);
        continue;
      }
      // Corner with a raised-cosine curvature profile over length lc:
      // kappa(s) = (alpha / lc) (1 - cos(2 pi s / lc)), peak 2 alpha / lc;
      // curvature and its derivative start and end at 0 (clothoid-like entry,
      // bounded lateral jerk). unit_tangent_length: vertex distance for lc = 1.
      const double unit_lt = detail::corner_tangent_length(alpha);
      double lt = std::max(2.0 * alpha * config_.turn_radius_m * unit_lt, config_.min_blend_length_m);
      lt = std::min({lt, 0.5 * in.norm(), 0.5 * out.norm()});
      const double lc = lt / unit_lt;
      Eigen::Vector3d m = d2 - cos_a * d1;
      if (m.norm() < 1e-9) m = Eigen::Vector3d::UnitZ().cross(d1);
      if (m.norm() < 1e-9) m = Eigen::Vector3d::UnitX().cross(d1);
      m.normalize();
      const Eigen::Vector3d a = pts[i] - lt * d1;
      const int steps = std::max(8, static_cast<int>(std::ceil(lc / (0.05 * h))));
      const double step = lc / static_cast<double>(steps);
      double x = 0.0;
      double y = 0.0;
      dense.push_back(a);
      for (int k = 0; k < steps; ++k) {
        const double theta = detail::corner_heading(alpha, (static_cast<double>(k) + 0.5) / static_cast<double>(steps));
        x += step * std::cos(theta);
        y += step * std::sin(theta);
        dense.push_back(a + x * d1 + y * m);
      }
    }
    dense.push_back(pts.back());

    std::vector<double> cum(dense.size(), 0.0);
    double total = 0.0;
    for (std::size_t i = 1; i < dense.size(); ++i) {
      total += (dense[i] - dense[i - 1]).norm();
      cum[i] = total;
    }
    const auto nseg = static_cast<std::size_t>(std::max(1.0, std::ceil(total / h)));
    const double spacing = total / static_cast<double>(nseg);
    std::vector<Eigen::Vector3d> q;
    q.reserve(nseg + 1);
    std::size_t seg = 0;
    for (std::size_t k = 0; k <= nseg; ++k) {
      const double s = std::min(static_cast<double>(k) * spacing, total);
      while (seg + 2 < dense.size() && cum[seg + 1] < s) ++seg;
      const double len = cum[seg + 1] - cum[seg];
      const double f = len > 0.0 ? std::clamp((s - cum[seg]) / len, 0.0, 1.0) : 0.0;
      q.push_back(dense[seg] + f * (dense[seg + 1] - dense[seg]));
    }
    // Dense routes (a sampled curve, median segment < dense_route_segment_m):
    // the curvature of a polyline sits in its vertices, which would make the
    // lateral acceleration ripple at the vertex rate; two box filters of the
    // vertex spacing remove that ripple (and its harmonics mostly) while
    // moving the path by only ~P^2 curvature / 12.
    std::vector<double> seg_len;
    for (std::size_t i = 1; i < pts.size(); ++i) seg_len.push_back((pts[i] - pts[i - 1]).norm());
    std::nth_element(seg_len.begin(), seg_len.begin() + static_cast<std::ptrdiff_t>(seg_len.size() / 2), seg_len.end());
    const double median_seg = seg_len[seg_len.size() / 2];
    if (median_seg < config_.dense_route_segment_m && q.size() > 2) {
      const auto r = static_cast<std::size_t>(std::max(1.0, std::round(0.5 * median_seg / spacing)));
      q = detail::box_filter(detail::box_filter(q, r), r);
    }
    path_ = detail::QuinticPath(q, spacing);
  }

  // Speed plan: plateaus (curve zones at their limit speed, stops at 0), then
  // smooth-step transitions in the gaps, limited by acceleration/braking.
  void build_time_law() {
    const TrajectoryConfig& c = config_;
    const double L = path_.length_m();
    const double cruise = c.cruise_speed_mps;
    const double acc = c.max_accel_mps2;
    const double dec = c.max_decel_mps2;
    const double jerk = c.max_jerk_mps3;
    // 1. Curve zones: runs of samples whose speed limit is below cruise.
    const double ds = 0.5 * std::min(c.control_spacing_m, 1.0);
    const auto ns = static_cast<std::size_t>(std::ceil(L / ds)) + 1;
    struct Zone {
      double a, b, v;
    };
    std::vector<Zone> zones;
    bool open = false;
    for (std::size_t k = 0; k < ns; ++k) {
      const double s = std::min(static_cast<double>(k) * ds, L);
      std::array<Eigen::Vector3d, 3> d;
      path_.evaluate<2>(s, d);
      const double sp = d[1].norm();
      const double kappa = d[1].cross(d[2]).norm() / (sp * sp * sp);
      const double vlim = kappa > 1e-12 ? std::sqrt(c.max_lateral_accel_mps2 / kappa) : cruise * 2.0;
      if (vlim < cruise) {
        if (!open) zones.push_back({std::max(0.0, s - ds), s, vlim});
        open = true;
        zones.back().b = std::min(L, s + ds);
        zones.back().v = std::min(zones.back().v, vlim);
      } else {
        open = false;
      }
    }
    // Merge overlapping zones (widening can make neighbours touch).
    std::vector<Zone> merged;
    for (const auto& z : zones) {
      if (!merged.empty() && z.a <= merged.back().b) {
        merged.back().b = std::max(merged.back().b, z.b);
        merged.back().v = std::min(merged.back().v, z.v);
      } else {
        merged.push_back(z);
      }
    }
    zones = merged;
    for (auto& z : zones) z.v *= 0.98;  // margin for curvature between samples
    auto zone_of = [&](double s) {
      for (std::size_t i = 0; i < zones.size(); ++i) {
        if (s >= zones[i].a && s <= zones[i].b) return static_cast<int>(i);
      }
      return -1;
    };
    auto cap_at = [&](double s) {
      const int z = zone_of(s);
      return z >= 0 ? zones[static_cast<std::size_t>(z)].v : cruise;
    };
    // 2. Plateaus in order: start, zone pieces split by stops, stops, end.
    std::vector<double> stops;
    for (double s : c.stop_at_arclength_m) {
      if (std::isfinite(s) && s > 0.0 && s < L) stops.push_back(s);
    }
    std::sort(stops.begin(), stops.end());
    std::vector<detail::Plateau> pl;
    pl.push_back({0.0, 0.0, c.start_at_rest ? 0.0 : cap_at(0.0), 0.0, zone_of(0.0)});
    std::size_t si = 0;
    for (std::size_t zi = 0; zi <= zones.size(); ++zi) {
      const double zone_start = zi < zones.size() ? zones[zi].a : L + 1.0;
      while (si < stops.size() && stops[si] < zone_start) {
        pl.push_back({stops[si], stops[si], 0.0, c.stop_duration_s, zone_of(stops[si])});
        ++si;
      }
      if (zi == zones.size()) break;
      const Zone& z = zones[zi];
      double a = z.a;
      while (si < stops.size() && stops[si] <= z.b) {
        pl.push_back({a, stops[si], z.v, 0.0, static_cast<int>(zi)});
        pl.push_back({stops[si], stops[si], 0.0, c.stop_duration_s, static_cast<int>(zi)});
        a = stops[si];
        ++si;
      }
      pl.push_back({a, z.b, z.v, 0.0, static_cast<int>(zi)});
    }
    pl.push_back({L, L, c.end_at_rest ? 0.0 : cap_at(L), 0.0, zone_of(L)});
    // Clip zone pieces next to zero-speed points by the braking/accelerating
    // distance, so the transition to/from rest happens inside the zone gap.
    for (std::size_t i = 0; i < pl.size(); ++i) {
      auto& p = pl[i];
      if (p.b <= p.a || p.v <= 0.0) continue;
      if (i > 0 && pl[i - 1].v == 0.0) {
        p.a = std::max(p.a, pl[i - 1].b + detail::transition_distance(0.0, p.v, acc, jerk));
      }
      if (i + 1 < pl.size() && pl[i + 1].v == 0.0) {
        p.b = std::min(p.b, pl[i + 1].a - detail::transition_distance(p.v, 0.0, dec, jerk));
      }
      if (p.a > p.b) p.a = p.b = 0.5 * (p.a + p.b);
    }
    // Keep order monotone after clipping.
    for (std::size_t i = 1; i < pl.size(); ++i) {
      pl[i].a = std::max(pl[i].a, pl[i - 1].b);
      pl[i].b = std::max(pl[i].b, pl[i].a);
    }
    // 3. Feasibility: lower plateau speeds that cannot be reached in the gap.
    for (std::size_t i = pl.size() - 1; i-- > 0;) {
      const double gap = pl[i + 1].a - pl[i].b;
      const double vn = pl[i + 1].v;
      if (pl[i].v > vn) {
        pl[i].v = detail::largest_fitting(vn, pl[i].v, gap, [&](double v) {
          return detail::transition_distance(v, vn, dec, jerk);
        });
      }
    }
    for (std::size_t i = 0; i + 1 < pl.size(); ++i) {
      const double gap = pl[i + 1].a - pl[i].b;
      const double vp = pl[i].v;
      if (pl[i + 1].v > vp) {
        pl[i + 1].v = detail::largest_fitting(vp, pl[i + 1].v, gap, [&](double v) {
          return detail::transition_distance(vp, v, acc, jerk);
        });
      }
    }
    for (auto& p : pl) {
      if (p.b > p.a) p.v = std::max(p.v, 0.1);  // guard: a stretch is never driven at 0
    }
    // 4. Time pieces.
    pieces_.clear();
    double t = 0.0;
    double s = 0.0;
    auto add = [&](double dur, double v0, double v1) {
      if (dur <= 0.0) return;
      pieces_.push_back({t, dur, s, v0, v1});
      s += 0.5 * (v0 + v1) * dur;
      t += dur;
    };
    for (std::size_t i = 0; i < pl.size(); ++i) {
      auto& p = pl[i];
      if (p.b > p.a) {
        add((p.b - p.a) / p.v, p.v, p.v);
      }
      if (p.dwell_s > 0.0) add(p.dwell_s, 0.0, 0.0);
      if (i + 1 == pl.size()) break;
      const auto& q = pl[i + 1];
      const double gap = std::max(0.0, q.a - p.b);
      const double cap = (p.zone >= 0 && p.zone == q.zone) ? zones[static_cast<std::size_t>(p.zone)].v : cruise;
      const double vlow = std::max(p.v, q.v);
      auto both = [&](double v) {
        return detail::transition_distance(p.v, v, acc, jerk) + detail::transition_distance(v, q.v, dec, jerk);
      };
      double vp = detail::largest_fitting(vlow, std::max(cap, vlow), gap, both);
      const double rest = std::max(0.0, gap - both(vp));
      if (vp > p.v) add(detail::transition_duration(vp - p.v, acc, jerk), p.v, vp);
      if (rest > 0.0 && vp > 0.0) add(rest / vp, vp, vp);
      if (vp > q.v) add(detail::transition_duration(vp - q.v, dec, jerk), vp, q.v);
    }
    if (pieces_.empty()) pieces_.push_back({0.0, 0.0, 0.0, 0.0, 0.0});
    duration_s_ = t;
  }

  [[nodiscard]] std::array<double, 5> sigma(double t_s) const {
    if (pieces_.empty()) return {};  // default-constructed: standing at the origin
    const double t = std::clamp(t_s, 0.0, duration_s_);
    auto it = std::upper_bound(pieces_.begin(), pieces_.end(), t,
                               [](double v, const detail::TimePiece& p) { return v < p.t0_s; });
    if (it != pieces_.begin()) --it;
    return detail::time_law(*it, t - it->t0_s);
  }

  template <int N>
  [[nodiscard]] Jets<N> eval(double t_s) const {
    using J = detail::Jet<N>;
    const std::array<double, 5> sd = sigma(t_s);
    if (pieces_.empty()) return Jets<N>{};  // default-constructed: identity pose, at rest
    J sj;
    J sdot;
    double fact = 1.0;
    for (int k = 0; k <= N; ++k) {
      if (k > 0) fact *= static_cast<double>(k);
      sj.c[static_cast<std::size_t>(k)] = sd[static_cast<std::size_t>(k)] / fact;
      sdot.c[static_cast<std::size_t>(k)] = sd[static_cast<std::size_t>(k + 1)] / fact;
    }
    std::array<Eigen::Vector3d, N + 3> d;
    path_.evaluate<N + 2>(sd[0], d);
    auto comp = [&](int axis, int offset) {
      std::array<double, N + 1> g{};
      double f = 1.0;
      for (int k = 0; k <= N; ++k) {
        if (k > 0) f *= static_cast<double>(k);
        g[static_cast<std::size_t>(k)] = d[static_cast<std::size_t>(k + offset)](axis) / f;
      }
      return detail::compose<N>(g, sj);
    };
    Jets<N> out;
    for (int a = 0; a < 3; ++a) out.p[static_cast<std::size_t>(a)] = comp(a, 0);
    const J tx = comp(0, 1);
    const J ty = comp(1, 1);
    const J tz = comp(2, 1);
    const J sx = comp(0, 2);
    const J sy = comp(1, 2);
    const J horiz = detail::sqrt(tx * tx + ty * ty);
    out.yaw = detail::atan2(ty, tx);
    out.pitch = -detail::atan2(tz, horiz);  // Ry(pitch) with nose up = negative angle
    const J a_lat = sdot * sdot * (tx * sy - ty * sx) * detail::inv(horiz);
    out.roll = config_.roll_per_lateral_accel * a_lat;
    return out;
  }

  // Body angular velocity of R = Rz(yaw) Ry(pitch) Rx(roll), as jets.
  template <int N>
  static std::array<detail::Jet<N>, 3> omega(const Jets<N>& j) {
    using detail::cos;
    using detail::sin;
    const auto dr = detail::derivative(j.roll);
    const auto dp = detail::derivative(j.pitch);
    const auto dy = detail::derivative(j.yaw);
    const auto sr = sin(j.roll);
    const auto cr = cos(j.roll);
    const auto sp = sin(j.pitch);
    const auto cp = cos(j.pitch);
    return {dr - sp * dy, cr * dp + sr * cp * dy, cr * cp * dy - sr * dp};
  }

  TrajectoryConfig config_;
  detail::QuinticPath path_;
  std::vector<detail::TimePiece> pieces_;
  double duration_s_ = 0.0;
};

}  // namespace semlio::sim
