#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hooke/linear/iterative_common.hpp"

namespace hooke {

/// Preconditioners of ConjugateGradientSolver.
enum class Preconditioner {
  None,         ///< plain CG ("cg")
  Jacobi,       ///< inverse diagonal ("pcg")
  BlockJacobi,  ///< inverse 3x3 diagonal blocks ("pcg-block")
  Factorization,  ///< a direct factorization of an earlier A, reused across steps ("pcg-cholmod")
};

/// Preconditioned conjugate gradients for symmetric positive definite A (Hestenes-Stiefel, with
/// the preconditioned residual z = P^-1 r). Hand-written rather than Eigen's ConjugateGradient
/// because it must report breakdown: when p^T A p <= 0 (A indefinite, e.g. compressed springs
/// without clamp_compressed) or r^T z <= 0 (preconditioner not SPD), it stops with
/// Status::BrokeDown and says which, instead of returning garbage; and its scratch is owned and
/// reused, so solves do not allocate. Warm starts from x when options.warm_start.
///
/// Preconditioner::Factorization (Hecht et al. 2012 and Liu et al. 2017 reuse factorizations
/// across steps in the same spirit): the preconditioner is a direct solver's factorization of the
/// matrix of an earlier step. Between steps A changes little, so P^-1 A stays close to I and PCG
/// needs a few iterations where Jacobi-PCG needs thousands; the factorization is refreshed when
/// that pays, by the renewal rule: refactor before a step once the last solve cost more than the
/// average cost per step since the last refactorization, factorization included. Costs are counted
/// in PCG iterations (never in wall time, so runs stay deterministic); a factorization costs
/// LinearSolver::factor_cost_in_solves() iterations (or 50 if the direct solver gives no estimate). A solve that breaks down
/// or misses its tolerance with a stale factorization refactors and retries once.
class ConjugateGradientSolver final : public LinearSolver {
 public:
  explicit ConjugateGradientSolver(Preconditioner p) : m_pre(p) {}
  /// Preconditioner::Factorization with this direct solver (e.g. CholmodSolver).
  explicit ConjugateGradientSolver(std::unique_ptr<LinearSolver> factorization);
  ~ConjugateGradientSolver() override;
  const char* name() const override;
  bool exact_resume() const override { return m_pre != Preconditioner::Factorization; }
  /// Factorizations so far (Preconditioner::Factorization).
  long long factorizations() const override { return m_factorizations; }
  /// What one factorization counts for in the renewal rule, in PCG iterations (after analyze()).
  double factor_cost() const { return m_factor_cost; }
  bool requires_spd() const override { return true; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;

 private:
  void apply_preconditioner(const Vec& r, Vec& z) const;
  LinearSummary run(ConstRef b, VecRef x, const LinearSolveOptions& options);
  LinearSummary refactor();

  Preconditioner m_pre;
  std::unique_ptr<LinearSolver> m_factorization;
  std::string m_name;
  double m_factor_cost = 50.0;      // one factorization, in PCG iterations
  double m_cost_since = 0.0;        // factorization + iterations since it
  int m_steps_since = 0, m_last_iterations = 0, m_factorizations = 0;
  bool m_fresh = false;             // the factorization is of the current A
  const SparseMatrix* m_A = nullptr;
  std::vector<int> m_diag_pos;
  std::vector<std::array<int, 9>> m_block_pos;
  Vec m_inv_diag;
  std::vector<Mat3> m_inv_blocks;
  Vec m_r, m_z, m_p, m_Ap;
  linear_detail::CsrMirror m_csr;  // A by rows: the product A p, parallel and deterministic
};

}  // namespace hooke
