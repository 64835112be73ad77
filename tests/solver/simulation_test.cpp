// Tests of solver/simulation.*: a failed step leaves the state unchanged, and with
// set_max_step_halvings(M) it is retried as two half steps (recursively, down to h / 2^M) that end
// exactly at t + h, each retry reported to the observer, iterations summed, and the count of
// retried steps kept. Under error control (advance_adaptive) with the embedded pairs, the achieved
// error follows the tolerance, the steps land on the end time, and rejected attempts are counted.
#include "hooke/simulation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/registry.hpp"
#include "support/order.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

/// Symplectic Euler on the system that reports NotConverged (state untouched) for any h above
/// h_max, and 1 iteration per accepted step.
class FailsAboveStep final : public Stepper {
 public:
  FailsAboveStep(const MassSpringSystem& sys, double h_max)
      : m_sys(sys), m_h_max(h_max), m_f(sys.dofs()) {}
  const char* name() const override { return "fails-above-step"; }
  StepSummary step(const State& s0, double h, State& s1) override {
    ++calls;
    sizes.push_back(h);
    StepSummary r;
    if (h > m_h_max) {
      r.status = Status::NotConverged;
      r.message = "h too large";
      return r;
    }
    m_sys.compute_forces(s0.x, s0.v, m_f);
    s1 = s0;
    for (Index i = 0; i < m_sys.dofs(); ++i) s1.v[i] += h * m_f[i] / m_sys.masses()[i / 3];
    s1.x = s0.x + h * s1.v;
    s1.t = s0.t + h;
    r.iterations = 1;
    return r;
  }
  int calls = 0;
  std::vector<double> sizes;  // h of every call

 private:
  const MassSpringSystem& m_sys;
  double m_h_max;
  Vec m_f;
};

TEST(Simulation, FailedStepLeavesTheStateUnchangedWithoutHalvings) {
  const test::TwoParticleSpring sp(1e3);
  Simulation sim(*sp.system, std::make_unique<FailsAboveStep>(*sp.system, 0.01), sp.initial(0.1));
  sim.set_accept_not_converged(false);
  const State before = sim.state();
  const StepSummary r = sim.advance(0.02);
  EXPECT_EQ(r.status, Status::NotConverged);
  EXPECT_EQ(sim.state().t, before.t);
  EXPECT_EQ(sim.state().x, before.x);
  EXPECT_EQ(sim.failed_t(), 0.0);
  EXPECT_EQ(sim.failed_h(), 0.02);
  EXPECT_EQ(sim.halved_steps(), 0);
}

TEST(Simulation, AStepAnotherProcessRefusedFailsHereTooAndRetriesTogether) {
  // The agreement of a distributed run (set_agreement): a step this process accepted fails if
  // another process's failed, leaving the state unchanged, and every retry asks again.
  const test::TwoParticleSpring sp(1e3);
  Simulation sim(*sp.system, std::make_unique<FailsAboveStep>(*sp.system, 1.0), sp.initial(0.1));
  std::vector<bool> asked;
  sim.set_agreement([&](bool here) {
    asked.push_back(here);
    return false;  // some other process failed
  });
  sim.set_max_step_halvings(1);
  const State before = sim.state();
  const StepSummary r = sim.advance(0.02);
  EXPECT_EQ(r.status, Status::Fatal);
  EXPECT_EQ(r.message, "the step failed on another process");
  EXPECT_TRUE(sim.failed_elsewhere());
  EXPECT_EQ(sim.state(), before);
  EXPECT_EQ(asked, (std::vector<bool>{true, true}));  // the step and its first half
  EXPECT_EQ(sim.failed_h(), 0.01);

  // Agreeing: the same bits as a process alone.
  Simulation alone(*sp.system, std::make_unique<FailsAboveStep>(*sp.system, 1.0), sp.initial(0.1));
  sim.set_agreement([](bool here) { return here; });
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(sim.advance(0.02).status, Status::Converged);
    ASSERT_EQ(alone.advance(0.02).status, Status::Converged);
  }
  EXPECT_FALSE(sim.failed_elsewhere());
  EXPECT_EQ(sim.state(), alone.state());
}

TEST(Simulation, FailedStepIsRetriedAsHalvesThatLandOnTPlusH) {
  const test::TwoParticleSpring sp(1e3);
  auto stepper = std::make_unique<FailsAboveStep>(*sp.system, 0.0026);
  FailsAboveStep* raw = stepper.get();
  Simulation sim(*sp.system, std::move(stepper), sp.initial(0.1));
  sim.set_accept_not_converged(false);
  sim.set_max_step_halvings(2);
  std::vector<std::pair<double, int>> retries;  // (h, depth)
  sim.set_retry_observer([&](double, double h, int depth, const StepSummary& failed) {
    EXPECT_EQ(failed.status, Status::NotConverged);
    retries.emplace_back(h, depth);
  });
  const double h = 0.01;  // needs two halvings: 0.01 -> 0.005 -> 0.0025
  const StepSummary r = sim.advance(h);
  ASSERT_EQ(r.status, Status::Converged) << r.message;
  EXPECT_EQ(sim.state().t, h) << "the last substep ends exactly at t + h";
  EXPECT_EQ(r.iterations, 4) << "four quarter steps, iterations summed";
  // 0.01 fails (depth 1 retry), then each 0.005 half fails once (depth 2 retries).
  ASSERT_EQ(retries.size(), 3u);
  EXPECT_EQ(retries[0], std::make_pair(0.01, 1));
  EXPECT_EQ(retries[1].second, 2);
  EXPECT_EQ(retries[2].second, 2);
  EXPECT_EQ(raw->calls, 1 + 2 + 4);
  EXPECT_EQ(sim.halved_steps(), 1);
  // A step that needs three halvings fails with two, at the substep that failed.
  Simulation short_of(*sp.system, std::make_unique<FailsAboveStep>(*sp.system, 0.001),
                      sp.initial(0.1));
  short_of.set_accept_not_converged(false);
  short_of.set_max_step_halvings(2);
  EXPECT_EQ(short_of.advance(h).status, Status::NotConverged);
  EXPECT_EQ(short_of.failed_h(), 0.0025);
  EXPECT_EQ(short_of.failed_t(), 0.0);
  EXPECT_EQ(short_of.halved_steps(), 1);
}

/// A spring pendulum: particle 0 pinned at the origin, particle 1 (1 kg) on a spring (k = 50 N/m,
/// rest length 1 m) released stretched and sideways under gravity: a nonlinear swinging and
/// bouncing motion with no closed form.
struct SpringPendulum {
  std::unique_ptr<MassSpringSystem> system;
  SpringPendulum() {
    system = std::make_unique<MassSpringSystem>(Vec::Ones(2), std::vector<char>{1, 0});
    auto spring = std::make_unique<HookeSpring>();
    spring->add(0, 1, 50.0, 1.0);
    system->add_force(std::move(spring));
    system->add_force(std::make_unique<Gravity>(Vec::Ones(2), Vec3(0, -9.81, 0)));
    system->finalize();
  }
  State initial() const {
    State s(2);
    s.x.segment<3>(3) = Vec3(1.2, -0.3, 0.0);
    return s;
  }
};

/// Runs method under error control from s0 to T; returns the final state and the counts.
struct AdaptiveRun {
  State state;
  long long accepted = 0, rejected = 0;
};
AdaptiveRun run_adaptive(const std::string& method, const MassSpringSystem& sys, const State& s0,
                         double T, const ErrorControl& c, double first_step) {
  Simulation sim(sys, make_stepper(method, sys), s0);
  sim.set_error_control(c, first_step);
  while (sim.state().t < T) {
    const StepSummary s = sim.advance_adaptive(T);
    EXPECT_EQ(s.status, Status::Converged) << method << ": " << s.message;
    if (s.status != Status::Converged) break;
  }
  return {sim.state(), sim.accepted_steps(), sim.rejected_steps()};
}

/// The same run with fixed steps of the method: the reference (dopri5 at T / N is far more
/// accurate than any tolerance tested here).
State run_fixed(const std::string& method, const MassSpringSystem& sys, const State& s0, double T,
                int N) {
  Simulation sim(sys, make_stepper(method, sys), s0);
  for (int n = 0; n < N; ++n) sim.advance(n + 1 == N ? T - sim.state().t : T / N);
  return sim.state();
}

/// The two small problems of the tolerance tests: the undamped two-particle spring (exact
/// solution) over 1 s and the spring pendulum over 2 s (reference: dopri5 at 1e-5 s).
struct ToleranceProblems {
  test::TwoParticleSpring sp{100.0};
  SpringPendulum pend;
  static constexpr double kA = 0.2, kTSpring = 1.0, kTPend = 2.0;
  State pend_ref = run_fixed("dopri5", *pend.system, pend.initial(), kTPend, 200000);
  static const char* name(int problem) { return problem == 0 ? "spring" : "pendulum"; }
  /// Runs `method` under control c on problem 0 (spring) or 1 (pendulum); the achieved error
  /// (largest over particles at the end) and rtol max|x| + atol, printed.
  struct Result {
    AdaptiveRun run;
    double error, allowed;
  };
  Result run(const std::string& method, int problem, const ErrorControl& c) const {
    Result out;
    Vec exact_x;
    if (problem == 0) {
      out.run = run_adaptive(method, *sp.system, sp.initial(kA), kTSpring, c, 1e-4);
      exact_x = sp.exact_xv(kA, kTSpring).head(6);
      EXPECT_EQ(out.run.state.t, kTSpring);
    } else {
      out.run = run_adaptive(method, *pend.system, pend.initial(), kTPend, c, 1e-4);
      exact_x = pend_ref.x;
      EXPECT_EQ(out.run.state.t, kTPend);
    }
    out.error = (out.run.state.x - exact_x).cwiseAbs().maxCoeff();
    out.allowed = c.rtol * exact_x.cwiseAbs().maxCoeff() + c.atol;
    std::printf(
        "[ adaptive ] %-17s %-9s rtol %.0e: error %.3e (%.2f of rtol max|x| + atol), "
        "%lld accepted, %lld rejected\n",
        method.c_str(), name(problem), c.rtol, out.error, out.error / out.allowed, out.run.accepted,
        out.run.rejected);
    return out;
  }
};

ErrorControl tolerances(double rtol) {
  ErrorControl c;
  c.rtol = rtol;
  c.atol = 1e-3 * rtol;
  return c;
}

// Achieved error against the requested tolerance (issue 21, acceptance 1, on small systems): the
// largest position error at T is within 10x of rtol max|x| + atol for rtol 1e-3 ... 1e-7 (the
// embedded pairs) and 1e-2 ... 1e-5 (step doubling: the implicit family and the whole-step
// methods), and the accepted steps fall as rtol loosens.
TEST(SimulationAdaptive, AchievedErrorFollowsTheTolerance) {
  const ToleranceProblems p;
  const std::vector<double> explicit_rtols = {1e-7, 1e-6, 1e-5, 1e-4, 1e-3};
  const std::vector<double> implicit_rtols = {1e-5, 1e-4, 1e-3, 1e-2};
  for (const std::string method : {"dopri5", "bs32", "implicit", "implicit-midpoint",
                                   "ceres-implicit", "fast-mass-spring", "vbd", "xpbd"}) {
    long long last_accepted[2] = {0, 0};
    const bool is_explicit = method_info(method).kind == MethodKind::Explicit;
    for (double rtol : is_explicit ? explicit_rtols : implicit_rtols) {
      for (int problem = 0; problem < 2; ++problem) {
        const ToleranceProblems::Result r = p.run(method, problem, tolerances(rtol));
        EXPECT_LE(r.error, 10.0 * r.allowed)
            << method << " problem " << problem << " rtol " << rtol;
        if (last_accepted[problem] > 0) {
          EXPECT_LT(r.run.accepted, last_accepted[problem])
              << method << " problem " << problem << " rtol " << rtol;
        }
        last_accepted[problem] = r.run.accepted;
      }
    }
  }
}

// BDF2 keeps the value whose error it estimates (local extrapolation, which makes the step-doubled
// methods above an order better than their estimate, would cost BDF2 its stability on stiff
// oscillations). So on these undamped oscillators its global error is the sum of its local
// errors over the run: with steps h ~ rtol^(1/3) (local error ~ h^3 ~ rtol) it falls as
// rtol^(2/3), not rtol, and exceeds 10 rtol max|x| at tight tolerances over several periods
// (measured: 43x on the spring and 104x on the pendulum at rtol 1e-5, 3-9x at 1e-2). Asserted:
// that slope (the controller does what local error control promises), and accepted steps that
// fall as rtol loosens. The work-precision cases (ErrorControlAccuracy) hold it to 10x.
TEST(SimulationAdaptive, Bdf2GlobalErrorFallsAsLocalErrorControlPromises) {
  const ToleranceProblems p;
  for (int problem = 0; problem < 2; ++problem) {
    std::vector<double> tols, errs;
    long long last_accepted = 0;
    for (double rtol : {1e-5, 1e-4, 1e-3, 1e-2}) {
      const ToleranceProblems::Result r = p.run("bdf2", problem, tolerances(rtol));
      tols.push_back(rtol);
      errs.push_back(r.error);
      if (last_accepted > 0) {
        EXPECT_LT(r.run.accepted, last_accepted) << "rtol " << rtol;
      }
      last_accepted = r.run.accepted;
    }
    const double slope = test::fitted_order(tols, errs);  // the log-log slope
    std::printf("[ adaptive ] bdf2 %-9s error ~ rtol^%.3f\n", ToleranceProblems::name(problem),
                slope);
    EXPECT_NEAR(slope, 2.0 / 3.0, 0.1) << "problem " << problem;
  }
}

// Under error control a BDF2 step is at most kBdf2MaxRatio times the one before it, landings on
// output times included (its variable-step formula is zero-stable only for bounded ratios).
TEST(SimulationAdaptive, Bdf2StepsGrowAtMostByTheMaxRatio) {
  test::TwoParticleSpring sp(100.0);
  ErrorControl c;
  c.rtol = 1e-4;
  c.atol = 1e-7;
  Simulation sim(*sp.system, make_stepper("bdf2", *sp.system), sp.initial(0.2));
  sim.set_error_control(c, 1e-5);
  double h_prev = 0.0, largest_ratio = 0.0;
  for (int frame = 1; frame <= 40; ++frame) {
    const double t_end = 0.0237 * frame;  // not a multiple of any step: every frame lands
    while (sim.state().t < t_end) {
      const double t0 = sim.state().t;
      ASSERT_EQ(sim.advance_adaptive(t_end).status, Status::Converged);
      const double h = sim.state().t - t0;
      if (h_prev > 0.0) largest_ratio = std::max(largest_ratio, h / h_prev);
      h_prev = h;
    }
  }
  std::printf("[ adaptive ] bdf2 largest step ratio %.4f over %lld steps\n", largest_ratio,
              sim.accepted_steps());
  EXPECT_LE(largest_ratio, kBdf2MaxRatio * (1.0 + 1e-9));
  EXPECT_GT(largest_ratio, 1.2);  // the steps did grow
}

// A first step far too large is rejected and counted, and the run still meets its tolerance;
// max_dt caps every step.
TEST(SimulationAdaptive, RejectsAFirstStepThatIsTooLargeAndHonoursMaxDt) {
  test::TwoParticleSpring sp(100.0);
  ErrorControl c;
  c.rtol = 1e-6;
  c.atol = 1e-9;
  const AdaptiveRun r = run_adaptive("dopri5", *sp.system, sp.initial(0.2), 0.5, c, 0.5);
  EXPECT_GE(r.rejected, 1);
  c.max_dt = 1e-3;
  Simulation sim(*sp.system, make_stepper("dopri5", *sp.system), sp.initial(0.2));
  sim.set_error_control(c, 0.5);
  double t = 0.0;
  while (sim.state().t < 0.5) {
    ASSERT_EQ(sim.advance_adaptive(0.5).status, Status::Converged);
    EXPECT_LE(sim.state().t - t, 1e-3 * (1 + 1e-12));
    t = sim.state().t;
  }
  EXPECT_GE(sim.accepted_steps(), 500);
}

// A tolerance the method cannot meet above the smallest allowed step (a spring so stiff that
// every step of at least min_dt is unstable) stops with a message and leaves the state where it
// was.
TEST(SimulationAdaptive, GivesUpBelowTheSmallestStepWithTheStateUnchanged) {
  test::TwoParticleSpring sp(1e12);
  Simulation sim(*sp.system, make_stepper("bs32", *sp.system), sp.initial(0.1));
  ErrorControl c;
  c.rtol = 1e-6;
  c.atol = 1e-9;
  c.min_dt = 1e-3;
  sim.set_error_control(c, 1e-2);
  const State before = sim.state();
  const StepSummary s = sim.advance_adaptive(1.0);
  EXPECT_EQ(s.status, Status::Fatal);
  EXPECT_NE(s.message.find("below the smallest allowed"), std::string::npos) << s.message;
  EXPECT_EQ(sim.state(), before);
  EXPECT_GE(sim.rejected_steps(), 1);
  EXPECT_EQ(sim.accepted_steps(), 0);
}

// The plan of fixed steps: every step is dt bit for bit but the last, which lands on the end;
// a duration one rounding short of a whole number of steps takes no sliver step after them.
TEST(StepPlan, FixedStepsAreDtButTheLastWhichLandsOnTheEnd) {
  StepPlan plan;
  plan.dt = 0.001;
  plan.end = 0.0105;
  EXPECT_EQ(plan.steps(), 11);
  EXPECT_EQ(plan.step_size(10, 0.01), 0.001);
  EXPECT_EQ(plan.step_size(11, 0.01), 0.0105 - 0.01);
  EXPECT_EQ(plan.time_at(3), 3 * 0.001);
  EXPECT_EQ(plan.time_at(11), 0.0105);
  plan.end = 10 * 0.1;  // 1.0, with dt 0.1: 10 steps, not 11
  plan.dt = 0.1;
  EXPECT_EQ(plan.steps(), 10);
  plan.start = 0.25;  // a plan from t = 0.25: 8 steps to 1.0, the last of 0.05
  EXPECT_EQ(plan.steps(), 8);
  EXPECT_EQ(plan.time_at(2), 0.25 + 2 * 0.1);
  plan.start = plan.end;
  EXPECT_EQ(plan.steps(), 0);
  EXPECT_TRUE(plan.done(0, plan.end));
}

TEST(StepPlan, StopsAreTheNextFrameTimeStopTimeOrTheEnd) {
  StepPlan plan;
  plan.dt = 0.01;
  plan.end = 1.0;
  plan.adaptive = true;
  EXPECT_EQ(plan.next_stop(0.3), 1.0);
  plan.frame_interval = 0.25;
  EXPECT_EQ(plan.next_stop(0.0), 0.25);
  EXPECT_EQ(plan.next_stop(0.3), 0.5);
  EXPECT_EQ(plan.next_stop(0.5 - 1e-13), 0.75) << "within round-off of a frame time counts";
  EXPECT_EQ(plan.next_stop(0.9), 1.0);
  plan.stop_times = {0.1, 0.6};
  EXPECT_EQ(plan.next_stop(0.0), 0.1);
  EXPECT_EQ(plan.next_stop(0.55), 0.6);
  long long next_frame = 1;
  EXPECT_FALSE(plan.frame_due(0.2, next_frame));
  EXPECT_TRUE(plan.frame_due(0.25, next_frame));
  EXPECT_FALSE(plan.frame_due(0.3, next_frame));
  EXPECT_TRUE(plan.frame_due(0.8, next_frame)) << "a step past two frame times: one frame";
  EXPECT_EQ(next_frame, 4);
  EXPECT_FALSE(plan.done(99, 0.99));
  EXPECT_TRUE(plan.done(0, 1.0));
}

// advance_to takes the plan's step sizes, numbers the steps, marks the last one, and a run
// stopped by its observer and continued from the next step ends in the same bits as one run
// through.
TEST(Simulation, AdvanceToTakesThePlansStepsAndContinuesWhereItStopped) {
  const test::TwoParticleSpring sp(1e3);
  StepPlan plan;
  plan.dt = 0.001;
  plan.end = 0.0105;
  auto run = [&](long long stop_after, std::vector<double>& sizes) {
    auto stepper = std::make_unique<FailsAboveStep>(*sp.system, 1.0);
    FailsAboveStep* raw = stepper.get();
    Simulation sim(*sp.system, std::move(stepper), sp.initial(0.1));
    std::vector<long long> steps;
    long long lasts = 0;
    auto observe = [&](const StepEvent& e) {
      steps.push_back(e.step);
      lasts += e.last;
      EXPECT_EQ(e.summary.iterations, 1);
      EXPECT_GE(e.wall, 0.0);
      return e.step != stop_after;
    };
    PlanOutcome out = sim.advance_to(plan, 1, observe);
    if (stop_after > 0) {
      EXPECT_EQ(out.end, PlanOutcome::End::Stopped);
      EXPECT_EQ(out.step, stop_after);
      out = sim.advance_to(plan, stop_after + 1, observe);
    }
    EXPECT_EQ(out.end, PlanOutcome::End::Finished);
    EXPECT_EQ(out.step, 11);
    EXPECT_EQ(lasts, 1);
    std::vector<long long> expected(11);
    for (long long k = 0; k < 11; ++k) expected[size_t(k)] = k + 1;
    EXPECT_EQ(steps, expected);
    EXPECT_NEAR(sim.state().t, 0.0105, 1e-15);
    sizes = raw->sizes;
    return sim.state();
  };
  std::vector<double> sizes, sizes_stopped;
  const State through = run(-1, sizes), stopped = run(4, sizes_stopped);
  ASSERT_EQ(sizes.size(), 11u);
  for (size_t k = 0; k < 10; ++k) EXPECT_EQ(sizes[k], 0.001) << "step " << k + 1;
  EXPECT_NEAR(sizes[10], 0.0005, 1e-15);
  EXPECT_EQ(sizes_stopped, sizes);
  EXPECT_EQ(stopped, through);
}

// A failed step ends advance_to with its number and summary, the state where the step before
// left it.
TEST(Simulation, AdvanceToStopsAtAFailedStep) {
  const test::TwoParticleSpring sp(1e3);
  StepPlan plan;
  plan.dt = 0.002;
  plan.end = 0.01;
  Simulation sim(*sp.system, std::make_unique<FailsAboveStep>(*sp.system, 0.0015), sp.initial(0.1));
  sim.set_accept_not_converged(false);
  int observed = 0;
  const PlanOutcome out = sim.advance_to(plan, 1, [&](const StepEvent&) {
    ++observed;
    return true;
  });
  EXPECT_EQ(out.end, PlanOutcome::End::Failed);
  EXPECT_EQ(out.step, 1);
  EXPECT_EQ(out.summary.status, Status::NotConverged);
  EXPECT_EQ(observed, 0);
  EXPECT_EQ(sim.state().t, 0.0);
}

// Under error control the steps land on every frame time and on the end, exactly.
TEST(SimulationAdaptive, AdvanceToLandsOnEveryFrameTime) {
  const test::TwoParticleSpring sp(1e3);
  Simulation sim(*sp.system, make_stepper("dopri5", *sp.system), sp.initial(0.1));
  sim.set_error_control(tolerances(1e-6), 1e-4);
  StepPlan plan;
  plan.dt = 1e-4;
  plan.end = 0.1;
  plan.adaptive = true;
  plan.frame_interval = 0.03;
  std::vector<double> ends;
  long long steps = 0;
  const PlanOutcome out = sim.advance_to(plan, 1, [&](const StepEvent& e) {
    ends.push_back(sim.state().t);
    steps = e.step;
    return true;
  });
  ASSERT_EQ(out.end, PlanOutcome::End::Finished) << out.summary.message;
  EXPECT_EQ(steps, sim.accepted_steps());
  EXPECT_GT(steps, 4);
  for (double frame : {1 * 0.03, 2 * 0.03, 3 * 0.03, 0.1})
    EXPECT_NE(std::find(ends.begin(), ends.end(), frame), ends.end())
        << "no step ends at " << frame;
  EXPECT_EQ(sim.state().t, 0.1);
}

}  // namespace
}  // namespace hooke
