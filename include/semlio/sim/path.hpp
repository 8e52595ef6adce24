#pragma once
/// \file
/// Polyline helpers for routes: rounded corners, lateral offsets, arclength
/// parametrisation. Paths are dense 3D polylines in the world frame (z up);
/// "left" is z x tangent.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace semlio::sim {

/// A polyline with cumulative arclength, for lookups by distance along it.
class Polyline {
 public:
  Polyline() = default;
  /// Wraps `points` (at least two, no repeated consecutive points expected).
  explicit Polyline(std::vector<Eigen::Vector3d> points) : pts_(std::move(points)) {
    s_.assign(pts_.size(), 0.0);
    for (std::size_t i = 1; i < pts_.size(); ++i) s_[i] = s_[i - 1] + (pts_[i] - pts_[i - 1]).norm();
  }
  /// Total length [m].
  [[nodiscard]] double length() const { return s_.empty() ? 0.0 : s_.back(); }
  /// The vertices.
  [[nodiscard]] const std::vector<Eigen::Vector3d>& points() const { return pts_; }
  /// Arclength of vertex i [m].
  [[nodiscard]] double arclength(std::size_t i) const { return s_[i]; }

  /// Position at arclength s (clamped to the ends).
  [[nodiscard]] Eigen::Vector3d at(double s) const {
    const std::size_t i = segment(s);
    const double len = s_[i + 1] - s_[i];
    const double u = len > 0.0 ? std::clamp((s - s_[i]) / len, 0.0, 1.0) : 0.0;
    return pts_[i] + u * (pts_[i + 1] - pts_[i]);
  }
  /// Unit horizontal tangent at arclength s.
  [[nodiscard]] Eigen::Vector3d tangent(double s) const {
    const std::size_t i = segment(s);
    Eigen::Vector3d t = pts_[i + 1] - pts_[i];
    t.z() = 0.0;
    const double n = t.norm();
    return n > 0.0 ? Eigen::Vector3d(t / n) : Eigen::Vector3d::UnitX();
  }
  /// Unit horizontal left normal at arclength s.
  [[nodiscard]] Eigen::Vector3d left(double s) const {
    const Eigen::Vector3d t = tangent(s);
    return {-t.y(), t.x(), 0.0};
  }

 private:
  [[nodiscard]] std::size_t segment(double s) const {
    const auto it = std::upper_bound(s_.begin(), s_.end(), s);
    const auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - s_.begin() - 1, 0));
    return std::min(i, pts_.size() - 2);
  }

  std::vector<Eigen::Vector3d> pts_;
  std::vector<double> s_;
};

/// Dense polyline through `corners` with every interior corner replaced by a
/// circular arc of radius `radius_m` (shrunk where segments are short),
/// sampled about every `step_m`. z is interpolated linearly.
inline std::vector<Eigen::Vector3d> round_corners(const std::vector<Eigen::Vector3d>& corners,
                                                  double radius_m, double step_m) {
  std::vector<Eigen::Vector3d> out;
  if (corners.size() < 2) return corners;
  const auto add_line = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const double len = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / step_m)));
    for (int k = (out.empty() ? 0 : 1); k <= n; ++k) {
      out.push_back(a + (b - a) * (static_cast<double>(k) / n));
    }
  };
  Eigen::Vector3d start = corners.front();
  for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
    const Eigen::Vector3d& p = corners[i];
    const Eigen::Vector3d d0 = (p - corners[i - 1]).normalized();
    const Eigen::Vector3d d1 = (corners[i + 1] - p).normalized();
    const double cos_turn = std::clamp(d0.dot(d1), -1.0, 1.0);
    const double turn = std::acos(cos_turn);
    if (turn < 1e-6) continue;  // straight: no corner
    const double half_len0 = 0.5 * (p - corners[i - 1]).norm();
    const double half_len1 = 0.5 * (corners[i + 1] - p).norm();
    double r = radius_m;
    double back = r * std::tan(0.5 * turn);
    const double limit = std::min(half_len0, half_len1);
    if (back > limit) {
      back = limit;
      r = back / std::tan(0.5 * turn);
    }
    const Eigen::Vector3d a = p - d0 * back;
    const Eigen::Vector3d b = p + d1 * back;
    add_line(start, a);
    // Arc from a to b about the centre on the inner side (horizontal plane).
    const double side = (d0.x() * d1.y() - d0.y() * d1.x()) >= 0.0 ? 1.0 : -1.0;
    const Eigen::Vector3d n0(-d0.y() * side, d0.x() * side, 0.0);
    const Eigen::Vector3d centre = a + n0 * r;
    const int n = std::max(2, static_cast<int>(std::ceil(r * turn / step_m)));
    const Eigen::Vector3d ra = a - centre;
    for (int k = 1; k <= n; ++k) {
      const double ang = side * turn * static_cast<double>(k) / n;
      const double c = std::cos(ang);
      const double s = std::sin(ang);
      Eigen::Vector3d q = centre + Eigen::Vector3d(c * ra.x() - s * ra.y(), s * ra.x() + c * ra.y(), 0.0);
      q.z() = a.z() + (b.z() - a.z()) * static_cast<double>(k) / n;
      out.push_back(q);
    }
    start = b;
  }
  add_line(start, corners.back());
  return out;
}

/// The polyline shifted sideways by `left_m` (negative = right) at every vertex.
inline std::vector<Eigen::Vector3d> offset_path(const std::vector<Eigen::Vector3d>& path,
                                                double left_m) {
  std::vector<Eigen::Vector3d> out(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Eigen::Vector3d& prev = path[i == 0 ? 0 : i - 1];
    const Eigen::Vector3d& next = path[std::min(i + 1, path.size() - 1)];
    Eigen::Vector3d t = next - prev;
    t.z() = 0.0;
    const double n = t.norm();
    if (n > 0.0) t /= n;
    out[i] = path[i] + left_m * Eigen::Vector3d(-t.y(), t.x(), 0.0);
  }
  return out;
}

/// A sparse corner polyline shifted sideways by `left_m` with mitred
/// corners (each segment moves parallel to itself), so a lane keeps its
/// distance from the street centreline through 90-degree turns.
inline std::vector<Eigen::Vector3d> offset_corners(const std::vector<Eigen::Vector3d>& corners,
                                                   double left_m) {
  const std::size_t n = corners.size();
  std::vector<Eigen::Vector3d> out(n);
  if (n < 2) return corners;
  const auto left_of = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    Eigen::Vector3d t = b - a;
    t.z() = 0.0;
    const double len = t.norm();
    if (len > 0.0) t /= len;
    return Eigen::Vector3d(-t.y(), t.x(), 0.0);
  };
  out[0] = corners[0] + left_m * left_of(corners[0], corners[1]);
  out[n - 1] = corners[n - 1] + left_m * left_of(corners[n - 2], corners[n - 1]);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const Eigen::Vector3d n0 = left_of(corners[i - 1], corners[i]);
    const Eigen::Vector3d n1 = left_of(corners[i], corners[i + 1]);
    const Eigen::Vector3d m = n0 + n1;
    const double denom = 1.0 + n0.dot(n1);
    // Miter: the point at distance left_m from both shifted segments.
    out[i] = denom > 1e-6 ? Eigen::Vector3d(corners[i] + left_m * m / denom)
                          : Eigen::Vector3d(corners[i] + left_m * n0);
  }
  return out;
}

/// The same path driven backwards.
inline std::vector<Eigen::Vector3d> reversed(std::vector<Eigen::Vector3d> path) {
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace semlio::sim
