// Claims of solver/sph/sph_stepper.* shared by every pressure method: a run gives the same bits
// on one and two threads (each particle's sums run in its own neighbour order); the methods of
// the registry, which know nothing of pressure, refuse a fluid.
#include "hooke/sph/sph_stepper.hpp"

#include <gtest/gtest.h>

#include <memory>

#include "hooke/registry.hpp"
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
  IisphOptions options;
  options.max_iterations = 1000;  // the first step starts cold
  return std::make_unique<IisphStepper>(system, options);
}

TEST(SphStepper, SameBitsOnOneOrTwoThreads) {
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  for (const char* method : {"wcsph", "iisph"}) {
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

TEST(SphStepper, EveryRegisteredMethodRefusesAFluid) {
  // The registry's methods would step the particles under gravity alone: they must say so.
  auto scene = test::tank_2d(0.01, 0.2, 0.2, 0.1, 0.1, FluidOptions{});
  int refused = 0;
  for (const auto& m : methods()) {
    const std::string why = method_unsupported(m.name, *scene.system);
    EXPECT_NE(why.find("SPH"), std::string::npos) << m.name << ": '" << why << "'";
    refused += !why.empty();
  }
  EXPECT_EQ(refused, int(methods().size()));
  EXPECT_GE(refused, 10);
}

}  // namespace
}  // namespace hooke
