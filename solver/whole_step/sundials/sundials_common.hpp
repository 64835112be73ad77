#pragma once
/// Pieces shared by the SUNDIALS whole-step backends (CvodeStepper, IdaStepper) that need no
/// SUNDIALS header, so that the public stepper headers stay free of SUNDIALS types:
///  - SundialsCounters, the cumulative integrator statistics both steppers report;
///  - FirstOrderMatrix, the 6n x 6n compressed-column matrices of the first-order system on
///    y = [x; v] (CVODE's Jacobian, IDA's iteration matrix) with a pattern built once and values
///    refilled from K and D without allocation;
///  - SchurPreconditioner, the preconditioner of the iterative (SPGMR) path, which reduces the
///    6n first-order Newton system to the 3n system M - gamma D - gamma^2 K and solves it with one
///    of hooke's linear backends;
///  - SunPtr, an owning pointer for SUNDIALS handles, and the options checks both share.
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "hooke/integrators/reduced_matrix.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/linear/linear_solver.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/options.hpp"

namespace hooke {

/// Statistics of a SUNDIALS stepper, cumulative over its lifetime: SUNDIALS resets its own counters
/// at every (re)initialisation, the stepper adds them up across restarts.
struct SundialsCounters {
  long steps = 0;      ///< internal integrator steps
  long rhs_evals = 0;  ///< CVODE: evaluations of f(t, y); IDA: of the residual F
  long jacobian_evals =
      0;                   ///< analytic assemblies of K and D (Jacobian, J*v setup, preconditioner)
  long linear_setups = 0;  ///< linear solver setups (KLU refactorizations / preconditioner setups)
  long linear_iterations = 0;     ///< Krylov (SPGMR) iterations; 0 with KLU
  long nonlinear_iterations = 0;  ///< Newton (or fixed-point) iterations
  long nonlinear_conv_fails =
      0;  ///< nonlinear solver convergence failures (each retried with smaller h)
  long error_test_fails = 0;  ///< local error test failures (each retried with smaller h)
  long restarts = 0;          ///< (re)initialisations: the first step, and every step whose s0 was
                              ///< not the state the stepper returned last
  double last_step = 0.0;     ///< size of the last internal step, s (not cumulative)
  int order = 0;              ///< method order for the next internal step (not cumulative)

  /// One line for logs: "steps 812, rhs 1093, jac 64, ...".
  std::string line() const;
  /// Adds the cumulative fields of o (everything except last_step and order).
  void add_totals(const SundialsCounters& o);
};

/// The counters in the form every stepper reports (steps are step() calls: the restarts' count is
/// not that, so steps is left 0 unless the caller knows it).
StepperStats to_stats(const SundialsCounters& c);

/// The last error a SUNDIALS error handler reported, kept in a fixed buffer (the handler runs
/// inside CVODE / IDA and must not allocate). Warnings are counted, not kept.
struct SundialsErrorLog {
  char text[512] = {0};  ///< "function (module): message" of the last error, "" if none
  int code = 0;          ///< its SUNDIALS flag (negative), 0 if none
  long warnings = 0;     ///< warnings reported so far (e.g. "t + h = t")
  /// Forgets the last error (before each integrator call); warnings keep counting.
  void clear() {
    text[0] = 0;
    code = 0;
  }
  /// Records an error (code < 0) or counts a warning (code > 0).
  void record(int error_code, const char* module, const char* function, const char* msg);
};

/// Owning pointer to a SUNDIALS handle (N_Vector, SUNMatrix, SUNLinearSolver, SUNContext, the void*
/// integrator memory) with its free function as a plain function pointer, e.g.
/// SunPtr<N_Vector> y(N_VNew_Serial(n, ctx), [](N_Vector v) { N_VDestroy(v); }).
template <class Handle>
using SunPtr =
    std::unique_ptr<std::remove_pointer_t<Handle>, void (*)(std::remove_pointer_t<Handle>*)>;

/// The sparse 6n x 6n matrices of the first-order form of a mass-spring system, y = [x; v]
/// (x, v 3n vectors), in compressed-column storage whose pattern is built once (construction) and
/// whose values are refilled from K = df/dx and D = df/dv (exact: clamp_compressed = false,
/// damping_position_terms = true) without allocation. P = diag(free) is 1 on free and 0 on pinned
/// DOFs, M the diagonal mass matrix:
///  - Kind::Ode, CVODE's Jacobian J = d/dy of y' = [P v; P M^-1 f(x, v)]:
///        J = [[0, P], [P M^-1 K, P M^-1 D]];
///  - Kind::Dae, IDA's iteration matrix dF/dy + cj dF/dy' of F(y, y') = [x' - P v; M v' - P f]:
///        G = [[cj I, -P], [-P K, cj M - P D]].
/// Pinned particles are kept in the 6n system (no elimination): their rows hold only the diagonal
/// (an explicit 0 in J, so that SUNDIALS forms I - gamma J in place; cj or cj m in G), which makes
/// x' = 0 and v' = 0 for them; their columns keep the K and D entries of free rows, since forces on
/// free particles depend on pinned positions and velocities. Every diagonal entry is stored.
class FirstOrderMatrix {
 public:
  /// Which of the two matrices above.
  enum class Kind { Ode, Dae };
  /// Builds the pattern for a finalized system (which must outlive this object); allocates.
  FirstOrderMatrix(const MassSpringSystem& system, Kind kind);

  Kind kind() const { return m_kind; }
  /// Number of rows and columns, 6n.
  Index size() const { return 2 * m_n3; }
  /// Number of stored entries.
  Index nonzeros() const { return Index(m_rows.size()); }
  /// Column starts (size() + 1 entries) and row indices (nonzeros()), 64-bit as SUNDIALS stores
  /// them; rows are sorted within each column.
  const std::vector<std::int64_t>& column_starts() const { return m_cols; }
  const std::vector<std::int64_t>& row_indices() const { return m_rows; }
  /// P as a 3n vector: 1 for free DOFs, 0 for pinned ones.
  const Vec& free_mask() const { return m_free; }

  /// Assembles the exact K and D at (x, v) (3n each). No allocation.
  void linearize(ConstRef x, ConstRef v);
  /// Writes the nonzeros() values of the matrix at the last linearization into values, with the
  /// given cj (1/s; ignored by Kind::Ode). No allocation.
  void fill(double cj, double* values) const;
  /// Writes the pattern (column starts, row indices) and the values of fill(cj) into the arrays of
  /// a compressed-column matrix with room for nonzeros() entries (e.g. a SUNDIALS sparse matrix:
  /// SUNDIALS zeroes the structure before each Jacobian call, so it is rewritten each time). No
  /// allocation.
  void write(double cj, std::int64_t* column_starts, std::int64_t* row_indices,
             double* values) const;
  /// out = A in for the matrix A at the last linearization and cj (in, out: 6n). Used by the
  /// Jacobian-times-vector callbacks of the iterative path. No allocation.
  void multiply(double cj, ConstRef in, VecRef out);
  /// The matrix at the last linearization and cj as an Eigen sparse matrix (allocates: tests and
  /// debugging only).
  SparseMatrix to_sparse(double cj) const;
  /// Number of linearize() calls so far.
  long linearizations() const { return m_linearizations; }

 private:
  // Value recipe of one stored entry: constant + cj_coef * cj + scale * source, where source is
  // K or D at value index src (K and D share the system's pattern), or nothing.
  enum class Source : char { None, K, D };
  struct Entry {
    int src = -1;
    Source from = Source::None;
    double scale = 0.0;
    double cj_coef = 0.0;
    double constant = 0.0;
  };

  const MassSpringSystem& m_system;
  Kind m_kind;
  Index m_n3 = 0;
  std::vector<std::int64_t> m_cols, m_rows;
  std::vector<Entry> m_entries;
  Vec m_free;     // P (3n)
  Vec m_weight;   // row weight of the K and D blocks: P M^-1 (Ode) or -P (Dae), 3n
  Jacobians m_J;  // exact K, D at the last linearization
  Vec m_tmp;      // 3n scratch of multiply()
  long m_linearizations = 0;
};

/// Preconditioner of the iterative (SPGMR) path: an approximate solve of the first-order Newton
/// system (I - gamma J) z = r with J = [[0, P], [P M^-1 K, P M^-1 D]] (r, z 6n). Eliminating
/// z_x = r_x + gamma P z_v leaves, on the free DOFs,
///     (M - gamma D - gamma^2 K)_ff z_v,f = (M r_v + gamma (K r_x + D r_v,pinned))_f,
/// and pinned rows give z_x = r_x, z_v = r_v. The 3n matrix is assembled with ReducedMatrix from
/// the SPD approximation of K and D (clamp_compressed = true, damping_position_terms = false, as
/// the implicit steppers use) and solved by one of hooke's linear backends, so it is symmetric
/// positive definite and any backend applies; it is exact up to that approximation (and, for an
/// iterative backend, its tolerance). IDA's iteration matrix G = cj diag(I, M) (I - J / cj) uses
/// the same solve with gamma = 1 / cj after scaling r by diag(I, M^-1) / cj.
class SchurPreconditioner {
 public:
  /// backend: a linear backend made by make_linear_solver (its pattern is analysed here);
  /// tolerance, max_iterations: of each backend solve (iterative backends only).
  SchurPreconditioner(const MassSpringSystem& system, std::unique_ptr<LinearSolver> backend,
                      double tolerance, int max_iterations);
  /// Re-linearises at (x, v) (3n each) unless reuse_jacobian, then assembles and factors
  /// M - gamma D - gamma^2 K. gamma in s. No allocation except inside the backend's factor (see
  /// the backend's documentation: CHOLMOD allocates in its numeric factorization).
  LinearSummary setup(ConstRef x, ConstRef v, double gamma, bool reuse_jacobian);
  /// z = (I - gamma J)^-1 r for the gamma of the last setup() (r, z: 6n; may not alias).
  LinearSummary solve(ConstRef r, VecRef z);
  /// The backend's name.
  const char* backend_name() const { return m_backend->name(); }
  /// Number of assemblies of the approximate K and D so far.
  long linearizations() const { return m_linearizations; }

 private:
  const MassSpringSystem& m_system;
  std::unique_ptr<LinearSolver> m_backend;
  LinearSolveOptions m_solve_options;
  Jacobians m_J;  // SPD approximation of K, D
  ReducedMatrix m_A;
  Vec m_pinned;  // 1 - P, 3n
  double m_gamma = 0.0;
  long m_linearizations = 0;
  Vec m_w, m_full, m_rv_pinned;  // 3n scratch
  Vec m_rhs, m_z, m_x_free;      // free-DOF scratch
};

/// Default of SundialsOptions::preconditioner_tolerance (only "spgmr" uses the field).
constexpr double kDefaultPreconditionerTolerance = 1e-10;

/// Linear solver of the Newton iterations of CVODE and IDA (SundialsOptions::linear_solver).
enum class SundialsLinearSolver { Klu, Spgmr };
template <>
struct EnumNames<SundialsLinearSolver> {
  static constexpr std::array<const char*, 2> names = {"klu", "spgmr"};
};

/// The options CvodeOptions and IdaOptions share, fixed for a stepper's lifetime. Error control is
/// SUNDIALS': each internal step keeps the weighted RMS norm of the local error estimate below 1,
/// with weight 1 / (rtol |y_i| + atol) on each of the 6n components of y = [x; v] (x in m, v in
/// m/s).
struct SundialsOptions {
  /// Relative tolerance of the local error test; in (0, 1). The global error is typically 10-100x
  /// larger after many oscillation periods.
  double rtol = 1e-8;
  /// Absolute tolerance (m for positions, m/s for velocities); > 0. Matters for components near 0.
  double atol = 1e-10;
  /// Linear solver of the Newton iterations (6n x 6n):
  ///  - Klu: sparse direct LU (SuiteSparse KLU) of the analytic Jacobian, pattern analysed once,
  ///    refactored when the integrator updates its Newton matrix; the best direct choice in this
  ///    build (SuperLU_MT and LAPACK are not built);
  ///  - Spgmr: restarted GMRES, matrix-free with the analytic product, left-preconditioned by
  ///    SchurPreconditioner (the 3n SPD system M - gamma D - gamma^2 K solved by a hooke linear
  ///    backend); for large meshes, where the 6n LU costs too much.
  SundialsLinearSolver linear_solver = SundialsLinearSolver::Klu;
  /// Linear backend of the SPGMR preconditioner (a name from linear_solvers(), or "none");
  /// "" = default_sundials_preconditioner(). Must stay "" with Klu (rejected otherwise).
  std::string preconditioner;
  /// Relative residual tolerance of each preconditioner solve, when its backend is iterative; in
  /// (0, 1). A loose tolerance makes the preconditioner vary between GMRES iterations.
  double preconditioner_tolerance = kDefaultPreconditionerTolerance;
  /// PETSc options of the preconditioner's KSP and PC when preconditioner = "petsc" (as the
  /// implicit step's petsc_options: "-pc_type gamg"); must stay "" otherwise.
  std::string petsc_options;
  /// Most internal steps per step() call (CVodeSetMaxNumSteps / IDASetMaxNumSteps); >= 1.
  /// Exceeding it returns Status::NotConverged with CV_TOO_MUCH_WORK / IDA_TOO_MUCH_WORK.
  long max_steps = 100000;
  /// The first shared field that breaks a rule, if any; who ("cvode", "ida") starts the message.
  OptionError validate_shared(const char* who) const;
};

/// The linear backend of the preconditioner when options leave it empty: "cholmod" when built
/// (exact solve of the SPD system, so SPGMR sees a fixed linear preconditioner), else "pcg-block".
std::string default_sundials_preconditioner();

/// Makes the preconditioner named by an options struct ("" = default_sundials_preconditioner());
/// nullptr for "none".
std::unique_ptr<SchurPreconditioner> make_schur_preconditioner(const MassSpringSystem& system,
                                                               const SundialsOptions& options);

}  // namespace hooke
