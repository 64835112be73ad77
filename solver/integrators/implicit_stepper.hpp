#pragma once
#include <memory>
#include <string>

#include "hooke/integrators/step_doubling.hpp"
#include "hooke/integrators/step_matrix.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/linear/linear_solver.hpp"
#include "hooke/options.hpp"

namespace hooke {

/// The implicit schemes ImplicitStepper implements.
enum class ImplicitScheme {
  /// beta-unified step: M (v1 - v0) = h f(x0 + beta h v1, v0 + beta (v1 - v0)), x1 = x0 + h v1.
  /// One Newton step from (x0, v0) is (M - beta h D - beta h^2 K) dv = h (f0 + beta h K v0):
  /// beta = 0 symplectic Euler, beta = 1 the linearised backward Euler of Baraff and Witkin 1998.
  Beta,
  /// Implicit midpoint on X = [x; v]: x1 = x0 + h (v0 + v1) / 2,
  /// M (v1 - v0) = h f((x0 + x1) / 2, (v0 + v1) / 2). Symplectic, energy-conserving for
  /// quadratic energies.
  Midpoint,
  /// Variable-step BDF2: with w = h / h_prev (the previous step's size),
  /// x1 = a0 x0 + a1 x_prev + b h v1, M (v1 - a0 v0 - a1 v_prev) = b h f(x1, v1), where
  /// a0 = (1 + w)^2 / (1 + 2w), a1 = -w^2 / (1 + 2w), b = (1 + w) / (1 + 2w) (constant steps:
  /// 4/3, -1/3, 2/3). Starts with a backward Euler step, and takes one wherever w exceeds
  /// kBdf2MaxRatio (the formula's zero-stability needs w < 1 + sqrt(2)).
  Bdf2,
};

/// Options of the implicit methods (implicit, implicit-midpoint, bdf2), fixed for a stepper's
/// lifetime.
struct ImplicitOptions {
  /// Linear backend by name (linear_solvers()); "" = default_linear_solver(). The registry makes
  /// the backend from it; ImplicitStepper checks that the backend it is given has this name.
  std::string linear_solver;
  /// With linear_solver = "pcg": its preconditioner by name (preconditioners()), so that a Krylov
  /// method and a preconditioner are a pair of names ("pcg" + "nodal" = "pcg-nodal"); "" = the
  /// backend's own (Jacobi for "pcg"). Must stay "" for every other backend.
  std::string preconditioner;
  /// With linear_solver = "petsc": PETSc options for its KSP and PC ("-pc_type hypre ..."), over
  /// the backend's defaults and under the environment's PETSC_OPTIONS (PetscSolverOptions).
  std::string petsc_options;
  /// beta in [0, 1] (Beta scheme only).
  double beta = 1.0;
  /// Maximum Newton iterations per step; 1 gives the linearised step (no convergence test).
  /// defaults() gives implicit midpoint kMidpointNewtonIterations instead.
  int newton_iterations = 1;
  /// Newton stops when ||delta v||_inf <= newton_tolerance * max(||v1||_inf, ||v0||_inf, 1e-12).
  /// defaults() gives implicit midpoint kMidpointNewtonTolerance instead.
  double newton_tolerance = 1e-10;
  /// Relative residual tolerance and iteration cap of iterative linear backends.
  double linear_tolerance = 1e-8;
  int max_linear_iterations = 10000;
  /// Clamp the indefinite term of compressed springs (see JacobianOptions), keeping A SPD. On by
  /// default for every backend: CG and Cholesky need SPD, and the stationary methods are only
  /// guaranteed to converge for it. Off exposes the exact linearisation (backends then report a
  /// breakdown when A is indefinite).
  bool clamp_compressed = true;
  /// Midpoint scheme: from the second Newton iteration on, the force is the discrete gradient
  /// between x0 and x1 (Force::add_discrete_gradient) instead of f at the midpoint: the step then
  /// converges to the energy-momentum method of Simo and Tarnow 1992, which conserves the energy
  /// of springs and gravity exactly (to the Newton tolerance) and dissipates it with dampers and
  /// drag, where the classical rule gains energy on stiff nonlinear springs and can blow up. The
  /// linearised first iteration is the same either way, so newton_iterations = 1 is unaffected.
  bool discrete_gradient = true;
  /// The first field that breaks a rule, if any (OptionError::ok() when valid). The linear
  /// backend's name is checked by the registry that makes it.
  OptionError validate() const;

  /// Newton iterations and tolerance of implicit midpoint by default: its one-step linearisation
  /// gains energy on stiff cloth until it blows up (the demo cloth: 0 J to 2e4 J by t = 2 s), so
  /// the default iterates the discrete-gradient step. With the clamped Newton matrix the iteration
  /// contracts only linearly on cloth (rates 0.2-0.6 per iteration on the demo cloth), so the
  /// tolerance is looser than newton_tolerance's default: the energy error it leaves is about
  /// 1e-9 of the kinetic energy over the demo cloth's 400 steps.
  static constexpr int kMidpointNewtonIterations = 20;
  static constexpr double kMidpointNewtonTolerance = 1e-8;
  /// The defaults of a scheme: these fields' defaults, with newton_iterations and
  /// newton_tolerance = kMidpointNewtonIterations and kMidpointNewtonTolerance for Midpoint.
  static ImplicitOptions defaults(ImplicitScheme scheme);
};

/// Implicit time steps on a pluggable linear backend. All three schemes are one-leg Newton
/// iterations of the form M (v1 - vb) = hf f(xa + bx v1, va + cv v1), x1 = xe + ex v1, whose
/// Newton matrix is A = M - hf cv D - hf bx K (StepMatrix: pinned DOFs as Dirichlet rows). The
/// first iteration linearises at the step's start (x0, v0), so newton_iterations = 1 reproduces the
/// classical linearised formulas exactly. The linear backend analyses A's pattern once
/// (construction) and refactors per Newton iteration; iterative backends are warm-started from the
/// previous correction. The damper's non-symmetric df/dx is left out of A (Baraff and Witkin 1998
/// do the same), so A is symmetric for every backend; Newton on the exact residual still converges
/// to the same step.
class ImplicitStepper final : public Stepper {
 public:
  ImplicitStepper(const MassSpringSystem& system, ImplicitScheme scheme,
                  std::unique_ptr<LinearSolver> solver, ImplicitOptions options = {});
  const char* name() const override;
  StepSummary step(const State& s0, double h, State& s1) override;
  /// The beta step (p = 1) and the midpoint rule (p = 2) estimate by step doubling (Hairer,
  /// Norsett and Wanner I, II.4): with the estimate on, a step of h is one step of h (y1) and two
  /// of h/2 (y2); the result is the Richardson-extrapolated y2 + (y2 - y1) / (2^p - 1) and the
  /// error estimate (y2 - y1) / (2^p - 1), the error of y2 (the lower-order value is controlled
  /// and the higher-order one kept, as embedded pairs do).
  /// BDF2 (order 2) estimates by Milne's device, for free: the local error is
  /// C / (P - C) (y1 - yp), where yp is the quadratic through the last three committed states,
  /// extrapolated to t + h, and C = -(1 + w)^2 h^3 / (6 w (1 + 2w)) and
  /// P = h (h + h1) (h + h1 + h2) / 6 (h1, h2: the previous steps) are the error constants (of
  /// y''') of the corrector and of the predictor. Under error control BDF2 starts with two
  /// backward Euler steps (so that the predictor has its three states), whose estimate is the
  /// same device on the explicit Euler predictor: -(y1 - y0 - h y0') / 2. Under error control
  /// Newton starts from the predictor (see newton()).
  int error_estimate_order() const override;
  double max_step_ratio() const override;
  double error_norm(double rtol, double atol) override;
  void set_error_estimation(bool on) override;
  const LinearSolver& linear_solver() const { return *m_solver; }
  bool exact_resume() const override {
    return m_solver->exact_resume() && (!m_solver_half || m_solver_half->exact_resume());
  }
  /// Newton iterations, linear iterations, the backend's factorizations and times by phase.
  StepperStats stats() const override;
  std::string report() const override;
  /// The last linear correction on the free DOFs (the warm start of iterative backends), after,
  /// for BDF2, its history: [has_last, last.t, last_t1, last_count, hist[0].t, last.x, last.v,
  /// hist[0].x, hist[0].v] (3n each), and under error control the last step's result [x, v]
  /// (see bdf2_history()). A checkpoint follows an accepted step, so the next step shifts last
  /// into the history and drops hist[1]: it is not stored.
  std::vector<double> history() const override;
  void restore_history(const std::vector<double>& history) override;

 private:
  /// Coefficients of the one-leg form M (v1 - vb) = hf f(xa + bx v1, va + cv v1), x1 = xe + ex v1.
  struct OneLeg {
    double bx, cv, hf, ex;
  };
  /// Sets xa, va, vb, xe for a step of size h from s0 (and BDF2's history); returns the scalars.
  OneLeg set_up(const State& s0, double h);
  /// BDF2: brings the history up to a step of h from s0 (a step from where the last one ended
  /// shifts that step's start in; a retry of the last step keeps the history it had; under error
  /// control, a start state that is not the last step's result starts it anew) and returns the
  /// step's ratio w = h / h_prev, or 0 for a backward Euler step.
  double bdf2_history(const State& s0, double h);
  /// BDF2 under error control: the predictor of a step of h from s0 (m_xp, m_vp) and Milne's
  /// factor C / (P - C); after the step, the local error estimate of s0 -> s1.
  void bdf2_predict(const State& s0, double h);
  void bdf2_estimate(const State& s0, const State& s1);
  /// Forces, Jacobians, the Newton matrix A and the right-hand side (zero on pinned DOFs) at
  /// (xlin, vlin).
  /// With discrete = true (Midpoint), the force is the discrete gradient between x0 and the
  /// current iterate's x1 instead of f(xlin, vlin).
  void assemble(const OneLeg& c, ConstRef x0, bool discrete);
  /// Newton's initial guess v1 (BDF2's predictor under error control, else v0; scripted pins on
  /// their path) and its first linearisation point (xlin, vlin).
  void start_newton(const State& s0, double h, const OneLeg& c);
  /// The step itself on the given backend (step() adds the counters).
  StepSummary newton(const State& s0, double h, State& s1, LinearSolver& solver);
  /// The rate test after Newton iteration k (0-based): why the iteration cannot reach the
  /// tolerance in the iterations left, or "" to go on. failed_predictions counts consecutive
  /// hopeless predictions (updated here).
  std::string newton_hopeless(int k, double delta_norm, double previous_norm, double scale,
                              int& failed_predictions) const;
  /// Step doubling: y1, y2 and the extrapolated result into s1 (see error_estimate_order()).
  StepSummary doubled(const State& s0, double h, State& s1);
  /// Why the current A = M - hf cv D - hf bx K can fail to be positive definite, appended to a
  /// backend's "A is not positive definite" (the backend does not know how A was built).
  std::string not_positive_definite_hint(const OneLeg& c) const;

  const MassSpringSystem& m_system;
  ImplicitScheme m_scheme;
  std::unique_ptr<LinearSolver> m_solver;
  ImplicitOptions m_options;
  JacobianOptions m_jac_options;
  StepMatrix m_A;          // holds K and D, then A over K's values
  LinearSummary m_totals;  // summed over all steps: iterations and times
  double m_assembly_seconds = 0.0, m_total_seconds = 0.0, m_last_residual = 0.0;
  long long m_steps = 0, m_newton_iterations = 0;
  // Scratch, 3n each (m_dv only with a stored D).
  Vec m_v0, m_vb, m_xa, m_va, m_xe, m_v1, m_xlin, m_vlin, m_rhs, m_tmp, m_dx, m_dv;
  Vec m_delta;  // the last linear correction, zero on pinned DOFs
  Vec m_x1;     // the current iterate's x1 (3n; Midpoint with discrete_gradient only)
  // Step doubling (set_error_estimation): the full step y1, the half step and its result y2 (in
  // s1), the step's start and end (for error_norm), and the estimate (3n each).
  bool m_doubling = false;
  // The half steps' own backend (a second instance of m_solver's), so that a backend reusing a
  // factorization across steps (pcg-cholmod, petsc) sees one slowly varying h in each instance
  // instead of h and h/2 in turn; null when the backend is not in the registry (then shared).
  std::unique_ptr<LinearSolver> m_solver_half;
  State m_full, m_half;
  LocalError m_error;  // the estimate, by doubling or (BDF2) Milne's device
  // BDF2 history: committed states before the current step's start, newest first (hist[0] =
  // y_{n-1}, hist[1] = y_{n-2}), and the last step's start, its end
  // time and the count it had (a step that starts at m_last_t1 follows it; one at m_last.t
  // retries it). Velocities with pinned DOFs zeroed, as the steps use them.
  struct Point {
    double t = 0.0;
    Vec x, v;
  };
  Point m_hist[2], m_last;
  double m_last_t1 = 0.0;
  int m_last_count = 0;  // valid states in m_hist when the last step started
  bool m_has_last = false;
  double m_w = 0.0;           // the current BDF2 step's ratio h / h_prev; 0: a backward Euler step
  bool m_estimating = false;  // set_error_estimation(true): m_error holds the estimate
  Vec m_xp, m_vp;             // BDF2 under error control: the predictor (3n each)
  double m_milne = 0.0;       // and Milne's factor C / (P - C)
};

/// The largest step ratio h / h_prev a BDF2 step takes (above it, a backward Euler step):
/// variable-step BDF2 is zero-stable for ratios below 1 + sqrt(2) (Grigorieff 1983; Hairer,
/// Norsett and Wanner I, III.5); 2 leaves a margin and lets a halved step grow back in one step.
constexpr double kBdf2MaxRatio = 2.0;

}  // namespace hooke
