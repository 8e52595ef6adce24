#pragma once
/// \file
/// Simulator primitives: oriented boxes, vertical cylinders, axis-aligned
/// ellipsoids and triangles, each carrying the SemanticKITTI raw label of the
/// surface, an instance id and a lidar reflectivity. Exact ray-primitive
/// intersection in double precision (the ray-cast tests compare against the
/// analytic distance).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <semlio/core/labels.hpp>

namespace semlio::sim {

/// Shape of a primitive.
enum class Shape : std::uint8_t { kBox, kCylinder, kEllipsoid, kTriangle };

/// What a surface is: raw SemanticKITTI id (e.g. 10 car, 252 moving-car),
/// instance id (0 = stuff without instance) and reflectivity in [0, 1].
struct Surface {
  std::uint16_t raw_label = 0;
  std::uint16_t instance = 0;
  float reflectivity = 0.3F;
};

/// One primitive in world coordinates [m]. Field meaning depends on `shape`:
/// box: a = centre, b = half extents, R = R_world_box;
/// cylinder (axis = world z): a = centre of the bottom cap, b = (radius, height, 0);
/// ellipsoid (axis-aligned): a = centre, b = radii;
/// triangle: a, b, c = vertices.
struct Primitive {
  Shape shape = Shape::kBox;
  Surface surface;
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
};

/// A ray with unit direction; `inv_dir` caches 1/dir for slab tests.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d dir = Eigen::Vector3d::UnitX();
  Eigen::Vector3d inv_dir = Eigen::Vector3d(1.0, std::numeric_limits<double>::infinity(),
                                            std::numeric_limits<double>::infinity());
  /// Builds a ray; `dir` is normalised here.
  static Ray make(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
    Ray r;
    r.origin = origin;
    r.dir = dir.normalized();
    r.inv_dir = r.dir.cwiseInverse();
    return r;
  }
};

/// Axis-aligned bounding box.
struct Aabb {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  /// Grows the box to contain p.
  void extend(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  /// Grows the box to contain o.
  void extend(const Aabb& o) {
    lo = lo.cwiseMin(o.lo);
    hi = hi.cwiseMax(o.hi);
  }
  /// Centre of the box.
  [[nodiscard]] Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
  /// Half the surface area (the SAH only needs ratios).
  [[nodiscard]] double half_area() const {
    const Eigen::Vector3d e = (hi - lo).cwiseMax(0.0);
    return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
  }
};

/// Oriented box with yaw `yaw_rad` about world z.
inline Primitive make_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents,
                          double yaw_rad, Surface s) {
  Primitive p;
  p.shape = Shape::kBox;
  p.surface = s;
  p.a = centre;
  p.b = half_extents;
  const double cy = std::cos(yaw_rad);
  const double sy = std::sin(yaw_rad);
  p.R << cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0;
  return p;
}

/// Oriented box with a general rotation R_world_box.
inline Primitive make_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents,
                          const Eigen::Matrix3d& R_world_box, Surface s) {
  Primitive p = make_box(centre, half_extents, 0.0, s);
  p.R = R_world_box;
  return p;
}

/// Vertical cylinder standing on `base` (centre of its bottom cap).
inline Primitive make_cylinder(const Eigen::Vector3d& base, double radius_m, double height_m,
                               Surface s) {
  Primitive p;
  p.shape = Shape::kCylinder;
  p.surface = s;
  p.a = base;
  p.b = Eigen::Vector3d(radius_m, height_m, 0.0);
  return p;
}

/// Axis-aligned ellipsoid.
inline Primitive make_ellipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& radii,
                                Surface s) {
  Primitive p;
  p.shape = Shape::kEllipsoid;
  p.surface = s;
  p.a = centre;
  p.b = radii;
  return p;
}

/// Triangle (two-sided).
inline Primitive make_triangle(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1,
                               const Eigen::Vector3d& v2, Surface s) {
  Primitive p;
  p.shape = Shape::kTriangle;
  p.surface = s;
  p.a = v0;
  p.b = v1;
  p.c = v2;
  return p;
}

/// World-space bounds of a primitive.
inline Aabb bounds(const Primitive& p) {
  Aabb box;
  switch (p.shape) {
    case Shape::kBox: {
      const Eigen::Vector3d e = p.R.cwiseAbs() * p.b;
      box.lo = p.a - e;
      box.hi = p.a + e;
      break;
    }
    case Shape::kCylinder:
      box.lo = p.a - Eigen::Vector3d(p.b.x(), p.b.x(), 0.0);
      box.hi = p.a + Eigen::Vector3d(p.b.x(), p.b.x(), p.b.y());
      break;
    case Shape::kEllipsoid:
      box.lo = p.a - p.b;
      box.hi = p.a + p.b;
      break;
    case Shape::kTriangle:
      box.extend(p.a);
      box.extend(p.b);
      box.extend(p.c);
      break;
  }
  return box;
}

namespace detail {

/// Smallest root of a t^2 + 2 h t + c = 0 in (t_min, t_max), and the larger
/// one as a fallback (ray starting inside); false when neither qualifies.
inline bool quadratic_hit(double a, double h, double c, double t_min, double t_max, double& t) {
  const double disc = h * h - a * c;
  if (disc < 0.0 || a <= 0.0) return false;
  const double s = std::sqrt(disc);
  const double t0 = (-h - s) / a;
  const double t1 = (-h + s) / a;
  if (t0 > t_min && t0 < t_max) {
    t = t0;
    return true;
  }
  if (t1 > t_min && t1 < t_max) {
    t = t1;
    return true;
  }
  return false;
}

inline bool hit_box(const Primitive& p, const Ray& ray, double t_min, double& t_hit) {
  const Eigen::Vector3d o = p.R.transpose() * (ray.origin - p.a);
  const Eigen::Vector3d d = p.R.transpose() * ray.dir;
  double t0 = -std::numeric_limits<double>::infinity();
  double t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (std::abs(o[k]) > p.b[k]) return false;
      continue;
    }
    const double inv = 1.0 / d[k];
    double ta = (-p.b[k] - o[k]) * inv;
    double tb = (p.b[k] - o[k]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  const double t = t0 > t_min ? t0 : t1;
  if (t > t_min && t < t_hit) {
    t_hit = t;
    return true;
  }
  return false;
}

inline bool hit_cylinder(const Primitive& p, const Ray& ray, double t_min, double& t_hit) {
  const double r = p.b.x();
  const double z0 = p.a.z();
  const double z1 = z0 + p.b.y();
  const double ox = ray.origin.x() - p.a.x();
  const double oy = ray.origin.y() - p.a.y();
  const double oz = ray.origin.z();
  const double dx = ray.dir.x();
  const double dy = ray.dir.y();
  const double dz = ray.dir.z();
  double best = t_hit;
  bool found = false;
  // Side: (ox + t dx)^2 + (oy + t dy)^2 = r^2, two roots checked against the height.
  const double a = dx * dx + dy * dy;
  if (a > 0.0) {
    const double h = ox * dx + oy * dy;
    const double c = ox * ox + oy * oy - r * r;
    const double disc = h * h - a * c;
    if (disc >= 0.0) {
      const double s = std::sqrt(disc);
      for (const double t : {(-h - s) / a, (-h + s) / a}) {
        const double z = oz + t * dz;
        if (t > t_min && t < best && z >= z0 && z <= z1) {
          best = t;
          found = true;
        }
      }
    }
  }
  // Caps.
  if (dz != 0.0) {
    for (const double zc : {z0, z1}) {
      const double t = (zc - oz) / dz;
      const double x = ox + t * dx;
      const double y = oy + t * dy;
      if (t > t_min && t < best && x * x + y * y <= r * r) {
        best = t;
        found = true;
      }
    }
  }
  if (found) t_hit = best;
  return found;
}

inline bool hit_ellipsoid(const Primitive& p, const Ray& ray, double t_min, double& t_hit) {
  const Eigen::Vector3d o = (ray.origin - p.a).cwiseQuotient(p.b);
  const Eigen::Vector3d d = ray.dir.cwiseQuotient(p.b);
  double t = 0.0;
  if (!quadratic_hit(d.squaredNorm(), o.dot(d), o.squaredNorm() - 1.0, t_min, t_hit, t)) {
    return false;
  }
  t_hit = t;
  return true;
}

inline bool hit_triangle(const Primitive& p, const Ray& ray, double t_min, double& t_hit) {
  // Moller-Trumbore, two-sided.
  const Eigen::Vector3d e1 = p.b - p.a;
  const Eigen::Vector3d e2 = p.c - p.a;
  const Eigen::Vector3d q = ray.dir.cross(e2);
  const double det = e1.dot(q);
  if (std::abs(det) < 1e-14) return false;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = ray.origin - p.a;
  const double u = s.dot(q) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const Eigen::Vector3d r = s.cross(e1);
  const double v = ray.dir.dot(r) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = e2.dot(r) * inv;
  if (t > t_min && t < t_hit) {
    t_hit = t;
    return true;
  }
  return false;
}

}  // namespace detail

/// Exact intersection: when the ray hits `p` at a distance in (t_min, t_hit),
/// sets t_hit to it and returns true; otherwise leaves t_hit unchanged.
inline bool intersect(const Primitive& p, const Ray& ray, double t_min, double& t_hit) {
  switch (p.shape) {
    case Shape::kBox: return detail::hit_box(p, ray, t_min, t_hit);
    case Shape::kCylinder: return detail::hit_cylinder(p, ray, t_min, t_hit);
    case Shape::kEllipsoid: return detail::hit_ellipsoid(p, ray, t_min, t_hit);
    case Shape::kTriangle: return detail::hit_triangle(p, ray, t_min, t_hit);
  }
  return false;
}

/// Unit outward surface normal of `p` at a point `x` on its surface (for a
/// triangle: the side facing `toward`, usually the ray origin).
inline Eigen::Vector3d surface_normal(const Primitive& p, const Eigen::Vector3d& x,
                                      const Eigen::Vector3d& toward) {
  switch (p.shape) {
    case Shape::kBox: {
      const Eigen::Vector3d l = p.R.transpose() * (x - p.a);
      int axis = 0;
      double best = -1.0;
      for (int k = 0; k < 3; ++k) {
        const double f = std::abs(l[k]) / std::max(p.b[k], 1e-12);
        if (f > best) {
          best = f;
          axis = k;
        }
      }
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = l[axis] >= 0.0 ? 1.0 : -1.0;
      return p.R * n;
    }
    case Shape::kCylinder: {
      const double eps = 1e-9;
      if (x.z() >= p.a.z() + p.b.y() - eps) return Eigen::Vector3d::UnitZ();
      if (x.z() <= p.a.z() + eps) return -Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d n(x.x() - p.a.x(), x.y() - p.a.y(), 0.0);
      const double len = n.norm();
      return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitX();
    }
    case Shape::kEllipsoid: {
      const Eigen::Vector3d g = (x - p.a).cwiseQuotient(p.b.cwiseProduct(p.b));
      const double len = g.norm();
      return len > 0.0 ? Eigen::Vector3d(g / len) : Eigen::Vector3d::UnitZ();
    }
    case Shape::kTriangle: {
      Eigen::Vector3d n = (p.b - p.a).cross(p.c - p.a);
      const double len = n.norm();
      n = len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
      return n.dot(toward - x) >= 0.0 ? n : Eigen::Vector3d(-n);
    }
  }
  return Eigen::Vector3d::UnitZ();
}

}  // namespace semlio::sim
