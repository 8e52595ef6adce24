#pragma once
/// \file
/// Closed-form eigen-decomposition of symmetric 3x3 matrices and the local
/// shape (mean, covariance, normal, line direction) of a point neighbourhood,
/// eq. 3-6 of the paper.
///
/// Method (why not Eigen::SelfAdjointEigenSolver: this runs per feature and per
/// map point, so it must be short, branch-light and allocation-free):
///  1. scale C by its largest absolute entry (no overflow / underflow);
///  2. eigenvalues from the trigonometric (Cardano) solution of the
///     characteristic cubic;
///  3. shift and normalise, B = (C - q I) / p (q = trace / 3, p = spread), so
///     that clusters of nearly equal eigenvalues keep their precision; take
///     the eigenvalue of B farthest from the other two (the largest when the
///     two smaller ones are closer together, else the smallest) -- it is
///     separated from the rest by at least sqrt(3), so its eigenvector from the
///     largest cross product of two rows of (B - beta I) is accurate;
///  4. deflate: project B onto the plane orthogonal to that vector and solve the
///     remaining symmetric 2x2 problem with a Jacobi rotation (its eigenvector
///     in closed form, no trigonometry: this runs ~50 000 times a frame). This stays exact
///     for repeated eigenvalues (any orthonormal pair is returned) and keeps the
///     eigenvalues accurate to ~1e-15 * ||C|| where the cubic alone loses digits
///     near a double root.
/// Fallbacks: C == 0 or C == q I give the identity basis; a rank-deficient
/// (B - beta I) (not expected: beta is separated by sqrt(3)) takes any unit
/// vector orthogonal to its largest row.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <utility>

namespace semlio {

/// Eigen-decomposition of a symmetric 3x3 matrix.
struct Eigen3 {
  Eigen::Vector3d values = Eigen::Vector3d::Zero();      ///< ascending
  Eigen::Matrix3d vectors = Eigen::Matrix3d::Identity();  ///< unit columns, matching values
};

namespace detail {

/// Unit vector orthogonal to unit vector v.
inline Eigen::Vector3d any_orthogonal(const Eigen::Vector3d& v) {
  const Eigen::Vector3d u = (std::abs(v.x()) > std::abs(v.y()))
                                ? Eigen::Vector3d(-v.z(), 0.0, v.x())
                                : Eigen::Vector3d(0.0, v.z(), -v.y());
  return u.normalized();
}

/// Unit eigenvector of symmetric A for eigenvalue lambda, assumed separated
/// from the other two: largest cross product of two rows of (A - lambda I).
inline Eigen::Vector3d separated_eigenvector(const Eigen::Matrix3d& A, double lambda) {
  Eigen::Matrix3d M = A;
  M.diagonal().array() -= lambda;
  const Eigen::Vector3d r0 = M.row(0).transpose();
  const Eigen::Vector3d r1 = M.row(1).transpose();
  const Eigen::Vector3d r2 = M.row(2).transpose();
  const Eigen::Vector3d c01 = r0.cross(r1);
  const Eigen::Vector3d c02 = r0.cross(r2);
  const Eigen::Vector3d c12 = r1.cross(r2);
  const double n01 = c01.squaredNorm();
  const double n02 = c02.squaredNorm();
  const double n12 = c12.squaredNorm();
  const double best = std::max({n01, n02, n12});
  // A is trace-free with ||A||_F^2 = 6 (see eigen_symmetric3), so rows are
  // O(1); a cross product this small means (A - lambda I) has rank <= 1.
  constexpr double kRankTol = 1e-24;
  if (best > kRankTol) {
    const Eigen::Vector3d& c = (best == n01) ? c01 : (best == n02) ? c02 : c12;
    return c / std::sqrt(best);
  }
  const double m0 = r0.squaredNorm();
  const double m1 = r1.squaredNorm();
  const double m2 = r2.squaredNorm();
  const double mr = std::max({m0, m1, m2});
  if (mr <= kRankTol) return Eigen::Vector3d::UnitX();  // A == lambda I
  const Eigen::Vector3d& r = (mr == m0) ? r0 : (mr == m1) ? r1 : r2;
  return any_orthogonal(r / std::sqrt(mr));
}

}  // namespace detail

/// Eigenvalues (ascending) and unit eigenvectors (columns) of the symmetric
/// matrix C (only the upper triangle is read). Closed form, no allocation,
/// deterministic; eigenvectors are defined up to sign (and, for repeated
/// eigenvalues, up to rotation within their eigenspace). Non-finite input
/// gives non-finite output; callers check their inputs.
inline Eigen3 eigen_symmetric3(const Eigen::Matrix3d& C) {
  Eigen3 out;
  Eigen::Matrix3d A = C.selfadjointView<Eigen::Upper>();
  if (!A.allFinite()) {  // garbage in, NaN out (never a silent plausible answer)
    out.values.setConstant(std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  const double scale = A.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return out;  // zero matrix
  A /= scale;

  // Trigonometric roots of det(A - lambda I) = 0 (Smith 1961).
  const double q = A.trace() / 3.0;
  const double p1 = A(0, 1) * A(0, 1) + A(0, 2) * A(0, 2) + A(1, 2) * A(1, 2);
  const double d0 = A(0, 0) - q;
  const double d1 = A(1, 1) - q;
  const double d2 = A(2, 2) - q;
  const double p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
  if (!(p2 > 0.0)) {  // A == q I
    out.values.setConstant(q * scale);
    return out;
  }
  const double p = std::sqrt(p2 / 6.0);
  Eigen::Matrix3d B = A;
  B.diagonal().array() -= q;
  B /= p;
  const double r = std::clamp(B.determinant() / 2.0, -1.0, 1.0);
  const double phi = std::acos(r) / 3.0;
  // Work on B = (A - q I) / p (trace-free, ||B||_F^2 = 6): its eigenvalues
  // are 2 cos(phi + 2 pi k / 3), so tolerances are absolute and clusters of
  // nearly equal eigenvalues (p << |q|) keep their relative precision.
  const double beta_max = 2.0 * std::cos(phi);
  const double beta_min = 2.0 * std::cos(phi + 2.0 * std::numbers::pi / 3.0);

  // The eigenvalue farthest from the other two (r >= 0: the largest).
  const double beta_sep = (r >= 0.0) ? beta_max : beta_min;
  const Eigen::Vector3d v_sep = detail::separated_eigenvector(B, beta_sep);

  // Deflate onto the orthogonal plane spanned by (u, w); Jacobi-rotate 2x2.
  const Eigen::Vector3d u = detail::any_orthogonal(v_sep);
  const Eigen::Vector3d w = v_sep.cross(u).normalized();
  const Eigen::Vector3d Bu = B * u;
  const Eigen::Vector3d Bw = B * w;
  const double a = u.dot(Bu);
  const double b = 0.5 * (u.dot(Bw) + w.dot(Bu));
  const double d = w.dot(Bw);
  const double mean = 0.5 * (a + d);
  const double e = 0.5 * (a - d);
  const double half = std::sqrt(e * e + b * b);  // B is O(1): no overflow, hypot not needed
  // Eigenvector (c, s) of [[a, b], [b, d]] for mean + half without
  // trigonometry: (e + half, b) when e >= 0, else (b, half - e) -- both exact
  // eigenvectors; the choice avoids cancellation. half == 0: any pair.
  double c = 1.0;
  double s = 0.0;
  if (half > 0.0) {
    const double x = e >= 0.0 ? e + half : b;
    const double y = e >= 0.0 ? b : half - e;
    const double len = std::sqrt(x * x + y * y);
    c = x / len;
    s = y / len;
  }
  const Eigen::Vector3d v_hi = (c * u + s * w).normalized();
  const Eigen::Vector3d v_lo = (c * w - s * u).normalized();
  const double l_sep = q + p * v_sep.dot(B * v_sep);  // Rayleigh quotient: error ~ eps^2
  const double l_hi = q + p * (mean + half);
  const double l_lo = q + p * (mean - half);

  std::array<std::pair<double, Eigen::Vector3d>, 3> pairs{
      {{l_sep, v_sep}, {l_hi, v_hi}, {l_lo, v_lo}}};
  std::sort(pairs.begin(), pairs.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  for (int i = 0; i < 3; ++i) {
    out.values[i] = pairs[static_cast<std::size_t>(i)].first * scale;
    out.vectors.col(i) = pairs[static_cast<std::size_t>(i)].second;
  }
  return out;
}

/// Shape of a point neighbourhood (eq. 3-6): centroid, covariance eigenvalues,
/// surface normal (smallest eigenvector) and line direction (largest).
struct LocalShape {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();         ///< centroid (eq. 3), same frame as points
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();      ///< unit, smallest eigenvalue's vector (unoriented)
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();   ///< unit, largest eigenvalue's vector (unoriented)
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  ///< of the covariance (eq. 4, divided by N), ascending [m^2]
  bool valid = false;  ///< n >= 2 and finite covariance; the normal is meaningful only for n >= 3
};

/// Fits eq. 3-6 to the n points point_at(0..n-1) (each returning an
/// Eigen::Vector3d or Vector3f): mean, covariance = (1/N) sum (p - mean)(p -
/// mean)^T (two-pass, centred, in double), its eigen-decomposition. Planarity /
/// linearity checks are the caller's (they need their own thresholds).
/// `valid` is false for n < 2 or non-finite points; no allocation.
template <typename PointAt>
LocalShape fit_local_shape(std::size_t n, PointAt point_at) {
  LocalShape shape;
  if (n == 0) return shape;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) sum += point_at(i).template cast<double>();
  const double inv_n = 1.0 / static_cast<double>(n);
  shape.mean = sum * inv_n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = point_at(i).template cast<double>() - shape.mean;
    cov.noalias() += d * d.transpose();
  }
  cov *= inv_n;
  if (n < 2 || !cov.allFinite()) return shape;
  const Eigen3 eig = eigen_symmetric3(cov);
  shape.eigenvalues = eig.values.cwiseMax(0.0);  // a covariance is PSD; clip rounding
  shape.normal = eig.vectors.col(0);
  shape.direction = eig.vectors.col(2);
  shape.valid = true;
  return shape;
}

}  // namespace semlio
