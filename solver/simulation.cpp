#include "hooke/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace hooke {

Simulation::Simulation(const MassSpringSystem& system, std::unique_ptr<Stepper> stepper,
                       State initial)
    : m_system(system),
      m_stepper(std::move(stepper)),
      m_state(std::move(initial)),
      m_next(m_state) {
  HOOKE_ASSERT(
      m_state.x.size() == system.dofs() && m_state.v.size() == system.dofs(),
      "initial state has " << m_state.x.size() << " positions for " << system.dofs() << " dofs");
}

StepSummary Simulation::advance(double h) { return advance_halving(h, 0); }

StepSummary Simulation::advance_halving(double h, int depth) {
  const double t_end = m_state.t + h;
  StepSummary s = advance_once(h);
  if (accepted(s)) return s;
  m_failed_t = m_state.t;
  m_failed_h = h;
  if (depth >= m_max_halvings) return s;
  if (depth == 0) ++m_halved_steps;
  if (m_on_retry) m_on_retry(m_state.t, h, depth + 1, s);
  StepSummary a = advance_halving(0.5 * h, depth + 1);
  if (!accepted(a)) return a;
  // The second half ends exactly at t_end, whatever rounding the first half met.
  StepSummary b = advance_halving(t_end - m_state.t, depth + 1);
  b.iterations += a.iterations;
  b.newton_iterations += a.newton_iterations;
  return b;
}

StepSummary Simulation::advance_once(double h) {
  StepSummary s = m_stepper->step(m_state, h, m_next);
  if (s.status != Status::Converged && s.status != Status::NotConverged) return s;
  if (s.status == Status::NotConverged && !m_accept_not_converged) return s;
  // Whole-step backends may stop short of t + h (e.g. CVODE's too-much-work): such a step cannot
  // be accepted as a step of size h.
  if (std::abs(m_next.t - (m_state.t + h)) > 1e-12 * std::max(std::abs(m_state.t) + h, 1.0)) {
    s.status = Status::Fatal;
    s.message = std::string(m_stepper->name()) + ": stopped at t = " + std::to_string(m_next.t) +
                " short of t + h = " + std::to_string(m_state.t + h) + ": " + s.message;
    return s;
  }
  // Scripted pins end the step exactly on their path, whatever the stepper's round-off or order.
  if (m_system.has_pin_motion()) m_system.pin_motion().place(m_next.t, m_next.x, m_next.v);
  m_system.apply_constraints(m_state.x, h, m_next.x, m_next.v);
  if (!m_next.is_finite()) {
    s.status = Status::Fatal;
    s.message = std::string(m_stepper->name()) + ": state became non-finite";
    return s;
  }
  if (m_stable_buffers) {
    m_state.x = m_next.x;  // same sizes: Eigen copies into the existing storage
    m_state.v = m_next.v;
    m_state.t = m_next.t;
  } else {
    std::swap(m_state, m_next);
  }
  return s;
}

}  // namespace hooke
