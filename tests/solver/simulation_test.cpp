// Tests of solver/simulation.*: a failed step leaves the state unchanged, and with
// set_max_step_halvings(M) it is retried as two half steps (recursively, down to h / 2^M) that end
// exactly at t + h, each retry reported to the observer, iterations summed, and the count of
// retried steps kept.
#include "hooke/simulation.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

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

}  // namespace
}  // namespace hooke
