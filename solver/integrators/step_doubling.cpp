#include "hooke/integrators/step_doubling.hpp"

#include <cmath>
#include <sstream>

#include "hooke/integrators/step_controller.hpp"

namespace hooke {

void LocalError::allocate(Index particles) {
  start = State(particles);
  end = State(particles);
  err_x.setZero(3 * particles);
  err_v.setZero(3 * particles);
}

void LocalError::set_ends(const State& s0, const State& s1) {
  start.x = s0.x;
  start.v = s0.v;
  end.x = s1.x;
  end.v = s1.v;
}

void LocalError::extrapolate(const State& s0, const State& y1, int order, double h, State& s1) {
  const double c = 1.0 / ((1 << order) - 1);
  err_x = c * (s1.x - y1.x);
  err_v = c * (s1.v - y1.v);
  s1.x += err_x;
  s1.v += err_v;
  s1.t = s0.t + h;
  set_ends(s0, s1);
}

double LocalError::norm(double rtol, double atol) const {
  const double ex = wrms_norm(err_x, start.x, end.x, rtol, atol);
  const double ev = wrms_norm(err_v, start.v, end.v, rtol, atol);
  return std::sqrt(0.5 * (ex * ex + ev * ev));
}

StepDoubling::StepDoubling(const MassSpringSystem& system, Factory make, int order)
    : m_system(system), m_make(std::move(make)), m_order(order), m_full(m_make()) {
  HOOKE_ASSERT(order >= 1 && order <= 8, "step doubling of order " << order);
}

void StepDoubling::set_error_estimation(bool on) {
  m_estimating = on;
  if (on && !m_half) {
    m_half = m_make();
    const Index n = m_system.num_particles();
    for (State* s : {&m_y1, &m_mid}) *s = State(n);
    m_error.allocate(n);
  }
}

StepSummary StepDoubling::step(const State& s0, double h, State& s1) {
  ++m_steps;
  if (!m_estimating) return m_full->step(s0, h, s1);
  // Three steps; a failure of any ends the step with its summary (the caller shrinks h).
  StepSummary out;
  add_substep(out, m_full->step(s0, h, m_y1));
  if (step_failed(out)) return out;
  add_substep(out, m_half->step(s0, 0.5 * h, m_mid));
  if (step_failed(out)) return out;
  add_substep(out, m_half->step(m_mid, (s0.t + h) - m_mid.t, s1));
  if (step_failed(out)) return out;
  m_error.extrapolate(s0, m_y1, m_order, h, s1);
  return out;
}

double StepDoubling::error_norm(double rtol, double atol) {
  HOOKE_ASSERT(m_estimating, name() << ": error_norm without set_error_estimation(true)");
  return m_error.norm(rtol, atol);
}

StepperStats StepDoubling::stats() const {
  StepperStats s = m_full->stats();
  s.steps = m_steps;
  if (m_half) add_work(s, m_half->stats());
  return s;
}

std::string StepDoubling::report() const {
  if (!m_half) return m_full->report();
  std::ostringstream os;
  os << "step doubling (3 steps per step, halves on a second instance); full steps: "
     << m_full->report() << "; half steps: " << m_half->report();
  return os.str();
}

std::vector<double> StepDoubling::history() const {
  const std::vector<double> full = m_full->history();
  std::vector<double> h{double(full.size())};
  h.insert(h.end(), full.begin(), full.end());
  if (m_half) {
    const std::vector<double> half = m_half->history();
    h.insert(h.end(), half.begin(), half.end());
  }
  return h;
}

void StepDoubling::restore_history(const std::vector<double>& h) {
  HOOKE_ASSERT(!h.empty() && h[0] >= 0 && h[0] <= double(h.size() - 1) && h[0] == std::floor(h[0]),
               name() << ": step-doubling history of " << h.size() << " numbers starts with "
                      << (h.empty() ? 0.0 : h[0]));
  const auto split = h.begin() + 1 + std::ptrdiff_t(h[0]);
  m_full->restore_history(std::vector<double>(h.begin() + 1, split));
  const std::vector<double> half(split, h.end());
  if (m_half)
    m_half->restore_history(half);
  else
    HOOKE_ASSERT(half.empty(), name() << ": history of half steps without error estimation");
}

}  // namespace hooke
