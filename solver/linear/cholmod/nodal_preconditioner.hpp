#pragma once
#include <array>
#include <memory>
#include <vector>

#include "hooke/linear/cholmod/cholmod_solver.hpp"
#include "hooke/linear/linear_solver.hpp"

namespace hooke {

/// A preconditioner for the 3n x 3n matrices of implicit steps (3x3 blocks per particle pair,
/// rows 3p .. 3p+2 for particle p): the nodal matrix N (n x n) with N_pq = tr(A_pq) / 3, applied
/// to the three coordinates at once as N (x) I3 through an n x n CHOLMOD factorization (METIS
/// ordering) and hooke's supernodal solves with three interleaved right-hand sides.
///
/// N = (A_xx + A_yy + A_zz) / 3 is the mean of three principal submatrices of A, so it is
/// symmetric positive definite whenever A is. For springs it replaces each spring's 3x3 block by
/// its isotropic part, the same shape as the prefactored global matrix M/h^2 + L of Liu et al. 2013
/// that the issue-7 brief names as a preconditioner. Each entry of N stands for a 3x3 block of A,
/// so its factor has about a ninth of the entries of A's own (pcg-cholmod's; 1/8.9 on a 48x48
/// cloth, tested) and fits where A's factor does not (the 6M-spring cloth). It is not a solver for
/// A: solve() returns (N (x) I3)^-1 b. Use it as ConjugateGradientSolver's factorization
/// ("pcg-nodal"); it is not registered on its own. Ignores LinearSolveOptions (direct method).
/// Requires A.rows() to be a multiple of 3.
class NodalPreconditioner final : public LinearSolver {
 public:
  NodalPreconditioner();
  ~NodalPreconditioner() override;
  const char* name() const override { return "nodal"; }
  bool requires_spd() const override { return true; }
  /// Builds N's pattern (both triangles) and the map from A's entries to it; analyses N.
  LinearSummary analyze(const SparseMatrix& A) override;
  /// N's values from A's diagonal entries of each block; factors N.
  LinearSummary factor(const SparseMatrix& A) override;
  /// x = (N (x) I3)^-1 b (3n vectors, particle-major: x, y, z of each particle); x may alias b.
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;
  double factor_cost_in_solves() const override { return m_chol.factor_cost_in_solves(); }
  void set_solve_threads(int threads) override { m_chol.set_solve_threads(threads); }
  /// Entries of N's Cholesky factor (after factor()).
  double factor_nonzeros() const { return m_chol.factor_nonzeros(); }
  /// The nodal matrix of the last factor() (n x n, both triangles).
  const SparseMatrix& nodal_matrix() const { return m_N; }

 private:
  SparseMatrix m_N;
  std::vector<std::array<Index, 3>>
      m_from;  // per entry of N: A's x-x, y-y, z-z positions (-1: none)
  CholmodSolver m_chol;
};

}  // namespace hooke
