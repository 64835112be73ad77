// Claims of solver/sph/wcsph.*: pressure and viscous forces conserve momentum; a step far beyond
// the CFL limit stops the run with a message naming the limit; bad options and systems without a
// fluid are refused; still water in a tank stays still for 100 t_ref (t_ref = sqrt(H / g)), with
// its surface within half a spacing of H, no particle through a wall and a mean density error
// below 1% (c0 = 10 v_max).
#include "hooke/sph/wcsph.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sph/sph_scenes.hpp"

namespace hooke {
namespace {

using test::kG;

/// A free 2D blob of water (no walls, no gravity) with random velocities.
FluidSystem moving_blob(double viscosity) {
  FluidOptions fluid;
  fluid.dimension = 2;
  fluid.spacing = 0.01;
  fluid.viscosity = viscosity;
  auto scene = make_fluid_system(sample_box(Vec3::Zero(), Vec3(0.3, 0.2, 0), 0.01, 2), {}, fluid,
                                 Vec3::Zero());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Index i = 0; i < scene.system->num_particles(); ++i) {
    scene.state.v.segment<2>(3 * i) = Eigen::Vector2d(u(rng), u(rng));
    // Squeeze the blob a little so that pressures are not all zero.
    scene.state.x.segment<2>(3 * i) *= 0.97;
  }
  return scene;
}

Vec3 momentum(const MassSpringSystem& system, const State& s) {
  Vec3 p = Vec3::Zero();
  for (Index i = 0; i < system.num_particles(); ++i)
    p += system.masses()[i] * s.v.segment<3>(3 * i);
  return p;
}

TEST(Wcsph, PressureAndViscosityConserveMomentum) {
  auto scene = moving_blob(1e-3);
  WcsphOptions options;
  options.sound_speed = 20;
  WcsphStepper stepper(*scene.system, options);
  const Vec3 p0 = momentum(*scene.system, scene.state);
  double scale = 0;
  for (Index i = 0; i < scene.system->num_particles(); ++i)
    scale += scene.system->masses()[i] * scene.state.v.segment<3>(3 * i).norm();
  ASSERT_EQ(test::run_fluid(stepper, scene.state, 2e-4, 0.02).status, Status::Converged);
  EXPECT_GT(stepper.last_fluid_stats().max_density_error, 0.0);  // pressure did act
  EXPECT_LE((momentum(*scene.system, scene.state) - p0).norm(), 1e-13 * scale);
}

TEST(Wcsph, AStepFarBeyondTheCflLimitStopsTheRunAndSaysWhichLimit) {
  auto scene = test::tank_2d(0.01, 0.2, 0.4, 0.2, 0.2, FluidOptions{});
  WcsphOptions options;
  options.sound_speed = 20;
  WcsphStepper stepper(*scene.system, options);
  const double cfl = stepper.cfl_step(scene.state, 0.4);
  const StepSummary s = test::run_fluid(stepper, scene.state, 30 * cfl, 1.0);
  ASSERT_EQ(s.status, Status::Fatal);
  EXPECT_TRUE(s.message.rfind("CFL:", 0) == 0 || s.message.rfind("density:", 0) == 0) << s.message;
  EXPECT_TRUE(scene.state.is_finite());
}

TEST(Wcsph, RefusesBadOptionsAndSystemsWithoutAFluid) {
  WcsphOptions o;
  EXPECT_EQ(o.validate().field, "sound_speed");
  o.sound_speed = 10;
  EXPECT_TRUE(o.validate().ok());
  o.gamma = 0.5;
  EXPECT_EQ(o.validate().field, "gamma");
  MassSpringSystem springs(Vec::Ones(2), {0, 0});
  springs.finalize();
  EXPECT_NE(sph_unsupported(springs).find("no fluid"), std::string::npos);
  EXPECT_THROW(WcsphStepper(springs, WcsphOptions{10}), std::invalid_argument);
}

TEST(SphValidation, WcsphStillWaterStaysStill) {
  const double dx = 0.01, depth = 0.2, width = 0.2;
  const double c0 = 10 * std::sqrt(2 * kG * depth);  // Monaghan: 10 v_max
  FluidOptions fluid;
  fluid.viscosity = 0.1 * c0 * dx / (2 * 4);  // artificial viscosity alpha = 0.1, H / 2 = dx
  auto scene = test::tank_2d(dx, width, 2 * depth, width, depth, fluid);
  WcsphOptions options;
  options.sound_speed = c0;
  WcsphStepper stepper(*scene.system, options);
  const double t_ref = std::sqrt(depth / kG), h = 0.4 * dx / c0;
  // Settle for 10 t_ref, then 100 t_ref in which the water must stay still, with the pressure
  // field hydrostatic to 2% of rho0 g H at every depth.
  const auto w =
      test::StillWater::run(stepper, scene.state, h, 10 * t_ref, 100 * t_ref, dx, width, depth);
  ASSERT_EQ(w.last.status, Status::Converged) << w.last.message;
  const double at_rest = stepper.last_fluid_stats().mean_density_error;
  w.print("wcsph", depth, dx, at_rest, stepper.last_fluid_stats().max_speed);
  w.expect_still(dx, depth);
  w.expect_hydrostatic(0.02);
  EXPECT_LT(w.largest_mean_error, 0.01);
}

}  // namespace
}  // namespace hooke
