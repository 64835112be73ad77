#pragma once
#include <string>

#include "hooke/core.hpp"

namespace hooke {

class AdaptiveTeam;

/// Options of one solve; they may change on every call.
struct LinearSolveOptions {
  /// Stop when ||b - A x|| <= tolerance * ||b|| (iterative backends; direct ones ignore it).
  double tolerance = 1e-8;
  /// Iteration cap of iterative backends (direct ones ignore it).
  int max_iterations = 10000;
  /// Start from the x passed in (true) or from zero (false). Direct backends ignore it.
  bool warm_start = true;
  /// "" if valid, else a message naming the field, its value and the rule it breaks.
  std::string validate() const;
};

/// What a linear backend reports for analyze, factor and solve calls.
struct LinearSummary {
  Status status = Status::Converged;
  int iterations = 0;          ///< iterations of the last solve (0 for direct backends)
  double residual = 0.0;       ///< ||b - A x|| / ||b|| of the last solve (0 if b = 0)
  double analyze_seconds = 0;  ///< wall time of the symbolic analysis (when it happened)
  double factor_seconds = 0;   ///< wall time of the numeric factorization / refresh
  double solve_seconds = 0;    ///< wall time of the solve
  std::string message;         ///< empty on success, else what failed with its numbers
  /// True when status is BrokeDown because A was found not to be positive definite (a Cholesky
  /// pivot, a curvature p^T A p, or a diagonal entry or block of A that is not positive). The
  /// backend knows only that; the caller, which knows how A was built, says why (see
  /// ImplicitStepper).
  bool not_positive_definite = false;
};

/// Adds s's iterations and times into total (a stepper's sum over its solves).
inline void accumulate(LinearSummary& total, const LinearSummary& s) {
  total.iterations += s.iterations;
  total.analyze_seconds += s.analyze_seconds;
  total.factor_seconds += s.factor_seconds;
  total.solve_seconds += s.solve_seconds;
}

/// A backend for A x = b with A square, sparse (compressed-column, both triangles stored) and,
/// for most backends, symmetric positive definite. Four verbs:
///  - analyze(A): once per sparsity pattern (symbolic work, orderings, colourings, scratch);
///  - factor(A): new values on the analysed pattern, every step (numeric factorization for direct
///    backends, diagonal/preconditioner refresh for iterative ones). A must stay alive and
///    unchanged until the next factor(): iterative backends keep a reference to it;
///  - solve(b, x, options): x is the warm start on entry (if options.warm_start) and the solution
///    on exit; no allocation;
///  - the returned LinearSummary reports status, iterations, residual and times.
/// Must implement all three, for every n including 0: a system with no free DOFs (every particle
/// pinned) gives a 0 x 0 A, which every verb accepts and solves trivially. Options a backend
/// ignores are listed in its class comment.
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Registry name ("cholmod", "pcg", ...).
  virtual const char* name() const = 0;
  /// True if the backend needs A symmetric positive definite to be correct (CG, Cholesky).
  virtual bool requires_spd() const = 0;
  virtual LinearSummary analyze(const SparseMatrix& A) = 0;
  virtual LinearSummary factor(const SparseMatrix& A) = 0;
  virtual LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) = 0;
  /// The positions of the particles whose DOFs are A's unknowns (3 per particle, in A's order),
  /// before each factor(): backends that build a near-null space from the geometry use them
  /// (PETSc GAMG's rigid-body modes); the others ignore them.
  virtual void set_coordinates(ConstRef x) { (void)x; }
  /// False if results depend on state carried from earlier steps that a checkpoint does not hold
  /// (e.g. the age of a reused preconditioner): a resumed run then agrees to tolerance, not bits.
  virtual bool exact_resume() const { return true; }
  /// Direct backends: the cost of one factor() in units of one solve(), estimated after analyze()
  /// from operation counts (deterministic, no timing); 0 if unknown.
  virtual double factor_cost_in_solves() const { return 0.0; }
  /// Numeric factorizations (or preconditioner refactorizations) done so far; 0 for backends
  /// that factor nothing.
  virtual long long factorizations() const { return 0; }
  /// The AdaptiveTeam that chooses the thread count of the backend's iterations (CG), or null:
  /// a stepper runs the rest of its step on the team's present size (TeamStep).
  virtual AdaptiveTeam* team() { return nullptr; }
  const AdaptiveTeam* team() const { return const_cast<LinearSolver*>(this)->team(); }
  /// The threads this backend's solves run on, where it chooses them per solve (CHOLMOD's
  /// supernodal solves, SupernodalSolver::solve): 0, OpenMP's count at each solve (the default), or
  /// a fixed count. Does nothing elsewhere.
  virtual void set_solve_threads(int /*threads*/) {}
};

}  // namespace hooke
