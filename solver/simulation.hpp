#pragma once
#include <functional>
#include <memory>

#include "hooke/integrators/step_controller.hpp"
#include "hooke/integrators/stepper.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/step_plan.hpp"

namespace hooke {

/// One step of a run, as Simulation::advance_to() reports it after taking it.
struct StepEvent {
  long long step;  ///< its number (1-based; under error control, accepted steps are counted)
  double t_start;  ///< the time it started at (s); it ended at Simulation::state().t
  double wall;     ///< wall-clock time it took, retries included (s)
  const StepSummary& summary;
  bool last;  ///< the plan's last step (StepPlan::done)
};

/// How Simulation::advance_to() ended.
struct PlanOutcome {
  enum class End {
    Finished,  ///< the plan's last step was taken
    Failed,    ///< a step failed (summary: the failure's; see Simulation::advance())
    Stopped,   ///< the observer asked to stop after `step` (the last one too)
  };
  End end = End::Finished;
  long long step = 0;  ///< the last step taken, or the one that failed
  StepSummary summary;
};

/// One mass-spring run without any I/O: a read-only system, a stepper and the current state.
/// advance(h) takes one step, applies the system's constraints and checks that the new state is
/// finite; on any failure the current state is left unchanged and the summary says why (a
/// NotConverged step counts as a failure only after set_accept_not_converged(false)). A step
/// that stops short of t + h (a whole-step backend giving up) is a failure (Status::Fatal).
/// With set_max_step_halvings(M) > 0 a failed step is retried as two steps of h/2, each of which
/// may be halved again, down to h / 2^M.
class Simulation {
 public:
  /// Called before each retry of a failed (sub)step: its start time t (s), its size h (s), the
  /// retry depth (1 = the first halving) and the failed step's summary.
  using RetryObserver =
      std::function<void(double t, double h, int depth, const StepSummary& failed)>;

  Simulation(const MassSpringSystem& system, std::unique_ptr<Stepper> stepper, State initial);
  /// One step of size h, retried with halved steps on failure (see the class comment). On success
  /// the summary is the last substep's, with the iterations of all substeps summed; on failure it
  /// is the failed substep's, the state stays where the last successful substep left it, and
  /// failed_t() / failed_h() say which substep failed.
  StepSummary advance(double h);
  /// Error control for advance_adaptive(): the tolerances, and the size of the first step to
  /// try. The stepper must make a local error estimate (Stepper::error_estimate_order() > 0);
  /// the options must be valid (ErrorControl::validate()).
  void set_error_control(const ErrorControl& control, double first_step);
  /// One accepted step under error control, ending at most at t_end (s). Tries the controller's
  /// step (capped by max_dt; stretched or shortened to land on t_end when it would end within
  /// 1% of a step of it), and while the step's local error estimate exceeds the tolerance, or the
  /// stepper fails, tries again with a smaller step (each attempt counts as rejected). The step
  /// after an accepted one is at most Stepper::max_step_ratio() times it. The
  /// summary of the accepted attempt has the iterations of all attempts summed. Fails (state
  /// unchanged, Status::Fatal) when the step would fall below ErrorControl::min_dt.
  StepSummary advance_adaptive(double t_end);
  /// Called after each step advance_to() takes; false stops the run after it.
  using StepObserver = std::function<bool(const StepEvent&)>;
  /// Runs the plan from the current state, taking steps numbered first, first + 1, ... until
  /// the plan is done (StepPlan::done), a step fails, or after_step returns false. A fixed step
  /// is advance(plan.step_size(step, t)); under error control (plan.adaptive, after
  /// set_error_control) a step is advance_adaptive(plan.next_stop(t)). The one scene loop: hooke
  /// run, the Python module and the studies all run scenes through it.
  PlanOutcome advance_to(const StepPlan& plan, long long first, const StepObserver& after_step);
  /// Steps accepted and attempts rejected by advance_adaptive(); the step it tries next (s).
  long long accepted_steps() const { return m_accepted; }
  long long rejected_steps() const { return m_rejected; }
  double next_step() const { return m_h_next; }
  /// What advance_adaptive() continues from, as a checkpoint holds it: the counts, the next
  /// step and the controller's memory (StepController::previous_error(), last_rejected()).
  void restore_adaptive(long long accepted, long long rejected, double next_step,
                        double previous_error, bool last_rejected);
  const StepController* controller() const { return m_controller.get(); }
  /// How often a failed step is halved (0, the default: never).
  void set_max_step_halvings(int max_halvings) { m_max_halvings = max_halvings; }
  /// Makes every advance() agree with the other processes of a distributed run (issue 17):
  /// after each attempt, agreement(accepted here) must return whether every process accepted its
  /// piece of the step (a collective call, e.g. an MPI logical and). A step that failed anywhere
  /// fails everywhere, with the message "the step failed on another process" where it did not
  /// fail (failed_elsewhere()), so all processes retry or stop together. Not for
  /// advance_adaptive(). Empty (the default): a process alone.
  void set_agreement(std::function<bool(bool)> agreement) { m_agreement = std::move(agreement); }
  /// True if the last failed attempt failed on another process only (set_agreement).
  bool failed_elsewhere() const { return m_failed_elsewhere; }
  /// Called before each retry (e.g. to report it); empty = nobody is told.
  void set_retry_observer(RetryObserver observer) { m_on_retry = std::move(observer); }
  /// Start time and size (s) of the last (sub)step that failed.
  double failed_t() const { return m_failed_t; }
  double failed_h() const { return m_failed_h; }
  /// Steps (advance() calls) that needed at least one retry; settable to continue a count.
  long long halved_steps() const { return m_halved_steps; }
  void set_halved_steps(long long n) { m_halved_steps = n; }
  /// Whether a NotConverged step is accepted (true, the default: the state advances and the
  /// summary says the step missed its tolerance) or treated like the other failures (false: the
  /// state stays unchanged, so the caller may retry with a smaller h or stop).
  void set_accept_not_converged(bool accept) { m_accept_not_converged = accept; }
  const State& state() const { return m_state; }
  /// The current state for editing between steps (e.g. a user moving a particle). A stepper that
  /// caches anything derived from the state (a factorization, BDF2's history) sees the edit only
  /// through the next step's start state.
  State& mutable_state() { return m_state; }
  /// true: a step copies its result into the current state's buffers instead of swapping them
  /// with the scratch state, so that pointers into state().x and state().v (numpy views in the
  /// Python module) keep showing the current state. Costs one copy of x and v per step; the
  /// values are the same bits either way. Default false.
  void set_stable_buffers(bool stable) { m_stable_buffers = stable; }
  const MassSpringSystem& system() const { return m_system; }
  Stepper& stepper() { return *m_stepper; }
  const Stepper& stepper() const { return *m_stepper; }
  /// Continues with another stepper (for the same system) from the current state.
  void set_stepper(std::unique_ptr<Stepper> stepper) {
    m_stepper = std::move(stepper);
    if (m_controller) m_stepper->set_error_estimation(true);
  }

 private:
  /// One attempt at a step of size h, without retries.
  StepSummary advance_once(double h);
  /// The stepper's step of size h into m_next, failed if it was not accepted or stopped short.
  StepSummary attempt(double h);
  /// Completes an attempt that succeeded: scripted pins and constraints on m_next, then the
  /// finiteness check, which fails the step (Status::Fatal) if m_next is not finite.
  StepSummary check_end_state(StepSummary s, double h);
  /// m_next becomes the current state.
  void make_current();
  /// advance_once, retried as two half steps while depth < m_max_halvings.
  StepSummary advance_halving(double h, int depth);
  /// True if the step advanced the state.
  bool accepted(const StepSummary& s) const {
    return s.status == Status::Converged ||
           (s.status == Status::NotConverged && m_accept_not_converged);
  }

  const MassSpringSystem& m_system;
  std::unique_ptr<Stepper> m_stepper;
  State m_state, m_next;
  bool m_accept_not_converged = true;
  int m_max_halvings = 0;
  RetryObserver m_on_retry;
  std::function<bool(bool)> m_agreement;
  bool m_failed_elsewhere = false;
  double m_failed_t = 0.0, m_failed_h = 0.0;
  long long m_halved_steps = 0;
  bool m_stable_buffers = false;
  // Error control (advance_adaptive).
  ErrorControl m_control;
  std::unique_ptr<StepController> m_controller;
  double m_h_next = 0.0;
  long long m_accepted = 0, m_rejected = 0;
};

}  // namespace hooke
