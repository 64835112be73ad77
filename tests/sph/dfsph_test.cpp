// Claims of solver/sph/dfsph.*: the divergence solve leaves velocities whose density change over
// the step is within its tolerance (checked with FluidModel's sums, not the stepper's), where
// the velocities it started from were not; the warm starts of both solves round-trip through
// history(). Its dam break is in dam_break_test.cpp, its momentum conservation and still water in
// iisph_test.cpp.
#include "hooke/sph/dfsph.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sph/sph_scenes.hpp"

namespace hooke {
namespace {

using test::kG;

/// The divergence solve's residual for velocities u: the mean over fluid particles of
/// h |drho/dt(u)| (under pressure p_i > 0) or max(h drho/dt(u), 0) (at p_i = 0), over rho0.
double divergence_residual(const DfsphStepper& stepper, const NeighbourSearch& search,
                           const State& s, ConstRef masses, ConstRef u, ConstRef p, double h) {
  const FluidModel& fluid = stepper.fluid();
  const Index nf = fluid.num_fluid();
  Vec div(nf);
  fluid.density_change(search, s.x, masses, u, div);
  double sum = 0.0;
  for (Index i = 0; i < nf; ++i)
    sum += p[i] > 0.0 ? std::abs(h * div[i]) : std::max(h * div[i], 0.0);
  return sum / (double(nf) * fluid.rest_density());
}

TEST(Dfsph, DivergenceSolveLeavesVelocitiesWithinItsTolerance) {
  // A column collapsing in a 2D tank, 0.1 s in: the velocities compress the fluid.
  auto scene = test::tank_2d(0.01, 0.6, 0.5, 0.2, 0.4, FluidOptions{});
  DfsphOptions options;
  options.divergence_tolerance = 1e-5;
  options.max_iterations = 5000;
  DfsphStepper stepper(*scene.system, options);
  const double h = 2e-3;
  ASSERT_EQ(test::run_fluid(stepper, scene.state, h, 0.1).status, Status::Converged);
  State next;
  ASSERT_EQ(stepper.step(scene.state, h, next).status, Status::Converged);
  const FluidModel& fluid = stepper.fluid();
  const Index nf = fluid.num_fluid(), n = scene.system->num_particles();
  NeighbourSearch search(fluid.support());
  ASSERT_EQ(search.update(scene.state.x, nf), Status::Converged);
  // v0 + h a(p_v), the pressure accelerations recomputed from the divergence pressures.
  Vec a = Vec::Zero(3 * n);
  fluid.add_pressure_acceleration(search, scene.state.x, scene.system->masses(),
                                  stepper.densities(), stepper.divergence_pressures(), a,
                                  stepper.gradient_scale());
  a.array() *= scene.system->moving().array();
  const Vec v_div = scene.state.v + h * a;
  const Vec& p_v = stepper.divergence_pressures();
  const double before = divergence_residual(stepper, search, scene.state, scene.system->masses(),
                                            scene.state.v, p_v, h);
  const double after =
      divergence_residual(stepper, search, scene.state, scene.system->masses(), v_div, p_v, h);
  std::printf(
      "[ dfsph    ] divergence residual %.2e before the solve, %.2e after (%d iterations; "
      "tolerance %.0e); %lld particles under divergence pressure\n",
      before, after, stepper.divergence_iterations(), options.divergence_tolerance,
      static_cast<long long>((p_v.array() > 0.0).count()));
  EXPECT_LE(after, options.divergence_tolerance);
  // There was something to remove: the last step's density solve leaves about 2e-4.
  EXPECT_GT(before, 10 * options.divergence_tolerance);
  EXPECT_GE(p_v.minCoeff(), 0.0);
  EXPECT_GT(p_v.maxCoeff(), 0.0);
}

TEST(Dfsph, WarmStartsRoundTripThroughHistory) {
  auto scene = test::tank_2d(0.01, 0.2, 0.4, 0.2, 0.2, FluidOptions{});
  DfsphStepper a(*scene.system, DfsphOptions{});
  ASSERT_EQ(test::run_fluid(a, scene.state, 2e-3, 0.02).status, Status::Converged);
  DfsphStepper b(*scene.system, DfsphOptions{});
  EXPECT_EQ(a.history().size(), size_t(2 * a.fluid().num_fluid()));
  b.restore_history(a.history());
  State sa, sb;
  a.step(scene.state, 2e-3, sa);
  b.step(scene.state, 2e-3, sb);
  EXPECT_TRUE(sa == sb);
  // A fresh stepper from the same state differs: the warm starts matter.
  DfsphStepper cold(*scene.system, DfsphOptions{});
  State sc;
  cold.step(scene.state, 2e-3, sc);
  EXPECT_FALSE(sa == sc);
}

}  // namespace
}  // namespace hooke
