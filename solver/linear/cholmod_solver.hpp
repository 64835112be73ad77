#pragma once
#include <memory>
#include <string>

#include "hooke/linear/linear_solver.hpp"
#include "hooke/linear/supernodal_solve.hpp"

namespace hooke {

/// Options of CholmodSolver fixed for its lifetime.
struct CholmodOptions {
  /// Fill-reducing ordering: "default" (CHOLMOD's choice: AMD, METIS if AMD fills badly),
  /// "amd", "metis" (nested dissection; usually best for cloth grids), "natural".
  std::string ordering = "default";
  /// Supernodal (true, BLAS-3, fastest for cloth) or simplicial (false) factorization.
  bool supernodal = true;
  std::string validate() const;
};

/// Sparse Cholesky LL^T of symmetric positive definite A through SuiteSparse CHOLMOD, with the
/// long-index API (cholmod_l_*: the int API overflows on large cloth factors). analyze() does the
/// ordering and symbolic factorization once per pattern; factor() refactorizes new values on it;
/// solve() runs hooke's SupernodalSolver on a supernodal factor (see solve_interleaved; its
/// packed copy of the factor is made after each factorization) and cholmod_l_solve2 on a
/// simplicial one, with workspace kept between calls, so it does not allocate.
/// A not positive definite gives Status::BrokeDown naming the failing column.
/// Ignores LinearSolveOptions::tolerance, max_iterations and warm_start (direct method).
class CholmodSolver final : public LinearSolver {
 public:
  explicit CholmodSolver(CholmodOptions options = {});
  ~CholmodSolver() override;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  const char* name() const override { return "cholmod"; }
  bool requires_spd() const override { return true; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;
  /// Solves A X = B for an n x k block of right-hand sides in one cholmod_l_solve2 call, so the
  /// supernodal triangular solves run as BLAS-3 on all k columns at once (the x, y and z columns of
  /// the Liu et al. 2013 global step). B and X are n x k, column-major; X may not alias B. Keeps
  /// its own workspace for the last k used, so repeated calls with the same k do not allocate.
  LinearSummary solve_columns(const Eigen::Ref<const Eigen::MatrixXd>& B,
                              Eigen::Ref<Eigen::MatrixXd> X);
  /// Solves A X = B for K right-hand sides (1..4) stored interleaved: entry c of row r at
  /// [K r + c], as hooke stores x, y, z. A supernodal factor uses the hand-written
  /// SupernodalSolver (faster than cholmod_l_solve2 for few right-hand sides: see its comment); a
  /// simplicial one goes through cholmod_l_solve2 column by column. x may alias b. Does not
  /// allocate after the first call with a given K.
  LinearSummary solve_interleaved(const double* b, double* x, int K);
  /// The factor's supernodal arrays (after factor(); all null if the factor is simplicial). Valid
  /// until the next analyze() or factor().
  SupernodalFactorView supernodal_view() const;
  /// CHOLMOD's flop count of one factorization over 4 nnz(L) (the flops of one solve), divided by
  /// the measured ratio of their flop rates (the factorization runs as BLAS-3, the solve streams L):
  /// see the definition. After analyze().
  double factor_cost_in_solves() const override;
  /// Nonzeros of the factor L (after factor()).
  double factor_nonzeros() const;
  /// factor() calls so far.
  long long factorizations() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

}  // namespace hooke
