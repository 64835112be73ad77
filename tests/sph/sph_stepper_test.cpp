// Claims of solver/sph/sph_stepper.* shared by every pressure method: a run gives the same bits
// on one and two threads (each particle's sums run in its own neighbour order); CFL substeps are
// the steps taken one by one; the fluid methods of the registry step fluids only, and the other
// methods, which know nothing of pressure, refuse a fluid.
#include "hooke/sph/sph_stepper.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "hooke/parallel/loops.hpp"
#include "hooke/registry.hpp"
#include "hooke/sph/dfsph.hpp"
#include "hooke/sph/iisph.hpp"
#include "hooke/sph/wcsph.hpp"
#include "sph/sph_scenes.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace hooke {
namespace {

std::unique_ptr<SphStepper> make(const char* method, const MassSpringSystem& system) {
  if (std::string(method) == "wcsph") {
    WcsphOptions options;
    options.sound_speed = 30;
    return std::make_unique<WcsphStepper>(system, options);
  }
  if (std::string(method) == "dfsph") {
    DfsphOptions options;
    options.max_iterations = 1000;  // the first step starts cold
    return std::make_unique<DfsphStepper>(system, options);
  }
  IisphOptions options;
  options.max_iterations = 1000;  // the first step starts cold
  return std::make_unique<IisphStepper>(system, options);
}

TEST(SphStepper, SameBitsOnOneOrTwoThreads) {
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  for (const char* method : {"wcsph", "iisph", "dfsph"}) {
    State end[2];
    for (int t : {1, 2}) {
      omp_set_num_threads(t);
      auto scene = test::tank_2d(0.005, 0.4, 0.4, 0.2, 0.3, FluidOptions{});
      auto stepper = make(method, *scene.system);
      const double h = std::string(method) == "wcsph" ? 5e-5 : 1e-3;
      ASSERT_EQ(test::run_fluid(*stepper, scene.state, h, 100 * h).status, Status::Converged)
          << method;
      end[t - 1] = scene.state;
    }
    EXPECT_TRUE(end[0] == end[1]) << method;
  }
  omp_set_num_threads(threads);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(SphStepper, OnlyTheFluidMethodsStepAFluidAndTheyStepNothingElse) {
  // The other methods would step the particles under gravity alone: they must say so.
  auto scene = test::tank_2d(0.01, 0.2, 0.2, 0.1, 0.1, FluidOptions{});
  MassSpringSystem springs(Vec::Ones(2), std::vector<char>(2, 0));
  springs.finalize();
  int fluid_methods = 0, refused = 0;
  for (const auto& m : methods()) {
    const std::string why = method_unsupported(m.name, *scene.system);
    if (m.kind == MethodKind::Fluid) {
      ++fluid_methods;
      EXPECT_EQ(why, "") << m.name;
      EXPECT_NE(method_unsupported(m.name, springs).find("has no fluid"), std::string::npos)
          << m.name;
      EXPECT_THROW(make_stepper(m.name, springs), std::invalid_argument) << m.name;
    } else {
      ++refused;
      EXPECT_NE(why.find("fluid methods (" + fluid_method_names() + ")"), std::string::npos)
          << m.name << ": '" << why << "'";
    }
  }
  EXPECT_EQ(fluid_methods, 3);
  EXPECT_EQ(fluid_method_names(), "wcsph, iisph, dfsph");
  EXPECT_GE(refused, 10);
}

TEST(SphStepper, CflSubstepsLandOnTheStepAndAreTheStepsTakenOneByOne) {
  for (const char* method : {"wcsph", "iisph"}) {
    SCOPED_TRACE(method);
    // A column of water collapsing in a wide tank, moving after 0.1 s (500 steps).
    auto scene = test::tank_2d(0.01, 0.4, 0.3, 0.1, 0.2, FluidOptions{});
    auto warm = make(method, *scene.system);
    ASSERT_EQ(test::run_fluid(*warm, scene.state, 2e-4, 500 * 2e-4).status, Status::Converged);
    const State s0 = scene.state;
    // The same method with substeps (courant 0.4) and without (each step as given).
    std::unique_ptr<SphStepper> sub, single;
    if (std::string(method) == "wcsph") {
      WcsphOptions o;
      o.sound_speed = 30;
      single = std::make_unique<WcsphStepper>(*scene.system, o);
      o.courant = 0.4;
      sub = std::make_unique<WcsphStepper>(*scene.system, o);
    } else {
      IisphOptions o;
      o.max_iterations = 1000;
      single = std::make_unique<IisphStepper>(*scene.system, o);
      o.courant = 0.4;
      sub = std::make_unique<IisphStepper>(*scene.system, o);
    }
    const double h = 7.5 * sub->cfl_limit(s0);
    State s1 = s0;
    ASSERT_EQ(sub->step(s0, h, s1).status, Status::Converged);
    EXPECT_EQ(s1.t, s0.t + h);
    const int substeps = sub->last_fluid_stats().substeps;
    EXPECT_GE(substeps, 8);
    EXPECT_LE(substeps, 12);
    // The same substeps one by one: the fewest equal pieces of the time left that the CFL step
    // at each piece's start allows.
    State from = s0, to = s0;
    double done = 0.0;
    int taken = 0;
    double largest_error = 0.0;
    while (true) {
      const double remaining = h - done;
      const double pieces = std::ceil(remaining / sub->cfl_limit(from) * (1.0 - 1e-12));
      const double hs = pieces <= 1.0 ? remaining : remaining / pieces;
      ASSERT_LE(hs, sub->cfl_limit(from) * (1.0 + 1e-12));
      ASSERT_EQ(single->step(from, hs, to).status, Status::Converged);
      largest_error = std::max(largest_error, single->last_fluid_stats().max_density_error);
      ++taken;
      if (pieces <= 1.0) break;
      done += hs;
      std::swap(from, to);
    }
    EXPECT_EQ(taken, substeps);
    EXPECT_TRUE(to.x == s1.x);
    EXPECT_TRUE(to.v == s1.v);
    EXPECT_EQ(sub->last_fluid_stats().max_density_error, largest_error);
  }
}

TEST(SphStepper, AParticleThatLeavesTheWallsIsLostAndStopsWhereItIs) {
  for (const char* method : {"wcsph", "iisph", "dfsph"}) {
    SCOPED_TRACE(method);
    // Water in a tank 0.2 m wide; one particle of the block moved far below the floor (spray
    // that fell out), falling at 5 m/s, and one high above the open top, rising at 1 m/s.
    auto scene = test::tank_2d(0.01, 0.2, 0.3, 0.2, 0.1, FluidOptions{});
    auto stepper = make(method, *scene.system);
    const Index below = 0, above = 1;
    State& s0 = scene.state;
    s0.x.segment<3>(3 * below) = Vec3(0.1, -0.5, 0.0);
    s0.v.segment<3>(3 * below) = Vec3(0.0, -5.0, 0.0);
    s0.x.segment<3>(3 * above) = Vec3(0.1, 2.0, 0.0);
    s0.v.segment<3>(3 * above) = Vec3(0.0, 1.0, 0.0);
    EXPECT_TRUE(stepper->lost(s0.x, below));
    EXPECT_FALSE(stepper->lost(s0.x, above));  // the tank is open at the top
    EXPECT_DOUBLE_EQ(stepper->max_fluid_speed(s0), 1.0);
    State s1 = s0;
    const double h = 1e-4;
    ASSERT_EQ(stepper->step(s0, h, s1).status, Status::Converged);
    EXPECT_EQ(stepper->last_fluid_stats().lost, 1);
    EXPECT_TRUE(s1.x.segment<3>(3 * below) == s0.x.segment<3>(3 * below));
    EXPECT_TRUE(s1.v.segment<3>(3 * below).isZero());
    // The particle above falls freely under gravity (symplectic Euler).
    EXPECT_NEAR(s1.v[3 * above + 1], 1.0 - test::kG * h, 1e-12);
    EXPECT_NE(stepper->report().find("1 fluid particles lost"), std::string::npos);
  }
}

// What a stepper publishes for output (Stepper::output_fields, step_figures) leaves its steps
// unchanged (it updates the stepper's own neighbour search): a run that asks for them after every
// step ends in the same bits as one that never does. The densities are those of the state asked
// about, as a fresh neighbour search gives them; before the first step the figures are the
// initial state's.
TEST(SphStepper, OutputFieldsAreTheStatesAndLeaveTheStepsUnchanged) {
  for (const char* method : {"wcsph", "iisph", "dfsph"}) {
    State end[2];
    for (int ask : {0, 1}) {
      auto scene = test::tank_2d(0.01, 0.4, 0.4, 0.2, 0.3, FluidOptions{});
      auto stepper = make(method, *scene.system);
      const FluidModel& fluid = stepper->fluid();
      const std::vector<StepFigure> start = stepper->step_figures(scene.state);
      ASSERT_EQ(start.size(), 6u);
      EXPECT_STREQ(start[0].name, "max_density_error");
      EXPECT_EQ(start[2].value, 0.0) << "no pressure iterations before the first step";
      int checked = 0;
      auto observe = [&](const State& s) {
        if (ask == 0) return;
        const std::vector<ParticleField> fields = stepper->output_fields(s);
        const std::vector<StepFigure> figures = stepper->step_figures(s);
        ASSERT_EQ(fields.size(), 2u);
        EXPECT_STREQ(fields[0].name, "density");
        NeighbourSearch search(fluid.support());
        ASSERT_EQ(search.update(s.x, fluid.num_fluid()), Status::Converged);
        Vec rho(fluid.num_fluid());
        fluid.compute_density(search, s.x, scene.system->masses(), rho);
        EXPECT_EQ(*fields[0].values, rho) << method;
        EXPECT_EQ(figures[0].value, stepper->last_fluid_stats().max_density_error);
        EXPECT_EQ(figures[3].value, stepper->last_fluid_stats().substeps);
        ++checked;
      };
      const double h = std::string(method) == "wcsph" ? 5e-5 : 1e-3;
      ASSERT_EQ(test::run_fluid(*stepper, scene.state, h, 40 * h, observe).status,
                Status::Converged)
          << method;
      if (ask == 1) {
        EXPECT_EQ(checked, 40) << method;
      }
      end[ask] = scene.state;
    }
    EXPECT_TRUE(end[0] == end[1]) << method << ": asking for the output changed the steps";
  }
}

}  // namespace
}  // namespace hooke
