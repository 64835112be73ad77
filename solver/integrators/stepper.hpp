#pragma once
#include <string>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// What one time step reports. Explicit steps always converge with 0 iterations; implicit and
/// whole-step backends fill iterations (linear or nonlinear, as documented by each) and residual.
struct StepSummary {
  Status status = Status::Converged;
  int iterations = 0;     ///< linear solver iterations spent in this step (summed over Newton)
  int newton_iterations = 0;  ///< Newton iterations (implicit methods; 0 for explicit ones)
  double residual = 0.0;  ///< final residual norm of the step's solve (0 if none)
  std::string message;    ///< empty on success; says what failed and with which numbers otherwise
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
  /// One line of counters accumulated over all steps so far (solver work, times), for logs;
  /// "" for methods with nothing to report.
  virtual std::string report() const { return ""; }

  // Checkpoints. A step may depend on more than its start state: a multistep history (BDF2's
  // previous state) or a warm start (an iterative linear backend's previous correction). A
  // stepper that carries such data exports it here, so that a run resumed from a checkpoint takes
  // bit-identical steps. The defaults describe a one-step method with nothing to carry; a method
  // with history it cannot export says so in exact_resume().

  /// Everything the next step depends on beyond its start state and h, as numbers (any layout
  /// the stepper chooses; empty for one-step methods without warm starts).
  virtual std::vector<double> history() const { return {}; }
  /// Restores what history() returned on a stepper made with the same method, options and
  /// system. Throws InternalError if the data cannot be from such a stepper.
  virtual void restore_history(const std::vector<double>& history) {
    HOOKE_ASSERT(history.empty(), name() << " keeps no history, got " << history.size() << " numbers");
  }
  /// True if history() and restore_history() make a resumed run bit-identical to an uninterrupted
  /// one. False for backends with internal history they cannot export (CVODE, IDA: a resumed run
  /// restarts them, like any change of state they did not produce).
  virtual bool exact_resume() const { return true; }
};

}  // namespace hooke
