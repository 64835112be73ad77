#pragma once
#include <memory>

#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// One mass-spring run without any I/O: a read-only system, a stepper and the current state.
/// advance(h) takes one step, applies the system's constraints and checks that the new state is
/// finite; on any failure the current state is left unchanged and the summary says why (a
/// NotConverged step counts as a failure only after set_accept_not_converged(false)). A step
/// that stops short of t + h (a whole-step backend giving up) is a failure (Status::Fatal).
class Simulation {
 public:
  Simulation(const MassSpringSystem& system, std::unique_ptr<Stepper> stepper, State initial);
  StepSummary advance(double h);
  /// Whether a NotConverged step is accepted (true, the default: the state advances and the
  /// summary says the step missed its tolerance) or treated like the other failures (false: the
  /// state stays unchanged, so the caller may retry with a smaller h or stop).
  void set_accept_not_converged(bool accept) { m_accept_not_converged = accept; }
  const State& state() const { return m_state; }
  const MassSpringSystem& system() const { return m_system; }
  Stepper& stepper() { return *m_stepper; }

 private:
  const MassSpringSystem& m_system;
  std::unique_ptr<Stepper> m_stepper;
  State m_state, m_next;
  bool m_accept_not_converged = true;
};

}  // namespace hooke
