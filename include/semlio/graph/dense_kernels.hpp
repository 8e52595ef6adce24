#pragma once
/// \file
/// Small dense kernels on runtime-sized views, used by the inertial graph
/// (graph/inertial_graph.hpp). Internal.
///
/// Why: every fixed-size Eigen product expression (15x15, 9x15, 6x15 times
/// their weights, per call site) and every fixed-size SelfAdjointEigenSolver
/// is a separate template instantiation, and GCC 12 spent ~60 s CPU and
/// 1.4 GB on those alone in each translation unit that included the inertial
/// graph (CI measurement, tests/CMakeLists.txt). Here each operation is one
/// plain loop over Eigen::Ref views, compiled once for every shape; the
/// matrices are at most 15x15, so the loops cost nothing at run time either.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace semlio::detail {

/// Read-only view of any column-major dense matrix or vector.
using DenseIn = Eigen::Ref<const Eigen::MatrixXd>;
/// Writable view of a column-major dense matrix, block or vector.
using DenseOut = Eigen::Ref<Eigen::MatrixXd>;

/// Largest dimension the kernels' stack scratch holds.
inline constexpr Eigen::Index kDenseKernelMaxDim = 15;

/// out = A * B (sizes: out m x n, A m x k, B k x n; out must not alias A or B).
inline void set_a_b(DenseOut out, const DenseIn& A, const DenseIn& B) {
  eigen_assert(out.rows() == A.rows() && out.cols() == B.cols() && A.cols() == B.rows());
  for (Eigen::Index j = 0; j < out.cols(); ++j) {
    for (Eigen::Index i = 0; i < out.rows(); ++i) {
      double s = 0.0;
      for (Eigen::Index k = 0; k < A.cols(); ++k) s += A(i, k) * B(k, j);
      out(i, j) = s;
    }
  }
}

/// out += alpha * A^T * W * B (A r x m, W r x r, B r x n, out m x n; r, n <= 15).
inline void add_at_w_b(DenseOut out, const DenseIn& A, const DenseIn& W, const DenseIn& B, double alpha = 1.0) {
  const Eigen::Index r = A.rows();
  const Eigen::Index n = B.cols();
  eigen_assert(W.rows() == r && W.cols() == r && B.rows() == r && out.rows() == A.cols() && out.cols() == n);
  eigen_assert(r <= kDenseKernelMaxDim && n <= kDenseKernelMaxDim);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kDenseKernelMaxDim, kDenseKernelMaxDim> WB(
      r, n);
  set_a_b(WB, W, B);
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = 0; i < out.rows(); ++i) {
      double s = 0.0;
      for (Eigen::Index k = 0; k < r; ++k) s += A(k, i) * WB(k, j);
      out(i, j) += alpha * s;
    }
  }
}

/// out += alpha * A^T * v (A r x m, v and out vectors of r and m).
inline void add_at_v(DenseOut out, const DenseIn& A, const DenseIn& v, double alpha = 1.0) {
  eigen_assert(v.rows() == A.rows() && v.cols() == 1 && out.rows() == A.cols() && out.cols() == 1);
  for (Eigen::Index i = 0; i < A.cols(); ++i) {
    double s = 0.0;
    for (Eigen::Index k = 0; k < A.rows(); ++k) s += A(k, i) * v(k, 0);
    out(i, 0) += alpha * s;
  }
}

/// out += A^T (same sizes transposed; out must not alias A).
inline void add_transposed(DenseOut out, const DenseIn& A) {
  eigen_assert(out.rows() == A.cols() && out.cols() == A.rows());
  for (Eigen::Index j = 0; j < out.cols(); ++j) {
    for (Eigen::Index i = 0; i < out.rows(); ++i) out(i, j) += A(j, i);
  }
}

/// a . b of two vectors of equal length.
inline double dot(const DenseIn& a, const DenseIn& b) {
  eigen_assert(a.cols() == 1 && b.cols() == 1 && a.rows() == b.rows());
  double s = 0.0;
  for (Eigen::Index k = 0; k < a.rows(); ++k) s += a(k, 0) * b(k, 0);
  return s;
}

/// m = 0.5 (m + m^T) in place (square m).
inline void symmetrize(DenseOut m) {
  eigen_assert(m.rows() == m.cols());
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = j + 1; i < m.rows(); ++i) {
      const double v = 0.5 * (m(i, j) + m(j, i));
      m(i, j) = v;
      m(j, i) = v;
    }
  }
}

/// Pseudo-inverse of a symmetric PSD matrix by its eigen-decomposition:
/// V diag(1 / lambda) V^T over the eigenvalues above relative_cut * max(1,
/// max |lambda|) (0 gives "above zero"); the others contribute nothing.
inline Eigen::MatrixXd inverse_spd(const DenseIn& c, double relative_cut) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(c);
  const Eigen::VectorXd& lambda = es.eigenvalues();
  const Eigen::MatrixXd& V = es.eigenvectors();
  const Eigen::Index n = c.rows();
  double max_abs = 1.0;
  for (Eigen::Index k = 0; k < n; ++k) max_abs = std::max(max_abs, std::abs(lambda[k]));
  const double cut = relative_cut * max_abs;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!(lambda[k] > cut)) continue;
    const double inv = 1.0 / lambda[k];
    for (Eigen::Index j = 0; j < n; ++j) {
      const double vj = inv * V(j, k);
      for (Eigen::Index i = 0; i < n; ++i) out(i, j) += V(i, k) * vj;
    }
  }
  return out;
}

}  // namespace semlio::detail
