#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hooke/linear/iterative_common.hpp"
#include "hooke/linear/preconditioner.hpp"
#include "hooke/parallel/thread_team.hpp"
#include "hooke/sparse/symmetric_product.hpp"

namespace hooke {

/// Preconditioned conjugate gradients for symmetric positive definite A (Hestenes-Stiefel, with
/// the preconditioned residual z = P^-1 r), with any Preconditioner (registry names "pcg-<p>").
/// Hand-written rather than Eigen's ConjugateGradient because it must report breakdown: when
/// p^T A p <= 0 (A indefinite, e.g. compressed springs without clamp_compressed) or r^T z <= 0
/// (preconditioner not SPD), it stops with Status::BrokeDown and says which, instead of returning
/// garbage; and its scratch is owned and reused, so solves do not allocate. Warm starts from x when
/// options.warm_start. A solve that breaks down or misses its tolerance with a stale preconditioner
/// (one reused from an earlier step, see ReusedFactorization) refreshes it and goes on once.
/// The product A p reads A's columns as its rows (SymmetricProduct): A must be symmetric in values,
/// not only positive definite, as CG itself assumes. When the team runs an iteration on one thread
/// (a busy core) and there is a second CPU, the product and a reused factorization's solves still
/// take a helper thread each, which they never wait for (HelpedBins).
class ConjugateGradientSolver final : public LinearSolver {
 public:
  explicit ConjugateGradientSolver(std::unique_ptr<Preconditioner> preconditioner);
  ~ConjugateGradientSolver() override;
  /// "pcg-<preconditioner>", or the short forms "pcg" (Jacobi) and "cg" (none).
  const char* name() const override { return m_name.c_str(); }
  bool exact_resume() const override { return m_pre->exact_resume(); }
  /// The preconditioner's factorizations so far.
  long long factorizations() const override { return m_pre->factorizations(); }
  AdaptiveTeam* team() override { return &m_team; }
  const Preconditioner& preconditioner() const { return *m_pre; }
  bool requires_spd() const override { return true; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;

 private:
  LinearSummary run(ConstRef b, VecRef x, const LinearSolveOptions& options);
  /// z = P^-1 r; false (with s's status and message set) if the preconditioner failed.
  bool precondition(LinearSummary& s);

  std::unique_ptr<Preconditioner> m_pre;
  std::string m_name;
  const SparseMatrix* m_A = nullptr;
  Vec m_r, m_z, m_p, m_Ap;
  SymmetricProduct m_product;  // A p from A's own arrays, by 3x3 blocks when A has them
  // One or all threads per iteration, by their recent times (a busy core): the product and every
  // preconditioner give the same bits on any thread count, so the choice changes timing only.
  AdaptiveTeam m_team;
};

}  // namespace hooke
