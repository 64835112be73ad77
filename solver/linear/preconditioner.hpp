#pragma once
#include "hooke/linear/linear_solver.hpp"

namespace hooke {

/// A preconditioner P ~ A for the Krylov backends (ConjugateGradientSolver), named in the
/// preconditioner registry (linear_registry.hpp): a Krylov method and a preconditioner are a pair
/// of names ("pcg" + "nodal" = "pcg-nodal"). Its verbs follow LinearSolver's:
///  - analyze(A): once per sparsity pattern;
///  - setup(A): new values on that pattern, before each solve's first iteration. A preconditioner
///    that is reused across steps may keep its older set-up here (see stale());
///  - apply(r, z): z = P^-1 r, every iteration; no allocation. Its status is checked: anything
///    but Converged stops the solve with that status.
/// Must implement name, analyze, setup and apply. May implement the reuse hooks (solved, stale,
/// refresh), factorizations() and exact_resume(); their defaults describe a preconditioner set up
/// anew by every setup().
class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  /// Registry name ("jacobi", "block", "nodal", ...).
  virtual const char* name() const = 0;
  virtual LinearSummary analyze(const SparseMatrix& A) = 0;
  /// A must stay alive and unchanged until the next setup() (refresh() reads it again).
  virtual LinearSummary setup(const SparseMatrix& A) = 0;
  /// z = P^-1 r (vectors of A's size; z may not alias r).
  virtual Status apply(ConstRef r, VecRef z) = 0;

  /// Told after each solve how many Krylov iterations it took (reuse policies count them).
  virtual void solved(int /*iterations*/) {}
  /// The threads apply() runs on where the preconditioner chooses them (a reused factorization:
  /// LinearSolver::set_solve_threads); 0, OpenMP's count at each call. Does nothing elsewhere.
  virtual void set_apply_threads(int /*threads*/) {}
  /// True if P was set up for an older A than the last setup() call's.
  virtual bool stale() const { return false; }
  /// Sets P up for the last setup() call's A now (after a failed solve with a stale P).
  virtual LinearSummary refresh() { return {}; }
  /// Factorizations done so far (0 for preconditioners that factor nothing).
  virtual long long factorizations() const { return 0; }
  /// False if apply() depends on state from earlier steps that a checkpoint does not hold.
  virtual bool exact_resume() const { return true; }
};

}  // namespace hooke
