#pragma once
/// IDA (SUNDIALS) as a whole-step backend: variable-order, variable-step BDF on the mass-spring
/// equations written as a residual F(t, y, y') = 0.
#include <memory>
#include <string>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/whole_step/sundials/sundials_common.hpp"

namespace hooke {

/// Statistics of an IdaStepper (cumulative over its lifetime; see SundialsCounters; rhs_evals
/// counts residual evaluations).
using IdaCounters = SundialsCounters;

/// Options of IdaStepper, fixed for its lifetime: the shared SUNDIALS ones (tolerances, linear
/// solver on G = dF/dy + cj dF/dy', preconditioner with gamma = 1 / cj, max_steps) and IDA's own.
struct IdaOptions : SundialsOptions {
  /// Largest BDF order, 1..5.
  int max_order = 5;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid).
  OptionError validate() const;
};

/// Whole steps with IDA on y = [x; v] (6n unknowns) and the residual
///     F(t, y, y') = [x' - P v; M v' - P f(x, v)] = 0,
/// where P zeroes the rows of pinned particles (x' = v' = 0 for them: kept in the system, not
/// eliminated; see FirstOrderMatrix). Newton iterations use the analytic iteration matrix
///     G = dF/dy + cj dF/dy' = [[cj I, -P], [-P K, cj M - P D]]
/// with the exact K and D (clamp_compressed = false, damping_position_terms = true), written into
/// a SUNDIALS CSC matrix whose pattern was built once; or, with "spgmr", the product G v. Every
/// (re)start uses the consistent y'(t0) = [P v; P M^-1 f(x, v)] computed from the state, so
/// IDACalcIC is not needed. See Brenan, Campbell and Petzold, "Numerical Solution of
/// Initial-Value Problems in DAEs" (SIAM 1996), and Hindmarsh et al., ACM TOMS 31(3), 2005.
///
/// step(), restarts and outcomes are those of CvodeStepper with IDA's flags: NotConverged for
/// IDA_TOO_MUCH_WORK, IDA_TOO_MUCH_ACC, IDA_ERR_FAIL, IDA_CONV_FAIL (s1 is IDA's solution at the
/// time it reached, s1.t < s0.t + h); BrokeDown for IDA_LSETUP_FAIL, IDA_LSOLVE_FAIL; Fatal
/// otherwise. StepSummary::iterations are Krylov iterations (0 with KLU), newton_iterations the
/// nonlinear iterations of the call, residual is 0.
///
/// All SUNDIALS objects are created in the constructor and freed in the destructor. Allocation
/// behaviour is CvodeStepper's: none in continued steps (callbacks and KLU refactorizations), a
/// new KLU symbolic analysis after each restart. IDA's first steps after a (re)start are tiny
/// (its initial step bounds ||h y'|| in the error norm, and the acceleration's absolute weight is
/// 1/atol), so restarts cost IDA more internal steps than CVODE.
class IdaStepper final : public Stepper {
 public:
  using Options = IdaOptions;
  /// system: finalized, must outlive the stepper. Throws std::invalid_argument if
  /// options.validate() fails, std::runtime_error if a SUNDIALS constructor fails.
  explicit IdaStepper(const MassSpringSystem& system, IdaOptions options = {});
  /// Frees the SUNDIALS memory, linear solver, matrix, vectors and context, in that order.
  ~IdaStepper() override;
  /// Not copyable: owns SUNDIALS memory whose callbacks point back at this object.
  IdaStepper(const IdaStepper&) = delete;
  IdaStepper& operator=(const IdaStepper&) = delete;

  /// Registry name, "ida".
  const char* name() const override { return "ida"; }
  /// IDA's step-size and order history cannot be exported: a resumed run restarts it.
  bool exact_resume() const override { return false; }
  /// Advances s0 by h (s); see the class comment.
  StepSummary step(const State& s0, double h, State& s1) override;

  /// The options the stepper was built with.
  const IdaOptions& options() const;
  /// Cumulative statistics, updated at the end of every step().
  const IdaCounters& counters() const;
  /// counters() as one log line.
  std::string counters_line() const;
  std::string report() const override { return counters_line(); }
  /// The counters as StepperStats: internal steps, Newton and Krylov iterations, linear setups.
  StepperStats stats() const override { return to_stats(counters()); }

  /// Test and debugging hook: F = F(y, yp) = [x' - P v; M v' - P f(x, v)] (6n each), the residual
  /// IDA solves. Not to be called during step().
  void residual(ConstRef y, ConstRef yp, VecRef F);
  /// Test and debugging hook: G = dF/dy + cj dF/dy' at y (6n x 6n; cj in 1/s) as the Jacobian
  /// callback writes it for KLU (allocates). Not to be called during step().
  SparseMatrix iteration_matrix(ConstRef y, double cj);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace hooke
