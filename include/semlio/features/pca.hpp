#pragma once
/// \file
/// Closed-form eigen-decomposition of symmetric 3x3 matrices and the local
/// shape (mean, covariance, normal, line direction) of a point neighbourhood,
/// eq. 3-6 of the paper.
///
/// Method (why not Eigen::SelfAdjointEigenSolver: this runs per feature and per
/// map point, so it must be short, branch-light and allocation-free):
///  1. scale C by its largest absolute entry (no overflow / underflow);
///  2. shift and normalise, B = (C - q I) / p (q = trace / 3, p = spread), so
///     that clusters of nearly equal eigenvalues keep their precision;
///  3. take the eigenvalue of B farthest from the other two (the largest when
///     the two smaller ones are closer together, else the smallest): the
///     extreme root of B's characteristic cubic beta^3 - 3 beta = det B,
///     by Newton's method from a polynomial start (cubic_top_root; the
///     trigonometric form 2 cos(acos(det B / 2) / 3) is the same number, but
///     acos and cos cost more than the two Newton steps). It is separated
///     from the rest by at least sqrt(3), so its eigenvector from the largest
///     cross product of two rows of (B - beta I) is accurate;
///  4. deflate: project B onto the plane orthogonal to that vector and solve the
///     remaining symmetric 2x2 problem with a Jacobi rotation (its eigenvector
///     in closed form, no trigonometry: this runs ~50 000 times a frame). This stays exact
///     for repeated eigenvalues (any orthonormal pair is returned) and keeps the
///     eigenvalues accurate to ~1e-15 * ||C|| where the cubic alone loses digits
///     near a double root.
/// Fallbacks: C == 0 or C == q I give the identity basis; a rank-deficient
/// (B - beta I) (not expected: beta is separated by sqrt(3)) takes any unit
/// vector orthogonal to its largest row.
/// One eigenvector only (eigenvector_symmetric3, fit_local_axis: what the
/// associators' axes need): when the end asked for is the separated
/// eigenvalue of step 3, step 4 and the sort are skipped -- the same vector,
/// for ~13 % (normals) to ~40 % (line directions) less time on real KITTI
/// neighbourhoods (bench_features, BM_EigenAxis_KittiNeighbourhoods). A
/// residual's fit (eigen_symmetric3_end, fit_local_shape_axis) needs all
/// three eigenvalues but one vector: the deflation runs, and the 2x2
/// rotation only when that vector is a deflated one. All these forms share
/// one arithmetic (deflate, ascending_order, deflation_vector), so each
/// equals eigen_symmetric3 bit for bit.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

namespace semlio {

/// Eigen-decomposition of a symmetric 3x3 matrix.
struct Eigen3 {
  Eigen::Vector3d values = Eigen::Vector3d::Zero();      ///< ascending
  Eigen::Matrix3d vectors = Eigen::Matrix3d::Identity();  ///< unit columns, matching values
};

namespace detail {

/// v / |v| for a nonzero v, by one division and three products (normalized()
/// divides each component; this runs several times per fit).
inline Eigen::Vector3d unit(const Eigen::Vector3d& v) { return v * (1.0 / std::sqrt(v.squaredNorm())); }

/// Unit vector orthogonal to unit vector v.
inline Eigen::Vector3d any_orthogonal(const Eigen::Vector3d& v) {
  const Eigen::Vector3d u = (std::abs(v.x()) > std::abs(v.y()))
                                ? Eigen::Vector3d(-v.z(), 0.0, v.x())
                                : Eigen::Vector3d(0.0, v.z(), -v.y());
  return unit(u);  // |u|^2 >= 1/2 for a unit v
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
    return c * (1.0 / std::sqrt(best));
  }
  const double m0 = r0.squaredNorm();
  const double m1 = r1.squaredNorm();
  const double m2 = r2.squaredNorm();
  const double mr = std::max({m0, m1, m2});
  if (mr <= kRankTol) return Eigen::Vector3d::UnitX();  // A == lambda I
  const Eigen::Vector3d& r = (mr == m0) ? r0 : (mr == m1) ? r1 : r2;
  return any_orthogonal(r * (1.0 / std::sqrt(mr)));
}

/// Largest root of x^3 - 3 x = 2 s for s in [0, 1] (it lies in [sqrt 3, 2]),
/// i.e. 2 cos(acos(s) / 3), without trigonometry: a cubic through the
/// function's values at the four Chebyshev nodes of [0, 1] (within 8.2e-5 of
/// it) and two Newton steps, each squaring the error (times ~0.6): ~1e-8,
/// then rounding level (within 7e-16 on a 200 001-point grid). The
/// derivative 3 (x^2 - 1) stays >= 6 near the root, so no step divides by
/// anything small.
inline double cubic_top_root(double s) {
  double x = ((0.01863937 * s - 0.08138239) * s + 0.3306607) * s + 1.73213266;
  for (int i = 0; i < 2; ++i) {
    const double x2 = x * x;
    x -= (x * (x2 - 3.0) - 2.0 * s) / (3.0 * (x2 - 1.0));
  }
  return x;
}

}  // namespace detail

/// Which end of the spectrum eigenvector_symmetric3 returns.
enum class EigenEnd : std::uint8_t {
  kSmallest,  ///< the smallest eigenvalue's vector (a neighbourhood's normal)
  kLargest,   ///< the largest eigenvalue's vector (a neighbourhood's line direction)
};

namespace detail {

/// Steps 1-3 of eigen_symmetric3 (file comment): C scaled by its largest
/// entry to A, the shift q and spread p of B = (A - q I) / p, and B's
/// eigenpair farthest from the other two.
struct SymmetricSplit {
  /// What kind of matrix C was; only kGeneral fills the fields below q.
  enum class Kind : std::uint8_t { kNonFinite, kZero, kScalar, kGeneral };
  Kind kind = Kind::kZero;
  double scale = 0.0;             ///< largest |C_ij|
  double q = 0.0;                 ///< trace(A) / 3
  double p = 0.0;                 ///< sqrt(||A - q I||_F^2 / 6)
  bool sep_is_largest = false;    ///< the separated eigenvalue is the largest (else the smallest)
  Eigen::Matrix3d B = Eigen::Matrix3d::Zero();  ///< (A - q I) / p: trace-free, ||B||_F^2 = 6
  Eigen::Vector3d v_sep = Eigen::Vector3d::UnitX();  ///< unit eigenvector of the separated eigenvalue
};

/// Steps 1-3 of eigen_symmetric3 for C (only its upper triangle is read).
inline SymmetricSplit split_symmetric3(const Eigen::Matrix3d& C) {
  SymmetricSplit s;
  Eigen::Matrix3d A = C.selfadjointView<Eigen::Upper>();
  if (!A.allFinite()) {  // garbage in, NaN out (never a silent plausible answer)
    s.kind = SymmetricSplit::Kind::kNonFinite;
    return s;
  }
  s.scale = A.cwiseAbs().maxCoeff();
  if (!(s.scale > 0.0)) return s;  // zero matrix
  // One division and nine products instead of nine divisions (here and for B).
  A *= 1.0 / s.scale;

  // Centre and spread of the roots of det(A - lambda I) = 0 (Smith 1961).
  s.q = A.trace() / 3.0;
  const double p1 = A(0, 1) * A(0, 1) + A(0, 2) * A(0, 2) + A(1, 2) * A(1, 2);
  const double d0 = A(0, 0) - s.q;
  const double d1 = A(1, 1) - s.q;
  const double d2 = A(2, 2) - s.q;
  const double p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
  if (!(p2 > 0.0)) {  // A == q I
    s.kind = SymmetricSplit::Kind::kScalar;
    return s;
  }
  s.kind = SymmetricSplit::Kind::kGeneral;
  s.p = std::sqrt(p2 / 6.0);
  s.B = A;
  s.B.diagonal().array() -= s.q;
  s.B *= 1.0 / s.p;
  const double r = std::clamp(s.B.determinant() / 2.0, -1.0, 1.0);
  // Work on B (trace-free, ||B||_F^2 = 6): its eigenvalues are the roots of
  // beta^3 - 3 beta - 2 r (all in [-2, 2]), so tolerances are absolute and
  // clusters of nearly equal eigenvalues (p << |q|) keep their relative
  // precision. The root farthest from the other two is the largest when
  // r >= 0, else the smallest; only that one is needed. The roots for -r are
  // those for r negated, so one solver for r in [0, 1] serves both.
  s.sep_is_largest = r >= 0.0;
  const double top = cubic_top_root(std::abs(r));
  const double beta_sep = s.sep_is_largest ? top : -top;
  s.v_sep = separated_eigenvector(s.B, beta_sep);
  return s;
}

/// Step 4 of eigen_symmetric3 before the sort: B deflated onto the plane
/// orthogonal to v_sep (basis u, w) and its 2x2 problem solved -- the three
/// eigenvalues (unscaled, in the order separated, deflated high, deflated
/// low) and what the two deflated eigenvectors are made of.
struct Deflation {
  std::array<double, 3> values{};
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();
  Eigen::Vector3d w = Eigen::Vector3d::UnitY();
  double e = 0.0;     ///< half the difference of the 2x2 problem's diagonal
  double b = 0.0;     ///< its off-diagonal
  double half = 0.0;  ///< half the gap between its eigenvalues
};

inline Deflation deflate(const SymmetricSplit& s) {
  // Deflate onto the orthogonal plane spanned by (u, w); Jacobi-rotate 2x2.
  Deflation f;
  const Eigen::Matrix3d& B = s.B;
  const Eigen::Vector3d& v_sep = s.v_sep;
  f.u = any_orthogonal(v_sep);
  f.w = unit(v_sep.cross(f.u));  // both unit and orthogonal: the product is unit up to rounding
  const Eigen::Vector3d Bu = B * f.u;
  const Eigen::Vector3d Bw = B * f.w;
  const double a = f.u.dot(Bu);
  f.b = 0.5 * (f.u.dot(Bw) + f.w.dot(Bu));
  const double d = f.w.dot(Bw);
  const double mean = 0.5 * (a + d);
  f.e = 0.5 * (a - d);
  f.half = std::sqrt(f.e * f.e + f.b * f.b);  // B is O(1): no overflow, hypot not needed
  const double l_sep = s.q + s.p * v_sep.dot(B * v_sep);  // Rayleigh quotient: error ~ eps^2
  f.values = {l_sep, s.q + s.p * (mean + f.half), s.q + s.p * (mean - f.half)};
  return f;
}

/// Positions of Deflation::values in ascending order, ties in the order
/// (separated, deflated high, deflated low): a stable sort of three.
inline std::array<int, 3> ascending_order(const std::array<double, 3>& values) {
  std::array<int, 3> o{0, 1, 2};  // swaps only on strictly less
  if (values[1] < values[0]) std::swap(o[0], o[1]);
  if (values[2] < values[static_cast<std::size_t>(o[1])]) {
    std::swap(o[1], o[2]);
    if (values[static_cast<std::size_t>(o[1])] < values[static_cast<std::size_t>(o[0])]) std::swap(o[0], o[1]);
  }
  return o;
}

/// Eigenvector number `which` (0 separated, 1 deflated high, 2 deflated low);
/// the 2x2 rotation is solved only for the deflated ones.
inline Eigen::Vector3d deflation_vector(const SymmetricSplit& s, const Deflation& f, int which) {
  if (which == 0) return s.v_sep;
  // Eigenvector (c, sn) of the 2x2 problem for its larger eigenvalue without
  // trigonometry: (e + half, b) when e >= 0, else (b, half - e) -- both exact
  // eigenvectors; the choice avoids cancellation. half == 0: any pair.
  double c = 1.0;
  double sn = 0.0;
  if (f.half > 0.0) {
    const double x = f.e >= 0.0 ? f.e + f.half : f.b;
    const double y = f.e >= 0.0 ? f.b : f.half - f.e;
    const double len = std::sqrt(x * x + y * y);
    const double inv = 1.0 / len;
    c = x * inv;
    sn = y * inv;
  }
  return unit(which == 1 ? Eigen::Vector3d(c * f.u + sn * f.w) : Eigen::Vector3d(c * f.w - sn * f.u));
}

/// The three eigenpairs of a kGeneral split in ascending order of their
/// eigenvalues (unscaled), ties in the order (separated, deflated high,
/// deflated low): step 4 of eigen_symmetric3 and a stable sort.
inline void ordered_eigenpairs(const SymmetricSplit& s, std::array<double, 3>& values,
                               std::array<Eigen::Vector3d, 3>& vectors) {
  const Deflation f = deflate(s);
  const std::array<int, 3> o = ascending_order(f.values);
  for (std::size_t i = 0; i < 3; ++i) {
    values[i] = f.values[static_cast<std::size_t>(o[i])] * s.scale;
    vectors[i] = deflation_vector(s, f, o[i]);
  }
}

/// Smallest spread p of a kGeneral split for which the separated eigenvalue
/// is provably the extreme one after rounding: it lies >= sqrt(3) p from the
/// other two, and each computed eigenvalue q + p x is off by at most a few
/// ulps of |q| + 2p <= 3 (A is scaled to entries <= 1).
inline constexpr double kSeparatedMinSpread = 1e-12;

}  // namespace detail

/// Eigenvalues (ascending) and unit eigenvectors (columns) of the symmetric
/// matrix C (only the upper triangle is read). Closed form, no allocation,
/// deterministic; eigenvectors are defined up to sign (and, for repeated
/// eigenvalues, up to rotation within their eigenspace). Non-finite input
/// gives non-finite output; callers check their inputs.
inline Eigen3 eigen_symmetric3(const Eigen::Matrix3d& C) {
  using Kind = detail::SymmetricSplit::Kind;
  Eigen3 out;
  const detail::SymmetricSplit s = detail::split_symmetric3(C);
  if (s.kind == Kind::kNonFinite) {
    out.values.setConstant(std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  if (s.kind == Kind::kScalar) out.values.setConstant(s.q * s.scale);
  if (s.kind != Kind::kGeneral) return out;  // zero or scalar matrix: identity basis
  std::array<double, 3> values;
  std::array<Eigen::Vector3d, 3> vectors;
  detail::ordered_eigenpairs(s, values, vectors);
  for (int i = 0; i < 3; ++i) {
    out.values[i] = values[static_cast<std::size_t>(i)];
    out.vectors.col(i) = vectors[static_cast<std::size_t>(i)];
  }
  return out;
}

/// Unit eigenvector of the smallest or largest eigenvalue of symmetric C:
/// bit for bit eigen_symmetric3(C).vectors.col(0) or col(2), for less. When
/// that eigenvalue is the separated one (a planar neighbourhood's normal, a
/// linear one's direction: most calls) the deflation and the sort are
/// skipped. Non-finite C gives the identity's column, as eigen_symmetric3.
inline Eigen::Vector3d eigenvector_symmetric3(const Eigen::Matrix3d& C, EigenEnd end) {
  const detail::SymmetricSplit s = detail::split_symmetric3(C);
  const bool largest = end == EigenEnd::kLargest;
  if (s.kind != detail::SymmetricSplit::Kind::kGeneral) {
    return largest ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  }
  if (s.sep_is_largest == largest && s.p > detail::kSeparatedMinSpread) return s.v_sep;
  // Else the sorted decomposition decides, but only the one vector is built.
  const detail::Deflation f = detail::deflate(s);
  return detail::deflation_vector(s, f, detail::ascending_order(f.values)[largest ? 2 : 0]);
}

/// eigen_symmetric3(C)'s eigenvalues and only one of its vectors -- column 0
/// (EigenEnd::kSmallest) or 2 (kLargest) -- bit for bit, without computing
/// the others (a residual's line or plane fit reads one; ~10 000 fits a
/// frame). Writes the ascending eigenvalues into values, returns the vector.
inline Eigen::Vector3d eigen_symmetric3_end(const Eigen::Matrix3d& C, EigenEnd end, Eigen::Vector3d& values) {
  using Kind = detail::SymmetricSplit::Kind;
  const detail::SymmetricSplit s = detail::split_symmetric3(C);
  const bool largest = end == EigenEnd::kLargest;
  const Eigen::Vector3d identity_column = largest ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  if (s.kind == Kind::kNonFinite) {
    values.setConstant(std::numeric_limits<double>::quiet_NaN());
    return identity_column;
  }
  values.setZero();
  if (s.kind == Kind::kScalar) values.setConstant(s.q * s.scale);
  if (s.kind != Kind::kGeneral) return identity_column;
  const detail::Deflation f = detail::deflate(s);
  const std::array<int, 3> o = detail::ascending_order(f.values);
  for (std::size_t i = 0; i < 3; ++i) {
    values[static_cast<Eigen::Index>(i)] = f.values[static_cast<std::size_t>(o[i])] * s.scale;
  }
  return detail::deflation_vector(s, f, o[largest ? 2 : 0]);
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

namespace detail {

/// Mean and covariance = (1/N) sum (p - mean)(p - mean)^T of the n >= 1
/// points point_at(0..n-1), two-pass and centred, in double (eq. 3-4).
template <typename PointAt>
void mean_covariance(std::size_t n, PointAt& point_at, Eigen::Vector3d& mean, Eigen::Matrix3d& cov) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) sum += point_at(i).template cast<double>();
  const double inv_n = 1.0 / static_cast<double>(n);
  mean = sum * inv_n;
  // The six distinct entries only (x * y == y * x in IEEE arithmetic, so the
  // mirrored ones are the same bits an outer product would give).
  double xx = 0.0;
  double xy = 0.0;
  double xz = 0.0;
  double yy = 0.0;
  double yz = 0.0;
  double zz = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = point_at(i).template cast<double>() - mean;
    xx += d.x() * d.x();
    xy += d.x() * d.y();
    xz += d.x() * d.z();
    yy += d.y() * d.y();
    yz += d.y() * d.z();
    zz += d.z() * d.z();
  }
  cov << xx * inv_n, xy * inv_n, xz * inv_n,  //
      xy * inv_n, yy * inv_n, yz * inv_n,     //
      xz * inv_n, yz * inv_n, zz * inv_n;
}

}  // namespace detail

/// Fits eq. 3-6 to the n points point_at(0..n-1) (each returning an
/// Eigen::Vector3d or Vector3f): mean, covariance = (1/N) sum (p - mean)(p -
/// mean)^T (two-pass, centred, in double), its eigen-decomposition. Planarity /
/// linearity checks are the caller's (they need their own thresholds).
/// `valid` is false for n < 2 or non-finite points; no allocation.
template <typename PointAt>
LocalShape fit_local_shape(std::size_t n, PointAt point_at) {
  LocalShape shape;
  if (n == 0) return shape;
  Eigen::Matrix3d cov;
  detail::mean_covariance(n, point_at, shape.mean, cov);
  if (n < 2 || !cov.allFinite()) return shape;
  const Eigen3 eig = eigen_symmetric3(cov);
  shape.eigenvalues = eig.values.cwiseMax(0.0);  // a covariance is PSD; clip rounding
  shape.normal = eig.vectors.col(0);
  shape.direction = eig.vectors.col(2);
  shape.valid = true;
  return shape;
}

/// What a residual's fit needs of eq. 3-6: centroid, eigenvalues and one axis.
struct LocalAxisShape {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();         ///< centroid (eq. 3)
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();        ///< unit normal (kSmallest) or line direction (kLargest)
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  ///< of the covariance, ascending [m^2], clipped at 0
  bool valid = false;  ///< as LocalShape::valid
};

/// fit_local_shape(n, point_at)'s mean, eigenvalues, validity and its normal
/// (end = kSmallest) or direction (kLargest), bit for bit, without the other
/// eigenvectors (eigen_symmetric3_end).
template <typename PointAt>
LocalAxisShape fit_local_shape_axis(std::size_t n, PointAt point_at, EigenEnd end) {
  LocalAxisShape shape;
  // LocalShape's defaults for the axis asked for (direction UnitX, normal UnitZ).
  shape.axis = end == EigenEnd::kLargest ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
  if (n == 0) return shape;
  Eigen::Matrix3d cov;
  detail::mean_covariance(n, point_at, shape.mean, cov);
  if (n < 2 || !cov.allFinite()) return shape;
  Eigen::Vector3d values;
  shape.axis = eigen_symmetric3_end(cov, end, values);
  shape.eigenvalues = values.cwiseMax(0.0);
  shape.valid = true;
  return shape;
}

/// One axis of the n points' shape -- the normal (EigenEnd::kSmallest) or
/// the line direction (kLargest) -- bit for bit fit_local_shape(n,
/// point_at)'s, without the rest of the fit (eigenvector_symmetric3): what
/// the associators' per-point axes need. Returns false where
/// fit_local_shape's `valid` is false (axis untouched).
template <typename PointAt>
bool fit_local_axis(std::size_t n, PointAt point_at, EigenEnd end, Eigen::Vector3d& axis) {
  if (n < 2) return false;
  Eigen::Vector3d mean;
  Eigen::Matrix3d cov;
  detail::mean_covariance(n, point_at, mean, cov);
  if (!cov.allFinite()) return false;
  axis = eigenvector_symmetric3(cov, end);
  return true;
}

}  // namespace semlio
