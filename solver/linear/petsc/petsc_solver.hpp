#pragma once
#include <memory>
#include <string>

#include "hooke/linear/linear_solver.hpp"
#include "hooke/model/distribution.hpp"

namespace hooke {

/// Settings of the PETSc backend (ImplicitOptions::petsc_options, scene key
/// [integrator] petsc_options).
struct PetscSolverOptions {
  /// PETSc options for this solver's KSP and PC, as on a PETSc command line:
  /// "-ksp_type cg -pc_type hypre -pc_hypre_type boomeramg". They override the defaults
  /// (kPetscDefaultOptions); the environment variable PETSC_OPTIONS overrides them in turn.
  std::string options;
  /// -ksp_view prints the solver once, after its first solve (false: never, for probes).
  bool view = true;
  /// The piece of a distributed system the matrices belong to (issue 17), or nullptr (a whole
  /// system on this process alone). See PetscSolver. Must outlive the solver.
  const Distribution* distribution = nullptr;
};

/// The defaults: CG on the true residual, preconditioned by one algebraic multigrid V-cycle per
/// coordinate (PCFIELDSPLIT, additive, over the x, y and z unknowns of the particles, each split
/// a hypre BoomerAMG on its scalar matrix A_xx, A_yy or A_zz). With two or more threads (and MPI
/// initialised for concurrent calls, as this backend asks for) the three splits are applied
/// concurrently, with the same results as PCFIELDSPLIT's one after another: hypre's V-cycle is
/// serial, and this takes about a quarter off a step (hooke run target_backward_euler_256 --set
/// mesh.nx=408 --set mesh.ny=408 --set integrator.linear_solver=petsc --set time.duration=0.03,
/// 2 threads: 0.82-0.86 s per warm step, against 1.16-1.20 s with --set
/// integrator.petsc_options=-log_view, which applies the splits one after another). Any other
/// preconditioner, other splits, or -log_view (PETSc's event log is not thread-safe) keep PETSc's
/// own application. Measured on the backward-Euler target (hooke run target_backward_euler_256
/// --set integrator.linear_solver=petsc --set time.duration=0.03, and --set mesh.nx=N --set
/// mesh.ny=N for the other sizes; one rank): 11 iterations and 0.47 s per step at 256 x 256 (the
/// splits in turn), 12 at 512 x 512, 12 to 14 at 1000 x 1000, where
/// smoothed aggregation on the coupled matrix (-pc_type gamg, with the Chebyshev and point-block
/// Jacobi smoothing below) needs 35 to 45 iterations at 2.3 s per step at 256 x 256, and BoomerAMG
/// on the coupled matrix 9 iterations at about 1.5 s. For -pc_type gamg the defaults smooth with
/// Chebyshev and point-block Jacobi (the 3 x 3 particle blocks): GAMG's default point-Jacobi
/// smoother cannot handle the nearly rank-deficient particle blocks of a cloth (1384 iterations at
/// 256 x 256 against 40). -hooke_rigid_body_modes adds the rigid-body near-null space of the
/// particles' positions to GAMG (off by default: with point-block Jacobi on every level its coarse
/// 6 x 6 blocks are singular). -hooke_setup_cost N sets what one preconditioner set-up counts for
/// in the renewal rule, in Krylov iterations (default kSetupCostInIterations; about 10 for GAMG).
inline constexpr const char* kPetscDefaultOptions =
    "-ksp_type cg -ksp_norm_type unpreconditioned -pc_type fieldsplit -pc_fieldsplit_block_size 3 "
    "-pc_fieldsplit_type additive -fieldsplit_0_pc_type hypre -fieldsplit_1_pc_type hypre "
    "-fieldsplit_2_pc_type hypre -mg_levels_ksp_type chebyshev -mg_levels_pc_type pbjacobi";

/// "" if `options` is a valid PETSc option string for this backend, else why not, naming the
/// option (an unknown type such as -pc_type no_such_pc, a malformed value, or an option no
/// PETSc object read, e.g. a misspelt name). Checked by setting up a solver on a small system.
std::string petsc_options_problem(const std::string& options);

/// Linear backend on PETSc's KSP/PC (serial, one rank), for A symmetric positive definite with
/// 3 x 3 blocks (one per free particle):
///  - the Krylov method multiplies by A with hooke's row-parallel product (a MATSHELL: PETSc's
///    AIJ product is serial within a rank); the preconditioner is built from the AIJ matrix;
///  - analyze() makes a PETSc AIJ matrix of block size 3 on A's own arrays (for a symmetric A,
///    Eigen's compressed columns are the compressed rows PETSc stores): no copy of the matrix, no
///    MatSetValues, no triplets; the values the caller assembles into A are PETSc's, and
///    factor() only tells PETSc that they changed; solve() wraps b and x without copies;
///  - set_coordinates() gives the positions from which the rigid-body near-null space of GAMG is
///    built (MatNullSpaceCreateRigidBody) when the options include -hooke_rigid_body_modes;
///  - the preconditioner (the multigrid hierarchy) is reused across factor() calls and rebuilt by
///    the renewal rule of ReusedFactorization, counted in Krylov iterations: rebuild once the last
///    solve cost more than the average per solve since the last build, the build included (which
///    counts kSetupCostInIterations);
///  - LinearSolveOptions::tolerance and max_iterations map onto -ksp_rtol and -ksp_max_it unless
///    the options give those explicitly; warm_start onto a nonzero initial guess.
/// A PETSc error (including an invalid option) is Status::Fatal with PETSc's message; a KSP that
/// diverges (e.g. indefinite A: DIVERGED_INDEFINITE_PC / _MAT) is BrokeDown with the reason.
/// The age of the hierarchy is not in a checkpoint: exact_resume() is false.
///
/// With PetscSolverOptions::distribution (issue 17), A is the step matrix of one process's piece
/// of a distributed system and every call is collective: the solver works on PETSC_COMM_WORLD
/// with an MPI AIJ matrix of the piece's owned rows (copied from A at each factor(), since a
/// piece's other rows are partial), PETSc's own product, the same options and renewal rule, and
/// after each solve the ghosts' unknowns from their owners (Distribution::complete). -ksp_view
/// and -log_view print once, on rank 0.
class PetscSolver final : public LinearSolver {
 public:
  /// What one preconditioner set-up counts for in the renewal rule, in Krylov iterations, with
  /// the defaults (-hooke_setup_cost overrides it). Measured with hooke run
  /// target_backward_euler_256 --set integrator.linear_solver=petsc --set
  /// integrator.petsc_options=-log_view --set time.duration=0.05: PCSetUp 0.135 s for the three
  /// BoomerAMG hierarchies against 37 ms per CG iteration (about 3.6); at 1000 x 1000 the first
  /// step costs about 2.4 iterations more than the next. (GAMG: 0.83 s over 3 set-ups against
  /// 57 ms per iteration, about 10.)
  static constexpr double kSetupCostInIterations = 3.0;

  explicit PetscSolver(PetscSolverOptions options = {});
  ~PetscSolver() override;
  PetscSolver(const PetscSolver&) = delete;
  PetscSolver& operator=(const PetscSolver&) = delete;

  const char* name() const override { return "petsc"; }
  bool requires_spd() const override { return true; }
  LinearSummary analyze(const SparseMatrix& A) override;
  LinearSummary factor(const SparseMatrix& A) override;
  LinearSummary solve(ConstRef b, VecRef x, const LinearSolveOptions& options) override;
  void set_coordinates(ConstRef x) override;
  bool exact_resume() const override { return false; }
  long long factorizations() const override;
  /// The options of this solver's database that no PETSc object has read so far (a misspelt
  /// name, or an option of another type than the one chosen), space-separated; "" if none. The
  /// defaults are not counted (a user's -pc_type hypre leaves the GAMG smoother's unread).
  std::string unused_options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

}  // namespace hooke
