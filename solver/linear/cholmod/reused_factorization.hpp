#pragma once
#include <memory>

#include "hooke/linear/preconditioner.hpp"

namespace hooke {

/// A direct solver's factorization of the matrix of an earlier step, reused as the preconditioner
/// of later ones ("cholmod": A's own Cholesky factor; "nodal": NodalPreconditioner's n x n factor).
/// Hecht et al. 2012 and Liu et al. 2017 reuse factorizations across steps in the same spirit:
/// between steps A changes little, so P^-1 A stays close to I and PCG needs a few iterations where
/// Jacobi-PCG needs thousands. The factorization is refreshed when that pays, by the renewal rule:
/// refactor before a step once the last solve cost more than the average cost per step since the
/// last refactorization, factorization included. Costs are counted in Krylov iterations (never in
/// wall time, so runs stay deterministic); a factorization costs
/// LinearSolver::factor_cost_in_solves() iterations, or 50 if the direct solver gives no estimate.
/// Its age is not in a checkpoint, so exact_resume() is false.
class ReusedFactorization final : public Preconditioner {
 public:
  /// direct: the solver whose factorization is reused (analyze / factor / solve on A).
  explicit ReusedFactorization(std::unique_ptr<LinearSolver> direct);
  const char* name() const override { return m_direct->name(); }
  LinearSummary analyze(const SparseMatrix& A) override;
  /// Applies the renewal rule: refactors on A, or keeps the factorization of an earlier A.
  LinearSummary setup(const SparseMatrix& A) override;
  Status apply(ConstRef r, VecRef z) override;
  void solved(int iterations) override;
  void set_apply_threads(int threads) override { m_direct->set_solve_threads(threads); }
  bool stale() const override { return !m_fresh; }
  LinearSummary refresh() override;
  long long factorizations() const override { return m_factorizations; }
  bool exact_resume() const override { return false; }
  /// What one factorization counts for in the renewal rule, in Krylov iterations (after analyze()).
  double factor_cost() const { return m_factor_cost; }

 private:
  std::unique_ptr<LinearSolver> m_direct;
  const SparseMatrix* m_A = nullptr;  // the matrix of the last setup()
  double m_factor_cost = 50.0;        // one factorization, in Krylov iterations
  double m_cost_since = 0.0;          // factorization + iterations since it
  int m_steps_since = 0, m_last_iterations = 0;
  long long m_factorizations = 0;
  bool m_fresh = false;  // the factorization is of the current A
};

}  // namespace hooke
