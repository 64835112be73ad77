// [fluid] scenes (problems/builders/fluid.cpp): the shipped dam break holds Martin and Moyce's
// geometry, a scene builds the system the SPH library builds from the same boxes (the same bits
// after a step), and the fluid's boxes are checked against each other.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "hooke/registry.hpp"
#include "hooke/sph/fluid_system.hpp"
#include "hooke/sph/sampling.hpp"
#include "hooke/sph/wcsph.hpp"
#include "problems/scene.hpp"

namespace hooke {
namespace {

std::string scene_path(const char* name) {
  const char* env = std::getenv("HOOKE_SOURCE_DIR");
  return (std::filesystem::path(env ? env : HOOKE_SOURCE_DIR) / "problems" / "scenes" / name)
      .string();
}

TEST(FluidScene, DamBreakHoldsMartinAndMoyceGeometry) {
  const Scene scene = load_scene(scene_path("dam_break_2d.toml"));
  ASSERT_TRUE(scene.is_fluid());
  const FluidModel& fluid = *scene.system->fluid();
  const double a = 0.25, dx = a / 20;
  EXPECT_EQ(fluid.dimension(), 2);
  EXPECT_EQ(fluid.options().spacing, dx);
  // A column a wide and 2a high, on the lattice: 20 x 40 particles.
  ASSERT_EQ(fluid.num_fluid(), 800);
  for (Index i = 0; i < fluid.num_fluid(); ++i) {
    const Vec3 x = scene.initial.x.segment<3>(3 * i);
    EXPECT_GT(x.x(), 0.0);
    EXPECT_LT(x.x(), a);
    EXPECT_GT(x.y(), 0.0);
    EXPECT_LT(x.y(), 2 * a);
    EXPECT_EQ(x.z(), 0.0);
  }
  EXPECT_EQ(fluid.num_boundary(),
            Index(sample_tank(Vec3::Zero(), Vec3(5 * a, 4 * a, 0), dx, 2, 2).size()));
  EXPECT_DOUBLE_EQ(scene.system->masses()[0], 1000.0 * dx * dx);
  EXPECT_EQ(scene.integrator.method, "wcsph");
  const auto* options = scene.integrator.options.get<WcsphOptions>();
  ASSERT_NE(options, nullptr);
  EXPECT_EQ(options->courant, 0.4);
  // Monaghan's rule: c0 = 10 sqrt(2 g 2a) to 3 digits.
  EXPECT_NEAR(options->sound_speed, 10 * std::sqrt(2 * 9.81 * 2 * a), 0.05);
}

TEST(FluidScene, BuildsTheSystemTheLibraryBuildsFromTheSameBoxes) {
  const std::string text =
      "[fluid]\ndimension = 2\nspacing = 0.01\nkernel = 'wendland-c2'\nviscosity = 1e-4\n"
      "[[fluid.block]]\nlower = [0, 0, 0]\nupper = [0.1, 0.15, 0]\n"
      "[[fluid.block]]\nlower = [0.2, 0, 0]\nupper = [0.3, 0.05, 0]\n"
      "[fluid.tank]\nlower = [0, 0, 0]\nupper = [0.4, 0.3, 0]\nlayers = 3\n"
      "[[fluid.obstacle]]\nlower = [0.15, 0, 0]\nupper = [0.17, 0.04, 0]\n"
      "[forces]\ngravity = [0, -9.81, 0]\n"
      "[integrator]\nmethod = 'wcsph'\nsound_speed = 25\ncourant = 0\n";
  const Scene scene = load_scene_from_string(text, "fluid.toml");
  FluidOptions o;
  o.dimension = 2;
  o.spacing = 0.01;
  o.kernel = KernelType::WendlandC2;
  o.viscosity = 1e-4;
  auto water = sample_box(Vec3::Zero(), Vec3(0.1, 0.15, 0), 0.01, 2);
  const auto second = sample_box(Vec3(0.2, 0, 0), Vec3(0.3, 0.05, 0), 0.01, 2);
  water.insert(water.end(), second.begin(), second.end());
  auto walls = sample_tank(Vec3::Zero(), Vec3(0.4, 0.3, 0), 0.01, 2, 3);
  const auto box = sample_solid_box(Vec3(0.15, 0, 0), Vec3(0.17, 0.04, 0), 0.01, 2, 2);
  walls.insert(walls.end(), box.begin(), box.end());
  const FluidSystem library = make_fluid_system(water, walls, o, Vec3(0, -9.81, 0));
  ASSERT_TRUE(scene.initial.x == library.state.x);
  EXPECT_TRUE(scene.system->masses() == library.system->masses());
  EXPECT_TRUE(scene.system->fluid()->boundary_psi() == library.system->fluid()->boundary_psi());
  // Ten steps of each: the same bits.
  WcsphOptions w;
  w.sound_speed = 25;
  auto from_scene = make_stepper("wcsph", *scene.system, scene.integrator.options);
  WcsphStepper direct(*library.system, w);
  State a = scene.initial, b = library.state, next = a;
  for (int k = 0; k < 10; ++k) {
    ASSERT_EQ(from_scene->step(a, 1e-4, next).status, Status::Converged);
    std::swap(a, next);
    ASSERT_EQ(direct.step(b, 1e-4, next).status, Status::Converged);
    std::swap(b, next);
  }
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.v == b.v);
  EXPECT_GT(a.v.norm(), 0.0);
}

TEST(FluidScene, ABlockMayTouchTheTankAndAnotherBlock) {
  // Faces in common are not overlaps: water fills a tank exactly, in two blocks.
  const std::string text =
      "[fluid]\ndimension = 2\nspacing = 0.01\n"
      "[[fluid.block]]\nlower = [0, 0, 0]\nupper = [0.1, 0.1, 0]\n"
      "[[fluid.block]]\nlower = [0.1, 0, 0]\nupper = [0.2, 0.1, 0]\n"
      "[fluid.tank]\nlower = [0, 0, 0]\nupper = [0.2, 0.1, 0]\n"
      "[integrator]\nmethod = 'iisph'\n";
  const Scene scene = load_scene_from_string(text, "fluid.toml");
  EXPECT_EQ(scene.system->fluid()->num_fluid(), 200);
}

}  // namespace
}  // namespace hooke
