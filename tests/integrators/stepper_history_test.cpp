// Claim of Stepper::history() / restore_history() / exact_resume()
// (solver/integrators/stepper.hpp), on which `hooke resume` rests: for every registered method (and
// implicit methods on an iterative backend, whose warm start is history too), 5 steps, then a fresh
// stepper given the exported history, then 7 more steps, end bit for bit where 12 uninterrupted
// steps end, whenever the method claims exact_resume(); the others (CVODE, IDA restart) agree to
// their tolerance. New methods of the registry join the sweep without a test edit.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "support/registry.hpp"
#include "support/systems.hpp"

namespace hooke {
namespace {

struct Case {
  std::string method, linear_solver;  // "" = the method's default
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const auto& m : methods()) {
    out.push_back({m.name, ""});
    if (m.kind == MethodKind::Implicit && test::has_backend("pcg")) out.push_back({m.name, "pcg"});
  }
  return out;
}

std::string case_name(const testing::TestParamInfo<Case>& info) {
  return test::pascal_case(info.param.method) +
         (info.param.linear_solver.empty() ? ""
                                           : "On" + test::pascal_case(info.param.linear_solver));
}

class StepperHistory : public testing::TestWithParam<Case> {
 protected:
  /// A 6 x 6 net of undamped springs (every method, ceres-implicit included, runs it) with one
  /// corner pinned, gravity, and random initial velocities.
  static test::Cloth cloth() {
    const int n = 6, np = n * n;
    const double s = 0.2, m = 1e-3;
    std::vector<char> pinned(size_t(np), 0);
    pinned[0] = 1;
    test::Cloth c;
    c.system = std::make_unique<MassSpringSystem>(Vec::Constant(np, m), pinned);
    c.state = State(np);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.1, 0.1);
    for (int i = 0; i < np; ++i) {
      c.state.x.segment<3>(3 * i) = Vec3((i % n) * s, (i / n) * s, u(rng));
      if (i) c.state.v.segment<3>(3 * i) = Vec3(u(rng), u(rng), u(rng));
    }
    auto springs = std::make_unique<HookeSpring>();
    for (int i = 0; i < np; ++i) {
      if (i % n + 1 < n) springs->add(i, i + 1, 1e3, s);
      if (i + n < np) springs->add(i, i + n, 1e3, s);
    }
    c.system->add_force(std::move(springs));
    c.system->add_force(std::make_unique<Gravity>(Vec::Constant(np, m), Vec3(0.0, -9.81, 0.0)));
    c.system->finalize();
    return c;
  }
  std::unique_ptr<Stepper> stepper(const MassSpringSystem& sys) const {
    hooke::ImplicitOptions o;
    o.linear_solver = GetParam().linear_solver;
    o.newton_iterations = 2;
    o.max_linear_iterations = 5;  // pcg stops early: the warm start then matters
    return make_stepper(GetParam().method, sys, hooke::options_for(GetParam().method, o));
  }
  static constexpr double kH = 1e-4;
};

TEST_P(StepperHistory, ResumedRunMatchesUninterruptedRun) {
  const test::Cloth c = cloth();
  const MassSpringSystem& sys = *c.system;
  const std::string why = method_unsupported(GetParam().method, sys);
  if (!why.empty()) GTEST_SKIP() << why;

  Simulation straight(sys, stepper(sys), c.state);
  for (int k = 0; k < 12; ++k) straight.advance(kH);

  Simulation first(sys, stepper(sys), c.state);
  for (int k = 0; k < 5; ++k) first.advance(kH);
  const std::vector<double> history = first.stepper().history();
  Simulation second(sys, stepper(sys), first.state());
  second.stepper().restore_history(history);
  for (int k = 0; k < 7; ++k) second.advance(kH);

  ASSERT_EQ(second.state().x.size(), straight.state().x.size());
  const double dx = (second.state().x - straight.state().x).lpNorm<Eigen::Infinity>();
  const double dv = (second.state().v - straight.state().v).lpNorm<Eigen::Infinity>();
  if (second.stepper().exact_resume()) {
    EXPECT_EQ(second.state().t, straight.state().t);
    EXPECT_EQ(dx, 0.0);
    EXPECT_EQ(dv, 0.0);
    EXPECT_TRUE(second.state().x == straight.state().x && second.state().v == straight.state().v);
  } else {
    // A restarted adaptive integrator: the difference is of the order of its tolerances.
    EXPECT_LT(dx, 1e-6);
    EXPECT_LT(dv, 1e-4);
  }
  EXPECT_GT((straight.state().x - c.state.x).lpNorm<Eigen::Infinity>(), 0.0);  // it did move
}

// The same under error control (methods with a local error estimate): the stepper's history and
// the controller's state (counts, next step, memory) continue the run on the same bits.
TEST_P(StepperHistory, ResumedAdaptiveRunMatchesUninterruptedRun) {
  const test::Cloth c = cloth();
  const MassSpringSystem& sys = *c.system;
  const std::string why = method_unsupported(GetParam().method, sys);
  if (!why.empty()) GTEST_SKIP() << why;
  if (method_info(GetParam().method).error_estimate_order == 0)
    GTEST_SKIP() << GetParam().method << " makes no error estimate";
  ErrorControl control;
  control.rtol = 1e-5;
  control.atol = 1e-8;
  const double t_end = 1.0;
  // The fixture's Newton and pcg caps leave steps NotConverged, which a Simulation accepts.
  auto taken = [](const StepSummary& s) {
    return s.status == Status::Converged || s.status == Status::NotConverged;
  };
  auto adaptive = [&](const State& s0) {
    auto sim = std::make_unique<Simulation>(sys, stepper(sys), s0);
    sim->set_error_control(control, kH);
    return sim;
  };
  auto straight = adaptive(c.state);
  for (int k = 0; k < 12; ++k) ASSERT_TRUE(taken(straight->advance_adaptive(t_end)));
  auto first = adaptive(c.state);
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(taken(first->advance_adaptive(t_end)));
  auto second = adaptive(first->state());
  second->stepper().restore_history(first->stepper().history());
  second->restore_adaptive(first->accepted_steps(), first->rejected_steps(), first->next_step(),
                           first->controller()->previous_error(),
                           first->controller()->last_rejected());
  for (int k = 0; k < 7; ++k) ASSERT_TRUE(taken(second->advance_adaptive(t_end)));
  ASSERT_TRUE(second->stepper().exact_resume()) << "every error-controlled method resumes exactly";
  EXPECT_EQ(second->state().t, straight->state().t);
  EXPECT_TRUE(second->state().x == straight->state().x && second->state().v == straight->state().v);
  EXPECT_EQ(second->accepted_steps(), straight->accepted_steps());
  EXPECT_EQ(second->rejected_steps(), straight->rejected_steps());
}

TEST_P(StepperHistory, RestoringForeignHistoryIsRefused) {
  const test::Cloth c = cloth();
  const std::string why = method_unsupported(GetParam().method, *c.system);
  if (!why.empty()) GTEST_SKIP() << why;
  auto s = stepper(*c.system);
  const std::vector<double> wrong(7, 1.0);
  EXPECT_THROW(s->restore_history(wrong), InternalError);
}

INSTANTIATE_TEST_SUITE_P(Registry, StepperHistory, testing::ValuesIn(cases()), case_name);

// The sweep above has teeth: BDF2 resumed without its history (a fresh stepper) restarts with a
// backward Euler step and ends elsewhere.
TEST(StepperHistoryBdf2, WithoutHistoryTheResumedRunDiffers) {
  test::ClothSpec spec;
  spec.n = 8;
  spec.spacing = 1.0 / 7.0;
  spec.speed = 0.1;
  const test::Cloth c = test::make_cloth(spec);
  Simulation straight(*c.system, make_stepper("bdf2", *c.system), c.state);
  Simulation first(*c.system, make_stepper("bdf2", *c.system), c.state);
  for (int k = 0; k < 5; ++k) {
    straight.advance(1e-3);
    first.advance(1e-3);
  }
  Simulation second(*c.system, make_stepper("bdf2", *c.system), first.state());
  for (int k = 0; k < 7; ++k) {
    straight.advance(1e-3);
    second.advance(1e-3);
  }
  EXPECT_GT((second.state().x - straight.state().x).lpNorm<Eigen::Infinity>(), 1e-12);
}

}  // namespace
}  // namespace hooke
