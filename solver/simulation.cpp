#include "hooke/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "hooke/parallel/loops.hpp"

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

PlanOutcome Simulation::advance_to(const StepPlan& plan, long long first,
                                   const StepObserver& after_step) {
  HOOKE_ASSERT(!plan.adaptive || m_controller,
               "an error-controlled plan without set_error_control");
  PlanOutcome out;
  for (long long step = first; !plan.done(step - 1, m_state.t); ++step) {
    const double t_start = m_state.t;
    const auto t0 = Clock::now();
    out.summary = plan.adaptive ? advance_adaptive(plan.next_stop(t_start))
                                : advance(plan.step_size(step, t_start));
    const double wall = seconds_since(t0);
    out.step = step;
    if (!accepted(out.summary)) {
      out.end = PlanOutcome::End::Failed;
      return out;
    }
    const StepEvent event{step, t_start, wall, out.summary, plan.done(step, m_state.t)};
    if (!after_step(event)) {
      out.end = PlanOutcome::End::Stopped;
      return out;
    }
  }
  out.end = PlanOutcome::End::Finished;
  return out;
}

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
  StepSummary s = attempt(h);
  if (accepted(s)) s = check_end_state(std::move(s), h);
  m_failed_elsewhere = false;
  if (m_agreement && !m_agreement(accepted(s)) && accepted(s)) {
    m_failed_elsewhere = true;
    s.status = Status::Fatal;
    s.message = "the step failed on another process";
  }
  if (accepted(s)) make_current();
  return s;
}

StepSummary Simulation::attempt(double h) {
  StepSummary s = m_stepper->step(m_state, h, m_next);
  if (!accepted(s)) return s;
  // Whole-step backends may stop short of t + h (e.g. CVODE's too-much-work): such a step cannot
  // be accepted as a step of size h.
  if (std::abs(m_next.t - (m_state.t + h)) > 1e-12 * std::max(std::abs(m_state.t) + h, 1.0)) {
    s.status = Status::Fatal;
    s.message = std::string(m_stepper->name()) + ": stopped at t = " + std::to_string(m_next.t) +
                " short of t + h = " + std::to_string(m_state.t + h) + ": " + s.message;
  }
  return s;
}

StepSummary Simulation::check_end_state(StepSummary s, double h) {
  // Scripted pins end the step exactly on their path, whatever the stepper's round-off or order.
  if (m_system.has_pin_motion()) m_system.pin_motion().place(m_next.t, m_next.x, m_next.v);
  m_system.apply_constraints(m_state.x, h, m_next.x, m_next.v);
  if (!m_next.is_finite()) {
    s.status = Status::Fatal;
    s.message = std::string(m_stepper->name()) + ": state became non-finite";
  }
  return s;
}

void Simulation::make_current() {
  if (m_stable_buffers) {
    // Same sizes: copied into the existing storage, over blocks in parallel.
    parallel_ranges(m_state.x.size(), [&](long long b, long long e) {
      m_state.x.segment(b, e - b) = m_next.x.segment(b, e - b);
      m_state.v.segment(b, e - b) = m_next.v.segment(b, e - b);
    });
    m_state.t = m_next.t;
  } else {
    std::swap(m_state, m_next);
  }
}

void Simulation::set_error_control(const ErrorControl& control, double first_step) {
  const OptionError e = control.validate();
  HOOKE_ASSERT(e.ok(), "error control: " << e.message);
  const int q = m_stepper->error_estimate_order();
  HOOKE_ASSERT(q > 0, m_stepper->name() << " makes no local error estimate for error control");
  HOOKE_ASSERT(first_step > 0.0 && std::isfinite(first_step), "first step " << first_step);
  m_control = control;
  m_controller = std::make_unique<StepController>(q, control);
  m_stepper->set_error_estimation(true);
  m_h_next = first_step;
}

void Simulation::restore_adaptive(long long accepted, long long rejected, double next_step,
                                  double previous_error, bool last_rejected) {
  HOOKE_ASSERT(m_controller, "restore_adaptive without set_error_control");
  HOOKE_ASSERT(next_step > 0.0 && std::isfinite(next_step), "next step " << next_step);
  m_accepted = accepted;
  m_rejected = rejected;
  m_h_next = next_step;
  m_controller->restore(previous_error, last_rejected);
}

StepSummary Simulation::advance_adaptive(double t_end) {
  HOOKE_ASSERT(m_controller, "advance_adaptive without set_error_control");
  HOOKE_ASSERT(!m_agreement, "advance_adaptive in a distributed run (set_agreement)");
  const double t = m_state.t;
  HOOKE_ASSERT(t_end > t, "advance_adaptive to t_end = " << t_end << " from t = " << t);
  const double h_min =
      m_control.min_dt > 0.0 ? m_control.min_dt : std::max(1e-14, 1e-12 * std::abs(t));
  int iterations = 0, newton = 0;
  double h = m_h_next;
  for (;;) {
    if (m_control.max_dt > 0.0) h = std::min(h, m_control.max_dt);
    const bool lands = t + 1.01 * h >= t_end;
    // A step shortened to land on t_end says little about the steps after it: the controller
    // proposes from it but keeps its memory, and the next step is at least the one shortened.
    const double unshortened = h;
    const double err_prev = m_controller->previous_error();
    const bool rejected_prev = m_controller->last_rejected();
    if (lands) h = t_end - t;
    if (h < h_min && !lands) {
      StepSummary f;
      f.status = Status::Fatal;
      std::ostringstream os;
      os << m_stepper->name() << ": error control needs a step of " << h << " s at t = " << t
         << ", below the smallest allowed (" << h_min
         << " s): the tolerance cannot be met here (rtol = " << m_control.rtol
         << ", atol = " << m_control.atol << ")";
      f.message = os.str();
      m_failed_t = t;
      m_failed_h = h;
      return f;
    }
    StepSummary s = attempt(h);
    iterations += s.iterations;
    newton += s.newton_iterations;
    if (!accepted(s)) {  // the stepper failed: a much smaller step, as CVODE does
      ++m_rejected;
      m_failed_t = t;
      m_failed_h = h;
      h *= 0.25;
      continue;
    }
    const double err = m_stepper->error_norm(m_control.rtol, m_control.atol);
    double h_new = m_controller->next(h, err);
    if (!(err <= 1.0)) {
      ++m_rejected;
      h = h_new;
      continue;
    }
    if (lands && h < unshortened) {
      m_controller->restore(err_prev, rejected_prev);
      h_new = std::max(h_new, unshortened);
    }
    h_new = std::min(h_new, m_stepper->max_step_ratio() * h);
    if (lands) m_next.t = t_end;  // exactly, whatever t + (t_end - t) rounds to
    s = check_end_state(std::move(s), h);
    if (s.status == Status::Fatal) {  // non-finite after constraints: retry smaller
      ++m_rejected;
      m_failed_t = t;
      m_failed_h = h;
      h *= 0.25;
      continue;
    }
    make_current();
    ++m_accepted;
    m_h_next = h_new;
    s.iterations = iterations;
    s.newton_iterations = newton;
    return s;
  }
}

}  // namespace hooke
