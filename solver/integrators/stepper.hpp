#pragma once
#include <string>

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
};

}  // namespace hooke
