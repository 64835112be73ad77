#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hooke/linear/cholmod/supernodal_solve.hpp"
#include "hooke/linear/linear_solver.hpp"
#include "hooke/options.hpp"

namespace hooke {

/// Options of CholmodSolver fixed for its lifetime.
/// Fill-reducing ordering of CholmodSolver (CholmodOptions::ordering).
enum class CholmodOrdering { Default, Amd, Metis, Natural };
template <>
struct EnumNames<CholmodOrdering> {
  static constexpr std::array<const char*, 4> names = {"default", "amd", "metis", "natural"};
};

struct CholmodOptions {
  /// Fill-reducing ordering: Default (CHOLMOD's choice: AMD, METIS if AMD fills badly), Amd,
  /// Metis (nested dissection; usually best for cloth grids), Natural.
  CholmodOrdering ordering = CholmodOrdering::Default;
  /// Supernodal (true, BLAS-3, fastest for cloth) or simplicial (false) factorization.
  bool supernodal = true;
  /// How much faster a factorization runs than a triangular solve, per flop (> 0): one
  /// factorization counts as fl / (4 nnz(L)) / flop_rate_ratio solves in factor_cost_in_solves(),
  /// which the reuse rule of ReusedFactorization weighs against Krylov iterations (counts, not wall
  /// time, so runs stay deterministic). The default 6 was measured on the 3n x 3n backward-Euler
  /// matrix of the 256 x 256 cloth (problems/scenes/target_backward_euler_256.toml) on a 2-core
  /// AVX-512 machine with one OpenBLAS thread: fl / (4 lnz) = 194 solves' worth of flops, but one
  /// factorization took 3.8 s against 0.11 s for a solve, i.e. 35 solves. A machine whose BLAS-3
  /// runs relatively faster than its memory streams wants a larger value.
  double flop_rate_ratio = 6.0;
  /// The supernodal solves of solve_interleaved read a copy of the factor rounded to single
  /// precision (SupernodalSolver::Precision::Single): half the bytes per sweep, solutions accurate
  /// only to about cond(L) x 6e-8 relative. For callers that correct them (a residual in double).
  bool single_precision_solve = false;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// Sparse Cholesky LL^T of symmetric positive definite A through SuiteSparse CHOLMOD, with the
/// long-index API (cholmod_l_*: the int API overflows on large cloth factors). analyze() does the
/// ordering and symbolic factorization once per pattern; factor() refactorizes new values on it;
/// solve() runs hooke's SupernodalSolver on a supernodal factor (see solve_interleaved; its
/// packed copy of the factor is made after each factorization) and cholmod_l_solve2 on a
/// simplicial one, with workspace kept between calls, so it does not allocate.
/// A not positive definite gives Status::BrokeDown naming the failing column. A 0 x 0 A is not
/// passed to CHOLMOD (which rejects it): analyze, factor and the solves then do nothing.
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
  LinearSummary solve_interleaved(const double* b, double* x, int K) {
    return solve_interleaved(b, x, K, nullptr);
  }
  /// The threads the supernodal solves of solve_interleaved run on (SupernodalSolver::solve):
  /// 0, OpenMP's count at each call (the default), or a fixed count (a caller whose other loops
  /// run on fewer threads than it has, AdaptiveTeam's one thread on a busy machine, can keep the
  /// solves on two: the first does not wait for the second while the kernel has descheduled it).
  void set_solve_threads(int threads) override;
  /// Where solve_interleaved_to_rows writes row r of the solution: x + K rows[r] (one row per
  /// unknown, n in all, distinct). Kept across analyze() and factor().
  void set_solution_rows(std::vector<Index> rows);
  /// solve_interleaved with row r of the solution written at x + K rows[r] (set_solution_rows):
  /// a caller whose unknowns are some rows of a larger vector (the free particles of a state)
  /// needs no pass of its own to place them. x must not alias b. The first call after analyze()
  /// composes the rows with the factor's permutation (allocates); later calls do not allocate.
  LinearSummary solve_interleaved_to_rows(const double* b, double* x, int K);
  /// The factor's supernodal arrays (after factor(); all null if the factor is simplicial). Valid
  /// until the next analyze() or factor().
  SupernodalFactorView supernodal_view() const;
  /// CHOLMOD's flop count of one factorization over 4 nnz(L) (the flops of one solve), divided by
  /// the measured ratio of their flop rates (the factorization runs as BLAS-3, the solve streams
  /// L): see the definition. After analyze().
  double factor_cost_in_solves() const override;
  /// Nonzeros of the factor L (after factor()).
  double factor_nonzeros() const;
  /// factor() calls so far.
  long long factorizations() const override;
  /// For tests: SupernodalSolver::test_helper(flags) on the supernodal solves' solvers, those
  /// made later too.
  void test_helper(int flags);

 private:
  /// solve_interleaved, row k of the factor's order going to x + K x_perm[k] (null: perm[k]).
  LinearSummary solve_interleaved(const double* b, double* x, int K, const std::int64_t* x_perm);

  struct Impl;
  std::unique_ptr<Impl> m;
};

}  // namespace hooke
