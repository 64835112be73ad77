#pragma once
#include <vector>

#include "hooke/linear/iterative_common.hpp"

namespace hooke {

/// Preconditioners of ConjugateGradientSolver.
enum class Preconditioner {
  None,         ///< plain CG ("cg")
  Jacobi,       ///< inverse diagonal ("pcg")
  BlockJacobi,  ///< inverse 3x3 diagonal blocks ("pcg-block")
};

/// Preconditioned conjugate gradients for symmetric positive definite A (Hestenes-Stiefel, with
/// the preconditioned residual z = P^-1 r). Hand-written rather than Eigen's ConjugateGradient
/// because it must report breakdown: when p^T A p <= 0 (A indefinite, e.g. compressed springs
/// without clamp_compressed) or r^T z <= 0 (preconditioner not SPD), it stops with
/// Status::BrokeDown and says which, instead of returning garbage; and its scratch is owned and
/// reused, so solves do not allocate. Warm starts from x when options.warm_start.
class ConjugateGradientSolver final : public LinearSolver {
 public:
  explicit ConjugateGradientSolver(Preconditioner p) : m_pre(p) {}
  const char* name() const override;
  bool requires_spd() const override { return true; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;

 private:
  void apply_preconditioner(const Vec& r, Vec& z) const;

  Preconditioner m_pre;
  const SparseMatrix* m_A = nullptr;
  std::vector<int> m_diag_pos;
  std::vector<std::array<int, 9>> m_block_pos;
  Vec m_inv_diag;
  std::vector<Mat3> m_inv_blocks;
  Vec m_r, m_z, m_p, m_Ap;
};

}  // namespace hooke
