// The PETSc linear backend (solver/linear/petsc_solver.*): it takes the same implicit steps as
// hooke's own pcg-nodal to within 1e-8 m, and every way of giving it options works as documented:
// the scene's string, the environment (PETSC_OPTIONS), explicit -ksp_rtol / -ksp_max_it over
// linear_tolerance / max_linear_iterations, and invalid or misspelt options refused by name.
// On two threads the default preconditioner's x, y and z splits run concurrently and give the
// bits of PETSc's own one-after-another PCFIELDSPLIT on one thread.
// The registry sweeps of tests/linear and tests/integrators cover it as one backend among all.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdlib>
#include <string>

#include "hooke/config.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/simulation.hpp"
#include "support/backend_scenes.hpp"
#include "support/registry.hpp"

#if HOOKE_WITH_PETSC
#include "hooke/linear/petsc/petsc_solver.hpp"
#include "hooke/parallel/loops.hpp"

namespace {

using hooke::ImplicitOptions;
using hooke::State;
using hooke::Status;

/// Sets an environment variable for the life of the object (restoring the old value).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : m_name(name) {
    if (const char* old = std::getenv(name)) m_old = old, m_had = true;
    setenv(name, value, 1);
  }
  ~ScopedEnv() {
    if (m_had)
      setenv(m_name, m_old.c_str(), 1);
    else
      unsetenv(m_name);
  }

 private:
  const char* m_name;
  std::string m_old;
  bool m_had = false;
};

/// Ten backward-Euler steps of h = 0.05 s (h^2 k / m = 6400 for the structural springs) of a
/// 12 x 12 cloth on one backend, at linear_tolerance 1e-12.
State ten_steps(const std::string& backend, const std::string& petsc_options = "") {
  const hooke::test::Scene scene = hooke::test::hanging_cloth(12, 0.1);
  ImplicitOptions o;
  o.linear_solver = backend;
  o.linear_tolerance = 1e-12;
  o.petsc_options = petsc_options;
  hooke::Simulation sim(*scene.system, hooke::make_stepper("implicit", *scene.system, o),
                        scene.state);
  for (int k = 0; k < 10; ++k) {
    const hooke::StepSummary s = sim.advance(0.05);
    EXPECT_EQ(s.status, Status::Converged) << backend << " " << petsc_options << ": " << s.message;
  }
  return sim.state();
}

TEST(PetscSolver, TenLargeStepsAgreeWithPcgNodalWithin1e8) {
  if (!hooke::test::has_backend("pcg-nodal")) GTEST_SKIP() << "pcg-nodal needs CHOLMOD";
  const State ref = ten_steps("pcg-nodal");
  for (const char* options :
       {"", "-pc_type hypre", "-pc_type gamg",
        "-pc_type gamg -hooke_rigid_body_modes -mg_levels_ksp_type richardson "
        "-mg_levels_pc_type sor"}) {
    const State s = ten_steps("petsc", options);
    const double dx = (s.x - ref.x).lpNorm<Eigen::Infinity>();
    std::printf("[ petsc    ] %-40s max |x - x_pcg-nodal| = %.3g m after 10 steps\n",
                options[0] ? options : "(defaults: CG + BoomerAMG per coordinate)", dx);
    EXPECT_LT(dx, 1e-8) << options;
    // The cloth really moved: the comparison is not between two resting states.
    EXPECT_GT((s.x - hooke::test::hanging_cloth(12, 0.1).state.x).norm(), 1e-2);
  }
}

/// One solve of the cloth's backward-Euler matrix by the backend with these options.
hooke::LinearSummary one_solve(const std::string& petsc_options,
                               const hooke::LinearSolveOptions& lin) {
  const hooke::test::Scene scene = hooke::test::hanging_cloth(12, 0.1);
  ImplicitOptions o;
  o.linear_solver = "petsc";
  o.linear_tolerance = lin.tolerance;
  o.max_linear_iterations = lin.max_iterations;
  o.petsc_options = petsc_options;
  auto stepper = hooke::make_stepper("implicit", *scene.system, o);
  State s1;
  const hooke::StepSummary s = stepper->step(scene.state, 0.05, s1);
  hooke::LinearSummary out;
  out.status = s.status;
  out.iterations = s.iterations;
  out.residual = s.residual;
  out.message = s.message;
  return out;
}

TEST(PetscSolver, SceneOptionsOverrideTheLinearTolerance) {
  hooke::LinearSolveOptions tight;
  tight.tolerance = 1e-12;
  const hooke::LinearSummary base = one_solve("", tight);
  ASSERT_EQ(base.status, Status::Converged) << base.message;
  EXPECT_LT(base.residual, 1e-12);
  // An explicit -ksp_rtol wins over linear_tolerance: a looser solve, fewer iterations.
  const hooke::LinearSummary loose = one_solve("-ksp_rtol 1e-3", tight);
  ASSERT_EQ(loose.status, Status::Converged) << loose.message;
  EXPECT_GT(loose.residual, 1e-12);
  EXPECT_LT(loose.residual, 1e-3);
  EXPECT_LT(loose.iterations, base.iterations);
  // -ksp_max_it 1 wins over max_linear_iterations: not converged after one iteration.
  const hooke::LinearSummary capped = one_solve("-ksp_max_it 1", tight);
  EXPECT_EQ(capped.status, Status::NotConverged) << capped.message;
  EXPECT_EQ(capped.iterations, 1);
  EXPECT_NE(capped.message.find("DIVERGED_ITS"), std::string::npos) << capped.message;
  // And without either, linear_tolerance and max_linear_iterations are what counts.
  hooke::LinearSolveOptions two;
  two.tolerance = 1e-12;
  two.max_iterations = 2;
  const hooke::LinearSummary two_its = one_solve("", two);
  EXPECT_EQ(two_its.status, Status::NotConverged);
  EXPECT_EQ(two_its.iterations, 2);
}

TEST(PetscSolver, EnvironmentOptionsApplyAndOverrideTheScene) {
  hooke::LinearSolveOptions tight;
  tight.tolerance = 1e-12;
  {
    const ScopedEnv env("PETSC_OPTIONS", "-ksp_max_it 1");
    const hooke::LinearSummary s = one_solve("", tight);
    EXPECT_EQ(s.status, Status::NotConverged) << s.message;
    EXPECT_EQ(s.iterations, 1);
  }
  {
    // The scene asks for 1 iteration, the environment for 3: the environment wins.
    const ScopedEnv env("PETSC_OPTIONS", "-ksp_max_it 3");
    const hooke::LinearSummary s = one_solve("-ksp_max_it 1", tight);
    EXPECT_EQ(s.iterations, 3) << s.message;
  }
  const hooke::LinearSummary s = one_solve("", tight);  // the variable is gone again
  EXPECT_EQ(s.status, Status::Converged) << s.message;
}

TEST(PetscSolver, InvalidOrUnusedOptionsAreNamed) {
  EXPECT_EQ(hooke::petsc_options_problem(""), "");
  EXPECT_EQ(hooke::petsc_options_problem("-pc_type hypre -pc_hypre_type boomeramg"), "");
  EXPECT_EQ(hooke::petsc_options_problem(
                "-pc_type gamg -mg_levels_ksp_type richardson -pc_gamg_threshold 0.02"),
            "");
  EXPECT_EQ(hooke::petsc_options_problem("-pc_type gamg -hooke_rigid_body_modes"), "");
  EXPECT_EQ(hooke::petsc_options_problem("-fieldsplit_0_pc_hypre_boomeramg_agg_nl 1"), "");
  // Each refused string: the problem names the offending part.
  const auto expect_named = [](const std::string& options, const std::string& named) {
    const std::string why = hooke::petsc_options_problem(options);
    EXPECT_NE(why.find(named), std::string::npos) << options << ": " << why;
  };
  // A GAMG option with the default preconditioner (fieldsplit + BoomerAMG) is read by nothing.
  expect_named("-pc_gamg_threshold 0.02", "-pc_gamg_threshold");
  expect_named("-hooke_setup_cost -1", "-hooke_setup_cost");
  expect_named("-pc_type no_such_pc", "no_such_pc");
  expect_named("-ksp_rtoll 1e-3", "-ksp_rtoll");
  expect_named("ksp_type cg", "'ksp_type' is not an option");
  expect_named("-ksp_rtol abc", "abc");
  {
    const ScopedEnv env("PETSC_OPTIONS", "-ksp_typo 1");
    expect_named("", "-ksp_typo");
  }
}

TEST(PetscSolver, HierarchyIsReusedAcrossSteps) {
  const hooke::test::Scene scene = hooke::test::hanging_cloth(16, 0.1);
  ImplicitOptions o;
  o.linear_solver = "petsc";
  hooke::Simulation sim(*scene.system, hooke::make_stepper("implicit", *scene.system, o),
                        scene.state);
  for (int k = 0; k < 20; ++k) ASSERT_EQ(sim.advance(0.01).status, Status::Converged);
  const long long builds = sim.stepper().stats().factorizations;
  std::printf("[ petsc    ] 20 steps, %lld hierarchy builds, %lld iterations\n", builds,
              sim.stepper().stats().linear_iterations);
  EXPECT_GE(builds, 1);
  EXPECT_LT(builds, 20);
}

/// Sets OpenMP's thread count for the life of the object.
class ScopedThreads {
 public:
  explicit ScopedThreads(int n) : m_old(omp_get_max_threads()) { omp_set_num_threads(n); }
  ~ScopedThreads() { omp_set_num_threads(m_old); }

 private:
  int m_old;
};

/// Twenty backward-Euler steps of h = 0.05 s of the 12 x 12 cloth on `threads` threads with the
/// default preconditioner and a zero set-up cost, so that the hierarchies are rebuilt whenever a
/// solve costs more than the average since the last build (and the concurrent splits are set up
/// again, which must happen outside the threads). builds: the set-ups.
State twenty_steps(int threads, const std::string& petsc_options, long long& builds) {
  const ScopedThreads scoped(threads);
  const hooke::test::Scene scene = hooke::test::hanging_cloth(12, 0.1);
  ImplicitOptions o;
  o.linear_solver = "petsc";
  o.linear_tolerance = 1e-10;
  o.petsc_options = "-hooke_setup_cost 0 " + petsc_options;
  hooke::Simulation sim(*scene.system, hooke::make_stepper("implicit", *scene.system, o),
                        scene.state);
  for (int k = 0; k < 20; ++k) {
    const hooke::StepSummary s = sim.advance(0.05);
    EXPECT_EQ(s.status, Status::Converged) << threads << " threads: " << s.message;
  }
  builds = sim.stepper().stats().factorizations;
  return sim.state();
}

TEST(PetscSolver, ConcurrentSplitsGiveTheBitsOfTheSequentialFieldsplit) {
  long long builds_one = 0, builds_two = 0;
  // One thread: PETSc's PCFIELDSPLIT applies the splits in turn.
  const State one = twenty_steps(1, "", builds_one);
  // Two threads: hooke's PCSHELL applies them concurrently (-ksp_view says so).
  testing::internal::CaptureStdout();
  const State two = twenty_steps(2, "-ksp_view", builds_two);
  const std::string view = testing::internal::GetCapturedStdout();
  std::printf("[ petsc    ] 20 steps: %lld hierarchy builds (1 thread), %lld (2 threads)\n",
              builds_one, builds_two);
  EXPECT_NE(view.find("3 splits applied concurrently"), std::string::npos) << view;
  EXPECT_NE(view.find("type: fieldsplit"), std::string::npos) << view;
  EXPECT_GE(builds_two, 3);  // set-ups after the first, while the splits run concurrently
  EXPECT_EQ(builds_one, builds_two);
  EXPECT_TRUE(one.x == two.x) << "max |dx| " << (one.x - two.x).lpNorm<Eigen::Infinity>();
  EXPECT_TRUE(one.v == two.v) << "max |dv| " << (one.v - two.v).lpNorm<Eigen::Infinity>();
}

}  // namespace

#endif  // HOOKE_WITH_PETSC
