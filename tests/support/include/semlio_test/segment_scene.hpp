#pragma once
/// \file
/// A small labelled street scene ray-cast with an HDL-64E-like beam layout,
/// for the GeometricSegmenter tests: flat road, a building, two cars, a
/// street light, a tree (trunk + canopy) and a bush. Exact labels.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>

namespace semlio_test {

/// One analytic primitive of the scene.
struct SegmentPrimitive {
  enum class Kind { kBox, kCylinder, kSphere } kind;
  Eigen::Vector3d lo, hi;  ///< box corners, or cylinder base centre (lo) with hi.z() the top and hi.x() the radius
  double radius = 0.0;     ///< sphere radius (centre in lo)
  semlio::Class label;
};

/// Sensor height of the scene [m] (KITTI's).
inline constexpr double kSceneSensorHeight = 1.73;

/// The scene's primitives (sensor frame, ground at z = -1.73).
inline std::vector<SegmentPrimitive> segment_scene_primitives() {
  using semlio::Class;
  const double g = -kSceneSensorHeight;
  using K = SegmentPrimitive::Kind;
  return {
      {K::kBox, {14.0, -15.0, g}, {24.0, 15.0, g + 10.0}, 0.0, Class::kBuilding},
      {K::kBox, {3.8, -4.9, g + 0.25}, {8.2, -3.1, g + 1.5}, 0.0, Class::kCar},
      {K::kBox, {-8.9, 3.0, g + 0.25}, {-7.1, 7.4, g + 1.55}, 0.0, Class::kCar},
      {K::kCylinder, {5.0, 7.0, g}, {0.1, 0.0, g + 6.5}, 0.0, Class::kPole},
      // A tree far enough for the top beam (+2 deg) to see its canopy.
      {K::kCylinder, {-24.0, -16.0, g}, {0.25, 0.0, g + 3.0}, 0.0, Class::kTrunk},
      {K::kSphere, {-24.0, -16.0, g + 4.6}, {0.0, 0.0, 0.0}, 2.0, Class::kVegetation},
      {K::kSphere, {-10.0, -12.0, g + 0.5}, {0.0, 0.0, 0.0}, 0.7, Class::kVegetation},  // a bush
  };
}

/// Distance along the unit ray d from the origin to primitive p (infinity if missed).
inline double segment_scene_hit(const SegmentPrimitive& p, const Eigen::Vector3d& d) {
  const double inf = std::numeric_limits<double>::infinity();
  switch (p.kind) {
    case SegmentPrimitive::Kind::kBox: {
      double t0 = 0.0, t1 = inf;
      for (int a = 0; a < 3; ++a) {
        if (std::abs(d[a]) < 1e-12) {
          if (0.0 < p.lo[a] || 0.0 > p.hi[a]) return inf;
          continue;
        }
        double ta = p.lo[a] / d[a];
        double tb = p.hi[a] / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      return t0 <= t1 && t0 > 0.0 ? t0 : inf;
    }
    case SegmentPrimitive::Kind::kCylinder: {
      const double r = p.hi.x();
      const double a = d.x() * d.x() + d.y() * d.y();
      const double b = -2.0 * (d.x() * p.lo.x() + d.y() * p.lo.y());
      const double c = p.lo.x() * p.lo.x() + p.lo.y() * p.lo.y() - r * r;
      const double disc = b * b - 4.0 * a * c;
      if (a < 1e-12 || disc < 0.0) return inf;
      const double t = (-b - std::sqrt(disc)) / (2.0 * a);
      const double z = t * d.z();
      return t > 0.0 && z >= p.lo.z() && z <= p.hi.z() ? t : inf;
    }
    case SegmentPrimitive::Kind::kSphere: {
      const double b = -2.0 * d.dot(p.lo);
      const double c = p.lo.squaredNorm() - p.radius * p.radius;
      const double disc = b * b - 4.0 * c;
      if (disc < 0.0) return inf;
      const double t = 0.5 * (-b - std::sqrt(disc));
      return t > 0.0 ? t : inf;
    }
  }
  return inf;
}

/// Ray-casts the scene with 64 beams (-24.9..+2 deg) x `azimuth_steps`
/// columns, ranges 2..80 m; the ground plane is road. Labels are exact.
inline semlio::Scan segment_scene(int azimuth_steps = 1800) {
  const std::vector<SegmentPrimitive> prims = segment_scene_primitives();
  semlio::Scan scan;
  for (int ring = 0; ring < 64; ++ring) {
    const double el_deg = -24.9 + (2.0 + 24.9) * static_cast<double>(ring) / 63.0;
    const double el = el_deg * std::numbers::pi / 180.0;
    for (int k = 0; k < azimuth_steps; ++k) {
      const double az = 2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(azimuth_steps);
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      double best = d.z() < 0.0 ? -kSceneSensorHeight / d.z() : std::numeric_limits<double>::infinity();
      semlio::Class label = semlio::Class::kRoad;
      for (const SegmentPrimitive& p : prims) {
        const double t = segment_scene_hit(p, d);
        if (t < best) {
          best = t;
          label = p.label;
        }
      }
      if (!(best >= 2.0 && best <= 80.0)) continue;
      scan.points.push_back((best * d).cast<float>());
      scan.labels.push_back(label);
      scan.rings.push_back(static_cast<std::uint16_t>(ring));
    }
  }
  return scan;
}

}  // namespace semlio_test
