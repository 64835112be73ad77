#pragma once
/// The backward Euler step solved to convergence as a nonlinear least-squares problem by Ceres.
#include <memory>
#include <string>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/options.hpp"

namespace hooke {

/// Which least-squares problem CeresImplicitStepper solves (CeresImplicitOptions::formulation).
enum class CeresFormulation { Residual, Energy };
template <>
struct EnumNames<CeresFormulation> {
  static constexpr std::array<const char*, 2> names = {"residual", "energy"};
};
/// Ceres' linear solver of each Levenberg-Marquardt iteration
/// (CeresImplicitOptions::linear_solver).
enum class CeresLinearSolver { SparseNormalCholesky, DenseQr, Cgnr };
template <>
struct EnumNames<CeresLinearSolver> {
  static constexpr std::array<const char*, 3> names = {"sparse-normal-cholesky", "dense-qr",
                                                       "cgnr"};
};

/// Options of CeresImplicitStepper, fixed for its lifetime. Ceres stops at the first of its three
/// tolerance tests that holds (termination "convergence") or after max_iterations
/// ("no-convergence"); the step is then checked against residual_tolerance.
struct CeresImplicitOptions {
  /// Which least-squares problem Ceres solves (see CeresImplicitStepper for the equations):
  ///   Residual (default): the backward Euler residual G(x1) = M (v1 - v0)/h - f(x1, v1) itself,
  ///     one 3-vector residual block per free particle. The problem has zero residual at the
  ///     solution, so Gauss-Newton is Newton's method on the step: 5-8 iterations per step on the
  ///     12x12 cloth, converged to round-off (|G| ~ 2e-12 N).
  ///   Energy: the incremental potential of Martin et al. 2011 / Liu et al. 2013 as a sum of
  ///     squares. Gauss-Newton drops the geometric stiffness k (1 - L/l) (I - u u^T) of stretched
  ///     springs, so it converges linearly, slowly where tension is large against m / h^2, and
  ///     Ceres' cost-based step acceptance cannot resolve |G| below about sqrt(2 eps cost m / h^2)
  ///     (~1e-7 N). On the 12x12 cloth held at two corners: 40-80 iterations per step, 40-60% of
  ///     the steps NotConverged (residual_tolerance), v1 within 4e-7 of Newton at h = 1e-2 but
  ///     1e-3 off at h = 1/60. An independent formulation for cross-checks, not a tight reference.
  CeresFormulation formulation = CeresFormulation::Residual;
  /// Largest number of Levenberg-Marquardt iterations per step; >= 1. Reaching it makes the
  /// step NotConverged.
  int max_iterations = 100;
  /// Relative cost-change test: |cost_old - cost_new| < function_tolerance * cost_old. Finite,
  /// >= 0 (0 disables it).
  double function_tolerance = 1e-14;
  /// Absolute test on the gradient g of the cost 1/2 |r|^2: ||g||_inf < gradient_tolerance. In the
  /// energy formulation g = G (N); in the residual formulation g = (dG/dx)^T G (N^2/m). Finite,
  /// >= 0 (0 disables it).
  double gradient_tolerance = 1e-14;
  /// Relative step test: ||dx||_2 <= parameter_tolerance * (||x - y||_2 + parameter_tolerance),
  /// with the unknowns x - y in metres (y the inertial prediction). Finite, >= 0 (0 disables it).
  /// The test that normally ends a residual-formulation step once Newton has converged.
  double parameter_tolerance = 1e-14;
  /// After Ceres stops, the step counts as Converged only if the backward Euler residual (with the
  /// system's own forces) satisfies ||G||_inf <= residual_tolerance * (||M (v1 - v0) / h||_inf +
  /// ||f(x1, v1)||_inf) over the free DOFs; otherwise it is NotConverged. Catches a stop away
  /// from the solution (a local minimum of |G|^2, or the energy formulation's floor). Finite, >= 0.
  double residual_tolerance = 1e-6;
  /// Linear solver of each Levenberg-Marquardt iteration: SparseNormalCholesky (J^T J factored
  /// by CHOLMOD through Ceres; the default), DenseQr (tiny problems only: O(n^3)), Cgnr
  /// (conjugate gradients on the normal equations, Jacobi preconditioner; inexact steps, so more
  /// iterations, and poor on the squared conditioning of the residual formulation).
  CeresLinearSolver linear_solver = CeresLinearSolver::SparseNormalCholesky;
  /// Threads Ceres uses for Jacobian evaluation and its linear algebra; >= 1.
  int threads = 1;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// What Ceres reported for the last step (see ceres::Solver::Summary).
struct CeresReport {
  int iterations = 0;              ///< Levenberg-Marquardt iterations (accepted + rejected)
  int successful_steps = 0;        ///< accepted iterations
  int unsuccessful_steps = 0;      ///< rejected iterations (trust region shrunk)
  double initial_cost = 0.0;       ///< 1/2 |r|^2 at the initial guess x = y (J, or N^2)
  double final_cost = 0.0;         ///< 1/2 |r|^2 at the returned x1
  double gradient_max_norm = 0.0;  ///< ||g||_inf of the cost at Ceres' last iteration
  double residual = 0.0;  ///< ||M (v1 - v0) / h - f(x1, v1)||_inf on free DOFs, N (hooke's forces)
  std::string termination;  ///< "convergence", "no-convergence", "failure", ...
  std::string message;      ///< Ceres' termination message
  double seconds = 0.0;     ///< wall time of ceres::Solve, s
};

/// "" if every force of system is one the backend can write as least-squares terms (HookeSpring
/// with k >= 0, Gravity, AirDrag with c >= 0, element sets of the constraint form k/2 C^2), else a
/// message naming the first force that cannot and why (e.g. SpringDamper: axial damping is not the
/// gradient of any function of x1). The same set holds for both formulations. Constraints
/// (colliders, strain limiting) are applied after the step by Simulation and never block it.
std::string ceres_implicit_unsupported(const MassSpringSystem& system);

/// The backward Euler step M (v1 - v0) = h f(x1, v1), x1 = x0 + h v1, solved to convergence by
/// Ceres' Levenberg-Marquardt (a reference for hooke's Newton-iterated "implicit" method with
/// beta = 1). With y = x0 + h v0 + h^2 M^-1 f_ext (f_ext: the constant forces, i.e. gravity) and
/// linear drag f = -C (v - w) (AirDrag), the step is the stationary point of the incremental
/// potential (Martin et al. 2011, "Example-based elastic materials", section 3; Liu et al. 2013,
/// "Fast simulation of mass-spring systems", eq. 3-4, there multiplied by h^2):
///
///   x1 = argmin_x  1/(2 h^2) (x - y)^T M (x - y) + E(x) + 1/(2h) (x - x0 - h w)^T C (x - x0 - h w)
///   E  = sum over Hooke springs k/2 (|x_a - x_b| - L)^2 + sum over elements E_e(x_e),
///
/// whose gradient is G(x) = M (x - y)/h^2 + C (x - x0 - h w)/h - f_springs(x), i.e.
/// M (v1 - v0)/h - f(x1, v1) with v1 = (x - x0)/h. Two least-squares forms (options.formulation):
///
///   energy:   objective = 1/2 |r|^2 with residual blocks (analytic Jacobians)
///               inertia, per free particle i   r = sqrt(m_i) / h (x_i - y_i)        3 x 3
///               spring, per Hooke spring       r = sqrt(k) (|x_a - x_b| - L)        1 x (3 + 3)
///               drag, per free particle (c>0)  r = sqrt(c / h) (x_i - x0_i - h w)    3 x 3
///               element, E_e = k/2 C(x_e)^2    r = sqrt(k) C(x_e)                   1 x 3K
///   residual: r = G(x), per free particle i the 3-vector G_i over the blocks of i and of its
///             spring and element neighbours, Jacobian dG/dx = M/h^2 + C/h - K(x) (exact K, no
///             clamping; the elements' exact Hessian blocks).
///
/// Pinned particles are constant parameter blocks held at x0 (v1 = 0, as in ImplicitStepper).
/// The unknowns are x - y per particle (a contiguous 3n buffer of ours; y is the initial guess),
/// which keeps the residuals' rounding relative to themselves rather than to |x| (not the
/// elements': an element set reads positions, formed as y + dx). (Ceres'
/// check_gradients is not offered: its differences use steps relative to the parameter values,
/// here near 0, and drown in round-off; the tests check the Jacobians by central differences.)
///
/// Supports HookeSpring, Gravity, AirDrag and element sets of the constraint form only (see
/// ceres_implicit_unsupported); constraints
/// are applied by Simulation after the step. This is a reference backend: the ceres::Problem is
/// built once in the constructor and step() only updates the buffers the cost functions read,
/// but ceres::Solve itself allocates and redoes its symbolic analysis on every call, so step() is
/// not allocation-free.
///
/// StepSummary: iterations = newton_iterations = Levenberg-Marquardt iterations of the step;
/// residual = ||M (v1 - v0)/h - f(x1, v1)||_inf over free DOFs in newtons, evaluated with the
/// system's forces after the solve (in the energy formulation it equals Ceres' final gradient
/// max-norm). Ceres NO_CONVERGENCE or a residual above residual_tolerance gives NotConverged;
/// Ceres FAILURE or a non-finite result gives Fatal; each with a message carrying Ceres'
/// termination message, the iterations, the gradient norm and the residual. step() never throws
/// for numerical outcomes.
class CeresImplicitStepper final : public Stepper {
 public:
  using Options = CeresImplicitOptions;
  /// system must be finalized, outlive the stepper and be supported (ceres_implicit_unsupported
  /// returns ""). Throws std::invalid_argument for invalid options or an unsupported system.
  explicit CeresImplicitStepper(const MassSpringSystem& system, CeresImplicitOptions options = {});
  ~CeresImplicitStepper() override;
  CeresImplicitStepper(const CeresImplicitStepper&) = delete;
  CeresImplicitStepper& operator=(const CeresImplicitStepper&) = delete;

  const char* name() const override { return "ceres-implicit"; }
  /// One backward Euler step of size h > 0 from s0 (initial guess x1 = y).
  StepSummary step(const State& s0, double h, State& s1) override;
  /// Steps, Levenberg-Marquardt iterations and the time in ceres::Solve (as solve_seconds).
  StepperStats stats() const override;

  const CeresImplicitOptions& options() const;
  /// Ceres' report of the last step() (default values before the first one).
  const CeresReport& last_report() const;

  /// Number of free (unpinned) particles, i.e. parameter blocks Ceres optimises.
  Index num_free_particles() const;
  /// Total number of scalar residuals of the least-squares problem.
  Index num_residuals() const;
  /// For tests and debugging (allocates): the residual vector r (num_residuals()) and its Jacobian
  /// dr/dx (num_residuals() x 3 num_free_particles(); columns = free particles in increasing id,
  /// three each) of the step from s0 with size h, at positions x (3n vector; pinned entries
  /// ignored: pinned particles sit at s0.x). Row order: energy formulation inertia blocks, springs,
  /// drag blocks; residual formulation G_i of the free particles in increasing id.
  void evaluate(const State& s0, double h, ConstRef x, Vec& residuals, Eigen::MatrixXd& jacobian);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace hooke
