#pragma once
#include <vector>

#include "hooke/linear/iterative_common.hpp"

namespace hooke {

/// Stationary iterations x <- x + P^-1 (b - A x): block Jacobi, Gauss-Seidel and multicolour
/// block Gauss-Seidel. Each solve checks ||b - A x|| / ||b|| after every sweep. It never returns a
/// silently wrong x: reaching max_iterations with a residual that decreased gives NotConverged
/// (an approximate x the caller may use or reject); a residual that grows past 1e6 times its
/// initial value or becomes non-finite means the iteration diverges for this A and gives
/// BrokeDown. They do not need A symmetric positive definite to run, but only converge for
/// suitable A (Gauss-Seidel: SPD is sufficient).
class StationarySolver : public LinearSolver {
 public:
  bool requires_spd() const override { return false; }
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;

 protected:
  /// One sweep updating x in place; r (scratch, n) may be used freely.
  virtual void sweep(ConstRef b, VecRef x) = 0;
  const SparseMatrix* m_A = nullptr;
  Vec m_r;
};

/// Block Jacobi over the 3x3 diagonal (per-particle) blocks: x <- x + D_b^-1 (b - A x), the form
/// cloth solvers use. Parallel-safe by construction. Unlike scalar Jacobi it converges on every
/// implicit-step matrix A = M - h D - h^2 K of springs with clamped (PSD) blocks: 2 D_b - A =
/// M + sum over springs of [[2, 1], [1, 2]] (x) B_s is positive definite, which is the
/// convergence condition for SPD A. Needs a 3n x 3n matrix.
class JacobiSolver final : public StationarySolver {
 public:
  const char* name() const override { return "jacobi"; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;

 protected:
  void sweep(ConstRef b, VecRef x) override;

 private:
  std::vector<std::array<int, 9>> m_block_pos;
  std::vector<Mat3> m_inv_blocks;
};

/// Scalar Gauss-Seidel in natural order (sequential), on a CSR mirror of A.
class GaussSeidelSolver final : public StationarySolver {
 public:
  const char* name() const override { return "gauss-seidel"; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;

 protected:
  void sweep(ConstRef b, VecRef x) override;

 private:
  linear_detail::CsrMirror m_csr;
  std::vector<int> m_diag_pos;  // position of each diagonal entry in A's values
};

/// Multicolour block Gauss-Seidel: particles (3x3 block rows) are greedily coloured so that no two
/// blocks of one colour are coupled; a sweep visits the colours in turn and solves each block row
/// exactly with its inverted diagonal block, in parallel (OpenMP) within a colour. Needs 3x3-block
/// structure (3n x 3n).
class ColoredGaussSeidelSolver final : public StationarySolver {
 public:
  const char* name() const override { return "colored-gauss-seidel"; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;
  /// Number of colours found by analyze().
  int colors() const { return int(m_color_start.size()) - 1; }

 protected:
  void sweep(ConstRef b, VecRef x) override;

 private:
  linear_detail::CsrMirror m_csr;
  std::vector<std::array<int, 9>> m_block_pos;
  std::vector<Mat3> m_inv_blocks;
  std::vector<int> m_color_start, m_order;  // blocks sorted by colour
};

}  // namespace hooke
