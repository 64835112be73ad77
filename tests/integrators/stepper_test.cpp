// Tests of solver/integrators/stepper.*: StepperStats, the statistics every stepper reports, agrees
// with what its steps said (StepSummary) and with facts about the method (one factorization per
// Newton iteration for a direct backend, none for Jacobi-PCG, substeps x sweeps for XPBD), and
// format_stats prints the fields that are set.
#include <gtest/gtest.h>

#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "support/backend_scenes.hpp"
#include "support/registry.hpp"

namespace hooke {
namespace {

/// Totals of the StepSummary values of `steps` steps of h from the scene's initial state.
struct Sums {
  long long newton = 0, iterations = 0;
  double last_residual = 0.0;
};

Sums run(Stepper& stepper, const test::Scene& scene, int steps, double h) {
  Sums s;
  State s0 = scene.state, s1;
  for (int k = 0; k < steps; ++k) {
    const StepSummary r = stepper.step(s0, h, s1);
    // NotConverged is expected where a test asks for a fixed iteration count.
    EXPECT_TRUE(r.status == Status::Converged || r.status == Status::NotConverged)
        << stepper.name() << ": " << r.message;
    s.newton += r.newton_iterations;
    s.iterations += r.iterations;
    s.last_residual = r.residual;
    s0 = s1;
  }
  return s;
}

TEST(StepperStats, ImplicitCountsNewtonLinearIterationsAndFactorizations) {
  const test::Scene scene = test::hanging_cloth(5, 0.05);
  for (const char* backend : {"cholmod", "pcg"}) {
    if (!test::has_backend(backend)) continue;
    SCOPED_TRACE(backend);
    ImplicitOptions o;
    o.linear_solver = backend;
    o.newton_iterations = 3;
    o.newton_tolerance = 1e-300;  // exactly 3 Newton iterations per step
    auto stepper = make_stepper("implicit", *scene.system, o);
    const Sums sums = run(*stepper, scene, 4, 1e-2);
    const StepperStats st = stepper->stats();
    EXPECT_EQ(st.steps, 4);
    EXPECT_EQ(st.iterations, sums.newton);
    EXPECT_EQ(st.iterations, 12);
    EXPECT_EQ(st.linear_iterations, sums.iterations);
    EXPECT_EQ(st.last_residual, sums.last_residual);
    const bool direct = std::string(backend) == "cholmod";
    EXPECT_EQ(st.factorizations, direct ? 12 : 0)
        << "one per Newton iteration for a direct backend";
    EXPECT_EQ(st.linear_iterations > 0, !direct);
    EXPECT_GT(st.assembly_seconds, 0.0);
    EXPECT_GT(st.solve_seconds, 0.0);
    EXPECT_GE(st.total_seconds, st.assembly_seconds + st.solve_seconds);
    EXPECT_NE(stepper->report(), "");
  }
}

TEST(StepperStats, WholeStepMethodsReportTheirIterations) {
  const test::Scene scene = test::hanging_cloth(5, 0.05);
  XpbdOptions x;
  x.substeps = 7;
  x.iterations = 2;
  auto xpbd = make_stepper("xpbd", *scene.system, x);
  run(*xpbd, scene, 3, 1e-2);
  EXPECT_EQ(xpbd->stats().steps, 3);
  EXPECT_EQ(xpbd->stats().iterations, 3 * 7 * 2);
  if (test::has_method("fast-mass-spring")) {
    auto fms = make_stepper("fast-mass-spring", *scene.system);
    const Sums sums = run(*fms, scene, 3, 1e-2);
    const StepperStats st = fms->stats();
    EXPECT_EQ(st.steps, 3);
    EXPECT_EQ(st.iterations, sums.iterations);
    EXPECT_EQ(st.factorizations, 1) << "one factorization for a fixed h";
    EXPECT_GT(st.factor_nonzeros, 0.0);
    EXPECT_GT(st.local_seconds + st.global_seconds, 0.0);
  }
  if (test::has_method("cvode")) {
    auto cvode = make_stepper("cvode", *scene.system);
    const Sums sums = run(*cvode, scene, 3, 1e-2);
    const StepperStats st = cvode->stats();
    EXPECT_EQ(st.iterations, sums.newton);
    EXPECT_GT(st.internal_steps, 3);
    EXPECT_GT(st.factorizations, 0);
  }
}

TEST(StepperStats, FormatPrintsTheFieldsThatAreSet) {
  StepperStats s;
  s.steps = 5;
  s.linear_iterations = 40;
  s.solve_seconds = 0.25;
  EXPECT_EQ(format_stats(s), "5 steps, 40 linear iterations; solve 0.25 s");
  EXPECT_EQ(format_stats(StepperStats{}), "0 steps");
}

}  // namespace
}  // namespace hooke
