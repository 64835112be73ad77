#pragma once
/// CVODE (SUNDIALS) as a whole-step backend: variable-order, variable-step BDF (or Adams) on the
/// first-order form of a mass-spring system.
#include <memory>
#include <string>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/whole_step/sundials/sundials_common.hpp"

namespace hooke {

/// Statistics of a CvodeStepper (cumulative over its lifetime; see SundialsCounters).
using CvodeCounters = SundialsCounters;

/// Nonlinear solver of CVODE's implicit steps (CvodeOptions::nonlinear_solver).
enum class CvodeNonlinearSolver { Newton, FixedPoint };
template <>
struct EnumNames<CvodeNonlinearSolver> {
  static constexpr std::array<const char*, 2> names = {"newton", "fixed-point"};
};

/// Options of CvodeStepper, fixed for its lifetime: the shared SUNDIALS ones (tolerances, linear
/// solver on I - gamma J, preconditioner, max_steps) and CVODE's own.
struct CvodeOptions : SundialsOptions {
  /// Largest method order: 1..5 for BDF, 1..12 for Adams.
  int max_order = 5;
  /// false: BDF (stiff problems: stiff springs; the default). true: Adams-Moulton (non-stiff
  /// problems only: soft springs, small steps).
  bool adams = false;
  /// Newton (uses linear_solver) or FixedPoint (functional iteration, no linear solves; Adams
  /// only: on a stiff problem it needs steps below the stability limit of the fast springs).
  CvodeNonlinearSolver nonlinear_solver = CvodeNonlinearSolver::Newton;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// Whole steps with CVODE on X = [x; v], X' = [P v; P M^-1 f(x, v)] (6n unknowns; P zeroes the
/// rows of pinned particles, so x' = v' = 0 for them: they are kept in the system, not
/// eliminated; see FirstOrderMatrix). Newton iterations use the analytic Jacobian
/// J = [[0, P], [P M^-1 K, P M^-1 D]] with the exact K and D (clamp_compressed = false,
/// damping_position_terms = true), written into a SUNDIALS CSC matrix whose pattern was built
/// once; or, with "spgmr", the matrix-free product J v. See Hindmarsh et al., "SUNDIALS: Suite of
/// nonlinear and differential/algebraic equation solvers", ACM TOMS 31(3), 2005.
///
/// step(s0, h, s1) integrates from s0.t to s0.t + h in CV_NORMAL mode with the stop time set to
/// s0.t + h (CVODE never steps past it), taking as many internal steps as its error control
/// needs. The CVODE memory persists between calls: if s0 is exactly (t, x, v) the state the
/// previous call returned, CVODE continues with its step size and order history; otherwise (the
/// first call, a constraint moved the state, the caller restarted) it is re-initialised
/// (CVodeReInit: order 1, a new initial step), which costs a few small steps.
///
/// Outcomes (never an exception for a numerical failure):
///  - Converged: s1 is the solution at s0.t + h;
///  - NotConverged: CV_TOO_MUCH_WORK (max_steps), CV_TOO_MUCH_ACC, CV_ERR_FAILURE, CV_CONV_FAILURE:
///    s1 is CVODE's solution at the time it reached (s1.t < s0.t + h), an accurate state;
///  - BrokeDown: the linear solver failed (CV_LSETUP_FAIL, CV_LSOLVE_FAIL);
///  - Fatal: any other flag, a non-finite s0 or h <= 0.
/// The message names the flag, the time reached and the counters. After any failure the next call
/// re-initialises. StepSummary::iterations are the Krylov iterations of the call (0 with KLU),
/// newton_iterations its nonlinear iterations, residual is 0.
///
/// The SUNContext, vectors, matrix, linear solver and CVODE memory are created once in the
/// constructor and freed in the destructor. The callbacks (RHS, Jacobian, J v, preconditioner) do
/// not allocate, and neither do KLU's refactorizations: measured, 50 continued steps of an 8x8
/// cloth allocate nothing with KLU, SPGMR + pcg-block or fixed-point. A restart does: SUNDIALS
/// re-initialises the linear solver after CVodeReInit, so KLU redoes its symbolic analysis (29
/// allocations on that cloth); CHOLMOD as preconditioner allocates in every numeric factorization.
class CvodeStepper final : public Stepper {
 public:
  using Options = CvodeOptions;
  /// system: finalized, must outlive the stepper. Throws std::invalid_argument if
  /// options.validate() fails, std::runtime_error if a SUNDIALS constructor fails.
  explicit CvodeStepper(const MassSpringSystem& system, CvodeOptions options = {});
  /// Frees the SUNDIALS memory, linear solver, matrix, vectors and context, in that order.
  ~CvodeStepper() override;
  /// Not copyable: owns SUNDIALS memory whose callbacks point back at this object.
  CvodeStepper(const CvodeStepper&) = delete;
  CvodeStepper& operator=(const CvodeStepper&) = delete;

  /// Registry name, "cvode".
  const char* name() const override { return "cvode"; }
  /// CVODE's step-size and order history cannot be exported: a resumed run restarts it.
  bool exact_resume() const override { return false; }
  /// Advances s0 by h (s); see the class comment for restarts and outcomes.
  StepSummary step(const State& s0, double h, State& s1) override;

  /// The options the stepper was built with.
  const CvodeOptions& options() const;
  /// Cumulative statistics, updated at the end of every step().
  const CvodeCounters& counters() const;
  /// counters() as one log line.
  std::string counters_line() const;
  std::string report() const override { return counters_line(); }
  /// The counters as StepperStats: internal steps, Newton and Krylov iterations, linear setups.
  StepperStats stats() const override { return to_stats(counters()); }

  /// Test and debugging hook: ydot = f(y) = [P v; P M^-1 f(x, v)] for y = [x; v] (6n each), the
  /// function CVODE integrates. Not to be called during step().
  void rhs(ConstRef y, VecRef ydot);
  /// Test and debugging hook: the analytic Jacobian J = df/dy at y (6n x 6n) as the Jacobian
  /// callback writes it for KLU (allocates). Not to be called during step().
  SparseMatrix jacobian(ConstRef y);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace hooke
