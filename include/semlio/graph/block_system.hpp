#pragma once
/// \file
/// Block-sparse symmetric normal equations (H + lambda D) dx = -g for the pose
/// graph, solved with Eigen's sparse LDL^T (SimplicialLDLT, AMD ordering).
/// Internal to the graph solver.
///
/// The sparsity pattern is built once per solve; afterwards every factor adds
/// its blocks straight into the compressed storage through precomputed value
/// offsets, so re-linearisation allocates nothing. Only the lower triangle is
/// read by the factorisation (diagonal blocks are stored whole).

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

namespace semlio::detail {

/// Outcome of a factorisation.
enum class FactorStatus { ok, failed, singular };

/// Symmetric system over `num_blocks` variables of dimension D each.
template <int D>
class BlockSystem {
 public:
  using Block = Eigen::Matrix<double, D, D>;
  using Sparse = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  using Solver = Eigen::SimplicialLDLT<Sparse, Eigen::Lower, Eigen::AMDOrdering<int>>;

  BlockSystem() = default;
  /// Copies start empty: the system is scratch, rebuilt by every solve.
  BlockSystem(const BlockSystem& /*other*/) {}
  /// Assignment keeps this object's (scratch) state.
  BlockSystem& operator=(const BlockSystem& /*other*/) { return *this; }
  BlockSystem(BlockSystem&&) noexcept = default;
  BlockSystem& operator=(BlockSystem&&) noexcept = default;
  ~BlockSystem() = default;

  /// Starts a new pattern with num_blocks block rows / columns.
  void begin_pattern(std::size_t num_blocks) {
    num_blocks_ = num_blocks;
    triplets_.clear();
    for (std::size_t b = 0; b < num_blocks; ++b) add_triplets(b, b);
  }

  /// Declares block (r, c); the pair is stored with r >= c.
  void declare(std::size_t r, std::size_t c) {
    if (r < c) std::swap(r, c);
    if (r != c) add_triplets(r, c);
  }

  /// Builds the compressed matrix and the symbolic factorisation.
  void end_pattern() {
    const auto n = static_cast<Eigen::Index>(num_blocks_ * D);
    H_.resize(n, n);
    H_.setFromTriplets(triplets_.begin(), triplets_.end());
    H_.makeCompressed();
    A_ = H_;
    diag_.resize(static_cast<std::size_t>(n));
    for (Eigen::Index k = 0; k < n; ++k) diag_[static_cast<std::size_t>(k)] = find(k, k);
    g_.setZero(n);
    if (!ldlt_) ldlt_ = std::make_unique<Solver>();
    ldlt_->analyzePattern(A_);
  }

  /// Handle of block (r, c) for add(): the value offset of its first entry
  /// in each of its D columns, stored at handles[base .. base + D).
  [[nodiscard]] std::array<int, D> handle(std::size_t r, std::size_t c) const {
    std::array<int, D> out{};
    for (int k = 0; k < D; ++k)
      out[static_cast<std::size_t>(k)] =
          find(static_cast<Eigen::Index>(r * D), static_cast<Eigen::Index>(c * D + static_cast<std::size_t>(k)));
    return out;
  }

  /// Zeroes H and g before a linearisation.
  void zero() {
    std::fill(H_.valuePtr(), H_.valuePtr() + H_.nonZeros(), 0.0);
    g_.setZero();
  }

  /// H(block) += B, with the handle of that block.
  void add(const std::array<int, D>& h, const Block& B) {
    double* v = H_.valuePtr();
    for (int k = 0; k < D; ++k) {
      double* col = v + h[static_cast<std::size_t>(k)];
      for (int m = 0; m < D; ++m) col[m] += B(m, k);
    }
  }

  /// Gradient vector g (dimension num_blocks * D).
  Eigen::VectorXd& g() { return g_; }
  /// H * x for the predicted cost decrease.
  [[nodiscard]] double quadratic(const Eigen::VectorXd& x) const {
    return x.dot(H_.template selfadjointView<Eigen::Lower>() * x);
  }

  /// Factorises H + lambda * diag(clamp(H_kk, 1e-6, 1e32)). With lambda == 0
  /// also checks the pivots: a pivot <= pivot_ratio * max pivot means the
  /// system is singular; `degenerate_row` then names its (unpermuted) row.
  FactorStatus factorize(double lambda, double pivot_ratio, Eigen::Index* degenerate_row) {
    std::copy(H_.valuePtr(), H_.valuePtr() + H_.nonZeros(), A_.valuePtr());
    if (lambda > 0.0) {
      double* a = A_.valuePtr();
      const double* h = H_.valuePtr();
      for (const int d : diag_) {
        a[d] = h[d] + lambda * std::clamp(h[d], 1e-6, 1e32);
      }
    }
    ldlt_->factorize(A_);
    if (ldlt_->info() != Eigen::Success) {
      if (degenerate_row != nullptr) *degenerate_row = weakest_diagonal(pivot_ratio);
      return lambda > 0.0 ? FactorStatus::failed : FactorStatus::singular;
    }
    if (lambda == 0.0) {
      const Eigen::VectorXd& D_piv = ldlt_->vectorD();
      const double max_d = D_piv.size() > 0 ? D_piv.cwiseAbs().maxCoeff() : 0.0;
      for (Eigen::Index k = 0; k < D_piv.size(); ++k) {
        if (!std::isfinite(D_piv[k]) || !(D_piv[k] > pivot_ratio * max_d)) {
          if (degenerate_row != nullptr) *degenerate_row = ldlt_->permutationPinv().indices()(k);
          return FactorStatus::singular;
        }
      }
    }
    return FactorStatus::ok;
  }

  /// First row whose diagonal entry is <= ratio * the largest one, or -1
  /// (best-effort diagnosis when the factorisation itself failed).
  [[nodiscard]] Eigen::Index weakest_diagonal(double ratio) const {
    double max_d = 0.0;
    for (const int d : diag_) max_d = std::max(max_d, std::abs(H_.valuePtr()[d]));
    for (std::size_t k = 0; k < diag_.size(); ++k) {
      if (!(H_.valuePtr()[diag_[k]] > ratio * max_d)) return static_cast<Eigen::Index>(k);
    }
    return -1;
  }

  /// Solves (H + lambda D) dx = -g with the last factorisation.
  void solve(Eigen::VectorXd& dx) const { dx = ldlt_->solve(-g_); }

 private:
  void add_triplets(std::size_t r, std::size_t c) {
    for (int k = 0; k < D; ++k) {
      for (int m = 0; m < D; ++m) {
        triplets_.emplace_back(static_cast<int>(r * D) + m, static_cast<int>(c * D) + k, 0.0);
      }
    }
  }

  [[nodiscard]] int find(Eigen::Index row, Eigen::Index col) const {
    const int* inner = H_.innerIndexPtr();
    const int* begin = inner + H_.outerIndexPtr()[col];
    const int* end = inner + H_.outerIndexPtr()[col + 1];
    const int* it = std::lower_bound(begin, end, static_cast<int>(row));
    return static_cast<int>(it - inner);
  }

  std::size_t num_blocks_ = 0;
  std::vector<Eigen::Triplet<double, int>> triplets_;
  Sparse H_;
  Sparse A_;
  std::vector<int> diag_;
  Eigen::VectorXd g_;
  std::unique_ptr<Solver> ldlt_;  // unique_ptr: Eigen's solvers are not movable
};

}  // namespace semlio::detail
