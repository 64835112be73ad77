#pragma once
#include <limits>
#include <string>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// What one time step reports. Explicit steps always converge with 0 iterations; implicit and
/// whole-step backends fill iterations (linear or nonlinear, as documented by each) and residual.
struct StepSummary {
  Status status = Status::Converged;
  int iterations = 0;         ///< linear solver iterations spent in this step (summed over Newton)
  int newton_iterations = 0;  ///< Newton iterations (implicit methods; 0 for explicit ones)
  double residual = 0.0;      ///< final residual norm of the step's solve (0 if none)
  std::string message;  ///< empty on success; says what failed and with which numbers otherwise
};

/// What a stepper has done since it was made, cumulative over all its steps (in the spirit of
/// Ceres' Solver::Summary and MuJoCo's timers): one type for every method, so studies and
/// benchmarks read work and time without knowing the concrete stepper. A field a method has no use
/// for stays 0.
struct StepperStats {
  long long steps = 0;              ///< step() calls
  long long internal_steps = 0;     ///< steps of adaptive integrators (CVODE, IDA); else 0
  long long iterations = 0;         ///< outer iterations: Newton (implicit methods, CVODE, IDA),
                                    ///< local/global iterations, XPBD substeps x sweeps, Ceres LM
  long long linear_iterations = 0;  ///< iterations of iterative linear solvers (CG, GMRES)
  long long factorizations = 0;  ///< numeric factorizations (or matrix refreshes) of linear solvers
  double last_residual = 0.0;    ///< residual of the last step's solve (its units: see StepSummary)
  double assembly_seconds = 0.0;     ///< forces and Jacobian values (s)
  double analyze_seconds = 0.0;      ///< symbolic analysis of sparsity patterns (s)
  double factor_seconds = 0.0;       ///< numeric factorizations and preconditioner set-up (s)
  double solve_seconds = 0.0;        ///< linear solves (s)
  double local_seconds = 0.0;        ///< local steps of local/global methods (s)
  double global_seconds = 0.0;       ///< global steps of local/global methods (s)
  double contact_seconds = 0.0;      ///< contact distances, barrier, friction and CCD (s; not in
                                     ///< assembly_seconds)
  double ccd_seconds = 0.0;          ///< of contact_seconds: continuous collision detection (s)
  double broad_phase_seconds = 0.0;  ///< of contact_seconds: self-contact's broad phase (s)
  long long contact_pattern_builds = 0;  ///< Newton matrix patterns built for self-contact
  double total_seconds = 0.0;    ///< wall time inside step() (s); 0 if the method does not time it
  double factor_nonzeros = 0.0;  ///< entries of the current factor (direct global solves)
};

/// "N steps, I iterations, L linear iterations, F factorizations; assembly a s, ..." with the
/// fields that are not zero: the line report() prints by default.
std::string format_stats(const StepperStats& s);
/// Adds `from`'s work (counts but steps, times, factor entries) to `to`, e.g. the work of a
/// second instance of a method (step doubling's half steps).
void add_work(StepperStats& to, const StepperStats& from);

/// The summary of several steps that make one (step doubling): `s`'s counts added to `total`,
/// its residual kept, and the first status that is not Converged with its message.
void add_substep(StepSummary& total, const StepSummary& s);
/// True for a status that ends a step (BrokeDown, Fatal), as opposed to Converged and the
/// recoverable NotConverged.
inline bool step_failed(const StepSummary& s) {
  return s.status == Status::BrokeDown || s.status == Status::Fatal;
}

/// A per-particle quantity a stepper publishes for a run's frames (Stepper::output_fields): its
/// name (a VTK point array) and values for the first values->size() particles (an SPH stepper's
/// fluid particles; the particles after them show NaN).
struct ParticleField {
  const char* name;
  const Vec* values;
};

/// A figure of a step for a run's log (Stepper::step_figures): its log.csv column, its value and
/// the significant digits it is written with (17 for counts, which then print as integers).
struct StepFigure {
  const char* name;
  double value;
  int digits;
};

/// Advances a mass-spring state by one step of size h. Implementations hold a reference to their
/// (read-only) system and own all their scratch; step() must not allocate once warmed up.
/// Constraints (colliders, strain limiting) are not applied here: Simulation applies them.
class Stepper {
 public:
  virtual ~Stepper() = default;
  /// Registry name of the method.
  virtual const char* name() const = 0;
  /// s1 = one step of size h from s0. s1 may not alias s0; its vectors are resized if needed.
  virtual StepSummary step(const State& s0, double h, State& s1) = 0;
  /// Order q of the local error estimate this method makes of each step (its error O(h^(q+1)));
  /// 0: none, so the method cannot run under error control (Simulation::advance_adaptive).
  virtual int error_estimate_order() const { return 0; }
  /// The local error estimate of the last step() in the weighted norm of the error control
  /// (wrms_norm in step_controller.hpp, between that step's start and its result before
  /// constraints). Only for methods with error_estimate_order() > 0.
  virtual double error_norm(double rtol, double atol);
  /// Switches the local error estimate on or off, for methods whose estimate costs work (the
  /// implicit family's step doubling: two extra steps per step); Simulation::set_error_control
  /// switches it on. Methods whose estimate is free (embedded pairs) ignore it.
  virtual void set_error_estimation(bool /*on*/) {}
  /// The largest ratio h_next / h between consecutive steps that error control may propose
  /// (Simulation::advance_adaptive): multistep formulas are stable only for bounded ratios.
  /// Infinity (no bound beyond the controller's own) for one-step methods.
  virtual double max_step_ratio() const { return std::numeric_limits<double>::infinity(); }
  /// Work and time over all steps so far (fields the method has no use for stay 0).
  virtual StepperStats stats() const { return {}; }
  /// One line of counters accumulated over all steps so far, for logs: format_stats(stats()) by
  /// default, with method-specific additions where a method has them; "" for methods that count
  /// nothing (stats().steps == 0).
  virtual std::string report() const {
    const StepperStats s = stats();
    return s.steps == 0 ? std::string() : format_stats(s);
  }

  // Output. What a stepper knows of a state beyond x and v (an SPH fluid's densities and
  // pressures), published so that a run's writers need not know the concrete stepper.

  /// The last step's figures for a run's log at state s, the state that step ended in; before
  /// the first step, those of the initial state s (counts 0). The same names in the same order on
  /// every call (they are log.csv's columns). Empty by default.
  virtual std::vector<StepFigure> step_figures(const State& /*s*/) { return {}; }
  /// The per-particle fields of state s, the state the last step ended in (or the initial one),
  /// for a run's frames; the values stay valid until the next step or call. Computing them must
  /// not change the steps that follow. Empty by default.
  virtual std::vector<ParticleField> output_fields(const State& /*s*/) { return {}; }

  // Checkpoints. A step may depend on more than its start state: a multistep history (BDF2's
  // previous state) or a warm start (an iterative linear backend's previous correction). A
  // stepper that carries such data exports it here, so that a run resumed from a checkpoint takes
  // bit-identical steps. The defaults describe a one-step method with nothing to carry; a method
  // with history it cannot export says so in exact_resume().

  /// Everything the next step depends on beyond its start state and h, as numbers (any layout
  /// the stepper chooses; empty for one-step methods without warm starts).
  virtual std::vector<double> history() const { return {}; }
  /// Restores what history() returned on a stepper made with the same method, options and
  /// system; an empty history (a distributed run keeps none) starts the stepper afresh, as a new
  /// one would. Throws InternalError if the data cannot be from such a stepper.
  virtual void restore_history(const std::vector<double>& history) {
    HOOKE_ASSERT(history.empty(), name()
                                      << " keeps no history, got " << history.size() << " numbers");
  }
  /// True if history() and restore_history() make a resumed run bit-identical to an uninterrupted
  /// one. False for backends with internal history they cannot export (CVODE, IDA: a resumed run
  /// restarts them, like any change of state they did not produce).
  virtual bool exact_resume() const { return true; }
};

}  // namespace hooke
