// Claims of solver/backends/fast_mass_spring.*: the objective's gradient is the backward-Euler
// residual (central differences); with enough iterations every variant (plain local/global,
// Chebyshev, L-BFGS) converges to the exact backward-Euler step computed by hooke's Newton
// iteration and, when built, by Ceres; plain local/global lowers the objective at every iteration;
// the matrix is refactored when h or the stiffness changes and not otherwise; pinned particles move
// with their velocity; the tolerance stop reports convergence or its failure; unsupported forces
// and bad options are refused with a message.
#include "hooke/config.hpp"

#if HOOKE_WITH_CHOLMOD

#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/parallel/helped_bins.hpp"
#include "hooke/registry.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"
#include "support/backend_scenes.hpp"
#include "support/finite_differences.hpp"
#include "support/random.hpp"
#include "support/systems.hpp"
#if HOOKE_WITH_CERES
#include "hooke/parallel/loops.hpp"
#include "hooke/whole_step/ceres/ceres_implicit_stepper.hpp"
#endif

namespace hooke {
namespace {

using test::hanging_cloth;
using test::Scene;

/// The scene after `steps` steps of hooke's Newton backward Euler from rest, so that the step under
/// test starts from a moving, folded cloth rather than the flat rest state.
State moving_state(const Scene& scene, double h, int steps) {
  auto newton = test::newton_backward_euler(*scene.system);
  State s = scene.state, s1;
  for (int k = 0; k < steps; ++k) {
    const StepSummary r = newton->step(s, h, s1);
    EXPECT_EQ(r.status, Status::Converged) << r.message;
    s = s1;
  }
  return s;
}

FastMassSpringOptions with(const std::string& acceleration, int iterations,
                           double tolerance = 0.0) {
  FastMassSpringOptions o;
  o.acceleration = hooke::from_string<hooke::Acceleration>(acceleration).value();
  o.chebyshev_delay = 10;
  o.iterations = iterations;
  o.tolerance = tolerance;
  return o;
}

/// ||a - b||_inf / ||scale||_inf.
double relative(const Vec& a, const Vec& b, const Vec& scale) {
  return (a - b).lpNorm<Eigen::Infinity>() / scale.lpNorm<Eigen::Infinity>();
}

TEST(FastMassSpring, ObjectiveGradientIsTheBackwardEulerResidual) {
  // grad g(x) = M (x - y) / h^2 - f(x, (x - x0) / h) at the free DOFs: the minimiser of g is the
  // backward-Euler step. Checked by central differences at random x near the start of the step.
  const Scene scene = hanging_cloth(4, 0.05, 1.05);
  const double h = 1e-2;
  FastMassSpringStepper fms(*scene.system);
  std::mt19937 rng(7);
  State s0 = scene.state;
  s0.v = test::random_vec(s0.v.size(), -0.3, 0.3, rng);
  for (Index p = 0; p < scene.system->num_particles(); ++p)
    if (scene.system->pinned()[size_t(p)]) s0.v.segment<3>(3 * p).setZero();
  const Vec y = s0.x + h * s0.v;
  const Vec& M = scene.system->mass_diagonal();
  int compared = 0;
  for (int sample = 0; sample < 5; ++sample) {
    Vec x = y + test::random_vec(y.size(), -0.02, 0.02, rng);
    for (Index p = 0; p < scene.system->num_particles(); ++p)
      if (scene.system->pinned()[size_t(p)]) x.segment<3>(3 * p) = y.segment<3>(3 * p);
    const Vec fd =
        test::central_gradient([&](const Vec& z) { return fms.objective(s0, h, z); }, x, 1e-6);
    Vec f(x.size());
    const Vec v1 = (x - s0.x) / h;
    scene.system->compute_forces(x, v1, f);
    const Vec residual = M.cwiseProduct(x - y) / (h * h) - f;
    for (Index p = 0; p < scene.system->num_particles(); ++p) {
      if (scene.system->pinned()[size_t(p)]) continue;
      for (int c = 0; c < 3; ++c) {
        const Index d = 3 * p + c;
        EXPECT_NEAR(fd[d], residual[d], 1e-6 * std::max(1.0, std::abs(residual[d]))) << "dof " << d;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 5 * 3 * 14);
}

struct Variant {
  const char* acceleration;
  int iterations;  // enough for 1e-8 on this scene (measured: see the test's output)
  const char* global_solver = "cholmod";
  const char* factor_precision = "double";
};

void PrintTo(const Variant& v, std::ostream* os) {
  *os << v.acceleration << " / " << v.global_solver << " (" << v.factor_precision << ") x "
      << v.iterations;
}

class FastMassSpringConvergence : public ::testing::TestWithParam<Variant> {};

TEST_P(FastMassSpringConvergence, ConvergesToTheExactBackwardEulerStep) {
  // A 6x6 cloth at a tenth of the default stiffness (k h^2 / m = 3.6 for the structural springs),
  // folded by 5 steps, with drag and wind: every supported term is in play.
  const Variant variant = GetParam();
  const Scene scene = hanging_cloth(6, 0.05, 1.0, 0.1);
  const double h = 1e-2;
  const State s0 = moving_state(scene, h, 5);
  State exact, s1;
  auto newton = test::newton_backward_euler(*scene.system);
  ASSERT_EQ(newton->step(s0, h, exact).status, Status::Converged);
  FastMassSpringOptions options = with(variant.acceleration, variant.iterations);
  options.global_solver = hooke::from_string<hooke::GlobalSolver>(variant.global_solver).value();
  options.factor_precision =
      hooke::from_string<hooke::FactorPrecision>(variant.factor_precision).value();
  FastMassSpringStepper fms(*scene.system, options);
  const StepSummary r = fms.step(s0, h, s1);
  ASSERT_EQ(r.status, Status::Converged) << r.message;
  EXPECT_EQ(r.iterations, variant.iterations);
  const double ex = relative(s1.x, exact.x, exact.x - s0.x), ev = relative(s1.v, exact.v, exact.v);
  std::printf("[ fms      ] %-9s %-7s %-6s %5d iterations: x %.2e, v %.2e relative to Newton\n",
              variant.acceleration, variant.global_solver, variant.factor_precision,
              variant.iterations, ex, ev);
  EXPECT_LT(ex, 1e-8);
  EXPECT_LT(ev, 1e-8);
  EXPECT_DOUBLE_EQ(s1.t, s0.t + h);
#if HOOKE_WITH_CERES
  CeresImplicitStepper ceres(*scene.system);
  State c1;
  ASSERT_EQ(ceres.step(s0, h, c1).status, Status::Converged);
  EXPECT_LT(relative(s1.x, c1.x, c1.x - s0.x), 1e-8);
  EXPECT_LT(relative(s1.v, c1.v, c1.v), 1e-8);
#endif
}

INSTANTIATE_TEST_SUITE_P(
    Accelerations, FastMassSpringConvergence,
    ::testing::Values(Variant{"none", 600}, Variant{"chebyshev", 250}, Variant{"lbfgs", 60},
                      Variant{"none", 300, "jacobi"}, Variant{"chebyshev", 100, "jacobi"},
                      Variant{"none", 600, "cholmod", "single"},
                      Variant{"chebyshev", 250, "cholmod", "single"},
                      Variant{"lbfgs", 60, "cholmod", "single"}),
    [](const auto& info) {
      return std::string(info.param.acceleration) +
             (std::string(info.param.global_solver) == "jacobi" ? "Jacobi" : "") +
             (std::string(info.param.factor_precision) == "single" ? "Single" : "");
    });

TEST(FastMassSpring, SinglePrecisionFactorLeavesTheConvergedStepUnchanged) {
  // The global step with a factor rounded to float corrects the iterate with its residual in
  // double, so the iteration has the same fixed point: converged to tolerance 1e-12 from a moving
  // state, every variant's step agrees with its double-precision twin to 1e-10 relative to the
  // positions (issue 18), and to 1e-8 relative to the step's displacement.
  const Scene scene = hanging_cloth(6, 0.05, 1.0, 0.1);
  const double h = 1e-2;
  const State s0 = moving_state(scene, h, 5);
  for (const char* a : {"none", "chebyshev", "lbfgs"}) {
    State d1, f1;
    FastMassSpringOptions o = with(a, 100000, 1e-12);
    FastMassSpringStepper dbl(*scene.system, o);
    o.factor_precision = FactorPrecision::Single;
    FastMassSpringStepper sgl(*scene.system, o);
    const StepSummary rd = dbl.step(s0, h, d1), rs = sgl.step(s0, h, f1);
    ASSERT_EQ(rd.status, Status::Converged) << a << ": " << rd.message;
    ASSERT_EQ(rs.status, Status::Converged) << a << ": " << rs.message;
    const double of_x = relative(f1.x, d1.x, d1.x), of_step = relative(f1.x, d1.x, d1.x - s0.x);
    std::printf(
        "[ fms f32  ] %-9s iterations %d (double %d); x differs by %.2e of x, %.2e of the "
        "step\n",
        a, rs.iterations, rd.iterations, of_x, of_step);
    EXPECT_GT(of_x, 0.0) << a << ": the rounded factor changes the iterates";
    EXPECT_LT(of_x, 1e-10) << a;
    EXPECT_LT(of_step, 1e-8) << a;
    EXPECT_LE(rs.iterations, rd.iterations + rd.iterations / 10 + 2) << a;
  }
}

TEST(FastMassSpring, PlainIterationsLowerTheObjectiveEveryTime) {
  // Local and global steps each minimise g exactly over their own variables (the directions, then
  // the positions), so g cannot rise (Liu et al. 2013, section 4). A stiff cloth converges slowly,
  // so all 60 decreases stay far above round-off.
  const Scene scene = hanging_cloth(8, 0.02, 1.0, 100.0);
  const double h = 1e-2;
  const State s0 = moving_state(scene, h, 3);
  FastMassSpringOptions o = with("none", 60);
  std::vector<double> g;
  FastMassSpringStepper* self = nullptr;
  o.on_iteration = [&](int, ConstRef x) { g.push_back(self->objective(s0, h, x)); };
  FastMassSpringStepper fms(*scene.system, o);
  self = &fms;
  const Vec y = s0.x + h * s0.v;
  const double g_start = fms.objective(s0, h, y);  // the inertial warm start
  State s1;
  ASSERT_EQ(fms.step(s0, h, s1).status, Status::Converged);
  ASSERT_EQ(g.size(), 60u);
  EXPECT_LT(g[0], g_start);
  int decreases = 0;
  for (size_t k = 1; k < g.size(); ++k) {
    EXPECT_LT(g[k], g[k - 1]) << "iteration " << k + 1;
    decreases += g[k] < g[k - 1];
  }
  EXPECT_EQ(decreases, 59);
  EXPECT_EQ(fms.objective(s0, h, s1.x), g.back());
}

TEST(FastMassSpring, SameBitsOnOneOrTwoThreadsWhateverTheTeamRuns) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  // Local/global and L-BFGS iterations run on one or all threads, chosen per iteration by their
  // recent times (AdaptiveTeam): sound only if every iteration gives the same bits on any thread
  // count. A cloth whose factor is large enough for the parallel solves (>= 1e5 entries); on two
  // threads the team's start alone runs iterations on both team sizes.
  const Scene scene = hanging_cloth(64, 0.02);
  const double h = 1e-2;
  const int threads = omp_get_max_threads();
  for (const char* acceleration : {"none", "lbfgs"}) {
    State out[2];
    for (int t = 1; t <= 2; ++t) {
      omp_set_num_threads(t);
      FastMassSpringStepper fms(*scene.system, with(acceleration, 12));
      State s = scene.state, s1;
      for (int k = 0; k < 2; ++k) {
        ASSERT_EQ(fms.step(s, h, s1).status, Status::Converged) << acceleration;
        std::swap(s, s1);
      }
      if (t == 2) {
        EXPECT_GE(fms.factor_nonzeros(), 1e5) << "large enough for two threads";
      }
      out[t - 1] = s;
    }
    omp_set_num_threads(threads);
    EXPECT_EQ((out[0].x - out[1].x).cwiseAbs().maxCoeff(), 0.0) << acceleration;
    EXPECT_EQ((out[0].v - out[1].v).cwiseAbs().maxCoeff(), 0.0) << acceleration;
    EXPECT_GT((out[0].x - scene.state.x).norm(), 0.0) << acceleration << ": the cloth moved";
  }
#endif
}

TEST(FastMassSpring, HelpedLocalStepGivesTheSameBitsAsOneThread) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one CPU: no helper thread";
  // With the team on one thread and a second CPU, the local step shares its particle ranges with
  // a helper thread that computes a range's springs in rows of its own (FastMassSpringStepper::
  // local_step). 130 x 130 particles: two ranges. The helper's results must be the one-thread
  // bits, whether it computes a range (kHelperFirst: the stepper lets it claim first) or the
  // stepper takes a stalled helper's range over (kHelperStalls: the helper sleeps 0.5 s in each)
  // rather than wait for it. Plain iterations, and L-BFGS with a tolerance (the gradient's rows
  // too); one spring set, and two grouped alike. Two OpenMP threads with the team's own choices
  // give the same bits too.
  const double h = 1e-2;
  const int threads = omp_get_max_threads();
  test::ClothSprings two_sets;
  two_sets.two_sets = true;
  const Scene scenes[2] = {hanging_cloth(130, 0.02), hanging_cloth(130, 0.02, 1.0, two_sets)};
  for (const Scene& scene : scenes)
    for (const FastMassSpringOptions& o : {with("none", 6), with("lbfgs", 8, 1e-9)}) {
      const std::string what =
          std::to_string(scene.system->forces().size()) + " forces, " + to_string(o.acceleration);
      // The final state, and each step's reported residual (with a tolerance, the error estimate
      // from the gradient's rows).
      std::vector<double> residuals[4];
      int case_no = 0;
      auto run = [&](int omp_threads, int flags, bool always,
                     FastMassSpringStepper::Helped* helped = nullptr) {
        std::vector<double>& residual = residuals[case_no++];
        omp_set_num_threads(omp_threads);
        FastMassSpringStepper fms(*scene.system, o);
        fms.test_local_helper(flags, always);
        State s = scene.state, s1;
        for (int k = 0; k < 2; ++k) {
          const StepSummary r = fms.step(s, h, s1);
          EXPECT_NE(r.status, Status::Fatal) << what;
          residual.push_back(r.residual);
          std::swap(s, s1);
        }
        if (helped) *helped = fms.local_helped();
        omp_set_num_threads(threads);
        return s;
      };
      const State one = run(1, 0, false);
      EXPECT_GT((one.x - scene.state.x).norm(), 0.0) << what << ": the cloth moved";
      FastMassSpringStepper::Helped first, stalled;
      const State by_helper = run(1, HelpedBins::kHelperFirst, true, &first);
      const State taken_over = run(1, HelpedBins::kHelperStalls, true, &stalled);
      const State two = run(2, 0, false);
      EXPECT_GT(first.helper_bins, 0) << what << ": the helper's ranges were used";
      // Every range a stalled helper held was taken over: had the stepper waited for one, the
      // helper would have finished it (0.5 s later) and its result would have been used.
      EXPECT_GT(stalled.taken_over, 0) << what << ": the stepper took ranges over";
      EXPECT_EQ(stalled.helper_bins, 0) << what << ": the stepper waited for a stalled helper";
      for (const State* s : {&by_helper, &taken_over, &two}) {
        EXPECT_EQ((s->x - one.x).cwiseAbs().maxCoeff(), 0.0) << what;
        EXPECT_EQ((s->v - one.v).cwiseAbs().maxCoeff(), 0.0) << what;
      }
      for (int c = 1; c < 4; ++c) EXPECT_EQ(residuals[c], residuals[0]) << what << ", case " << c;
    }
#endif
}

TEST(FastMassSpring, RefactorsWhenStepOrStiffnessChangesOnly) {
  Scene scene = hanging_cloth(5, 0.0);
  const double h = 1e-2;
  FastMassSpringStepper fms(*scene.system);
  State s = scene.state, s1;
  auto step = [&](double hh) {
    ASSERT_EQ(fms.step(s, hh, s1).status, Status::Converged);
    s = s1;
  };
  step(h);
  step(h);
  step(h);
  EXPECT_EQ(fms.factorizations(), 1);
  // The last step of a run whose duration is a multiple of h up to round-off keeps the factor
  // (issue 18); a resumed run handed the factored h (history) takes the same bits.
  const std::vector<double> history = fms.history();
  ASSERT_EQ(history, std::vector<double>{h});
  const State before_last = s;
  step(h * (1 + 1e-13));
  EXPECT_EQ(fms.factorizations(), 1);
  FastMassSpringStepper resumed(*scene.system);
  resumed.restore_history(history);
  State r1;
  ASSERT_EQ(resumed.step(before_last, h * (1 + 1e-13), r1).status, Status::Converged);
  EXPECT_EQ((r1.x - s.x).lpNorm<Eigen::Infinity>(), 0.0);
  step(h * (1 + 1e-9));  // a real change of h refactors
  EXPECT_EQ(fms.factorizations(), 2);
  step(h);
  EXPECT_EQ(fms.factorizations(), 3);
  step(h / 2);
  EXPECT_EQ(fms.factorizations(), 4);
  step(h / 2);
  EXPECT_EQ(fms.factorizations(), 4);
  // A stiffness change between steps (through mutable_force) must refactor: the result then equals,
  // bit for bit, a fresh stepper's on the changed system.
  static_cast<HookeSpring&>(scene.system->mutable_force(0)).scale_stiffness(3.0);
  State before = s;
  step(h / 2);
  EXPECT_EQ(fms.factorizations(), 5);
  FastMassSpringStepper fresh(*scene.system);
  State f1;
  ASSERT_EQ(fresh.step(before, h / 2, f1).status, Status::Converged);
  EXPECT_EQ((f1.x - s.x).lpNorm<Eigen::Infinity>(), 0.0);
  step(h / 2);
  EXPECT_EQ(fms.factorizations(), 5);
}

/// The chain of issue 58 (item 1): 6 particles 0.21 m apart on the x axis (5% longer than the
/// springs' rest length 0.2 m), 0.05 kg each, k = 80 N/m, the first pinned, under gravity.
struct StretchedChain {
  std::unique_ptr<MassSpringSystem> system;
  State state{6};
  StretchedChain() {
    std::vector<char> pinned(6, 0);
    pinned[0] = 1;
    system = std::make_unique<MassSpringSystem>(Vec::Constant(6, 0.05), pinned);
    auto springs = std::make_unique<HookeSpring>();
    for (int p = 0; p < 6; ++p) state.x.segment<3>(3 * p) = Vec3(0.21 * p, 0.0, 0.0);
    for (int p = 0; p + 1 < 6; ++p) springs->add(p, p + 1, 80.0, 0.2);
    system->add_force(std::move(springs));
    system->add_force(std::make_unique<Gravity>(Vec::Constant(6, 0.05), Vec3(0.0, -9.81, 0.0)));
    system->finalize();
  }
};

TEST(FastMassSpring, LastStepRoundedFromDtConvergesAtTightTolerances) {
  // A run of 0.5 s at dt = 1e-3 (or 5e-4) whose last step lands on the duration, h = 0.5 - t with
  // t the sum of the steps: that h differs from dt in its last bits, the stepper keeps the factor
  // of dt (kSameStep), and before issue 58 it iterated towards the fixed point of that factor's
  // mass term (M / dt^2 where the step has M / h^2), stalling at an error of 1.5e-12 with 5000
  // iterations (not-converged). Each step must converge, and the last one equal the step of a
  // fresh stepper factored for its own h to the tolerance.
  const StretchedChain chain;
  for (const double dt : {1e-3, 5e-4}) {
    for (const double tolerance : {1e-12, 1e-13, 1e-14}) {
      FastMassSpringStepper fms(*chain.system, with("none", 5000, tolerance));
      State s = chain.state, s1;
      const long long steps = std::llround(0.5 / dt);
      int rounded = 0;
      for (long long k = 1; k <= steps; ++k) {
        const double h = k == steps ? 0.5 - s.t : dt;
        rounded += h != dt;
        const State s0 = s;
        const StepSummary r = fms.step(s0, h, s1);
        ASSERT_EQ(r.status, Status::Converged)
            << "dt " << dt << ", tolerance " << tolerance << ", step " << k
            << " (h - dt = " << h - dt << "): " << r.message;
        if (k == steps) {
          FastMassSpringStepper fresh(*chain.system, with("none", 5000, tolerance));
          State f1;
          ASSERT_EQ(fresh.step(s0, h, f1).status, Status::Converged);
          // Both are within the tolerance (relative to the chain's 1.05 m) of the exact step.
          EXPECT_LE((f1.x - s1.x).lpNorm<Eigen::Infinity>(), 2 * tolerance * 1.05)
              << "dt " << dt << ", tolerance " << tolerance;
        }
        s = s1;
      }
      EXPECT_EQ(fms.factorizations(), 1) << "dt " << dt;  // the rounded h kept dt's factor
      EXPECT_EQ(rounded, 1) << "dt " << dt << ": the last h is not dt's rounding, test void";
    }
  }
}

TEST(FastMassSpring, PinnedParticlesMoveWithTheirVelocity) {
  const Scene scene = hanging_cloth(4, 0.0);
  State s0 = scene.state, s1;
  const Vec3 w(0.1, -0.2, 0.3);
  s0.v.segment<3>(0) = w;  // particle 0 is pinned
  FastMassSpringStepper fms(*scene.system);
  ASSERT_EQ(fms.step(s0, 1e-2, s1).status, Status::Converged);
  EXPECT_EQ(s1.v.segment<3>(0), w);
  EXPECT_NEAR((s1.x.segment<3>(0) - s0.x.segment<3>(0) - 1e-2 * w).norm(), 0.0, 1e-16);
}

TEST(FastMassSpring, ToleranceStopsEarlyOrSaysItDidNot) {
  const Scene scene = hanging_cloth(6, 0.05);
  const double h = 1e-2;
  const State s0 = moving_state(scene, h, 2);
  State s1;
  for (const char* a : {"none", "chebyshev", "lbfgs"}) {
    FastMassSpringStepper loose(*scene.system, with(a, 5000, 1e-6));
    const StepSummary r = loose.step(s0, h, s1);
    EXPECT_EQ(r.status, Status::Converged) << a << ": " << r.message;
    EXPECT_GT(r.iterations, 1) << a;
    EXPECT_LT(r.iterations, 5000) << a;
    EXPECT_LE(r.residual, 1e-6) << a;
    FastMassSpringStepper capped(*scene.system, with(a, 2, 1e-12));
    const StepSummary c = capped.step(s0, h, s1);
    EXPECT_EQ(c.status, Status::NotConverged) << a;
    EXPECT_NE(c.message.find("iterations"), std::string::npos) << c.message;
    EXPECT_TRUE(s1.is_finite()) << a;
  }
}

TEST(FastMassSpring, ToleranceOnTheGradientGivesTheExactStep) {
  // The soft 6x6 cloth (k 400 / 100 / 10 N/m, no dampers) converges slowly under plain
  // local/global: a stop on the change per iteration left it 1.0e-7 m from the exact step at
  // tolerance 1e-12. The stop on the gradient (whole_step tolerance rule) must hold each step
  // within 2e-12 and a 20-step run within 1e-9 of Newton's, relative to the cloth's size (1 m).
  const Scene scene = hanging_cloth(6, 0.0, 1.0, test::ClothSprings{400.0, 100.0, 10.0, 0.0});
  const double h = 1e-2;
  auto newton = test::newton_backward_euler(*scene.system);
  for (const char* a : {"none", "chebyshev", "lbfgs"}) {
    FastMassSpringStepper fms(*scene.system, with(a, 100000, 1e-12));
    State exact = scene.state, run = scene.state, e1, r1, f1;
    double worst_step = 0.0;
    long long iterations = 0;
    for (int k = 0; k < 20; ++k) {
      ASSERT_EQ(newton->step(exact, h, e1).status, Status::Converged);
      const StepSummary one = fms.step(exact, h, f1);  // one step from the exact state
      ASSERT_EQ(one.status, Status::Converged) << a << ": " << one.message;
      EXPECT_LE(one.residual, 1e-12) << a;
      iterations += one.iterations;
      worst_step = std::max(worst_step, (f1.x - e1.x).lpNorm<Eigen::Infinity>());
      ASSERT_EQ(fms.step(run, h, r1).status, Status::Converged) << a;
      exact = e1;
      run = r1;
    }
    const double drift = (run.x - exact.x).lpNorm<Eigen::Infinity>();
    std::printf(
        "[ fms tol  ] %-9s tolerance 1e-12: worst step %.2e m, after 20 steps %.2e m "
        "(%lld iterations over 20 steps)\n",
        a, worst_step, drift, iterations);
    // The cloth is 1 m wide: relative and in metres alike. One step from the exact state lands
    // within about the tolerance of the exact step (docs/methods.md: measured 9.8e-13 .. 1.0e-12
    // for the three accelerations), the error estimate being nearly tight on the slow modes.
    EXPECT_LT(worst_step, 2e-12) << a;
    EXPECT_LT(drift, 1e-9) << a;
  }
}

TEST(FastMassSpring, StepResidualMeasuresTheBackwardEulerEquations) {
  // step_residual() is 0 for the exact step: hooke's Newton backward Euler (an independent solver
  // of the same equations) gives round-off; a converged local/global step gives little; a fixed
  // count of 2 iterations leaves much more, which the step's residual and report() then show.
  const Scene scene = hanging_cloth(6, 0.05);
  const double h = 1e-2;
  const State s0 = moving_state(scene, h, 2);
  State exact, s1;
  ASSERT_EQ(test::newton_backward_euler(*scene.system)->step(s0, h, exact).status,
            Status::Converged);
  FastMassSpringStepper converged(*scene.system, with("none", 20000, 1e-10));
  const double r_exact = converged.step_residual(s0, h, exact);
  const StepSummary c = converged.step(s0, h, s1);
  ASSERT_EQ(c.status, Status::Converged) << c.message;
  const double r_converged = converged.step_residual(s0, h, s1);
  FastMassSpringStepper two(*scene.system, with("none", 2));
  const StepSummary r = two.step(s0, h, s1);
  const double r_two = two.step_residual(s0, h, s1);
  std::printf("[ residual ] exact %.2e, converged local/global %.2e, 2 iterations %.2e\n", r_exact,
              r_converged, r_two);
  EXPECT_LT(r_exact, 1e-9);
  EXPECT_LT(r_converged, 1e-5);
  EXPECT_GT(r_two, 100.0 * r_converged);
  EXPECT_EQ(r.residual, r_two);  // tolerance 0: the step reports this residual
  const std::string report = two.report();
  EXPECT_NE(report.find("worst relative residual of the backward-Euler equations"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("(step 1)"), std::string::npos) << report;
}

TEST(FastMassSpring, RefusesDampersAndBadOptions) {
  test::ClothSpec spec;
  spec.n = 4;
  const test::Cloth cloth = test::make_cloth(spec);  // has a SpringDamper
  const std::string why = fast_mass_spring_unsupported(*cloth.system);
  EXPECT_NE(why.find("spring-damper"), std::string::npos) << why;
  EXPECT_EQ(method_unsupported("fast-mass-spring", *cloth.system), why);
  EXPECT_THROW(make_stepper("fast-mass-spring", *cloth.system), std::invalid_argument);
  const Scene scene = hanging_cloth(3, 0.0);
  EXPECT_EQ(fast_mass_spring_unsupported(*scene.system), "");
  // Choices are enums: a name that is none of them is refused where text is read (scenes).
  EXPECT_FALSE(hooke::from_string<hooke::Acceleration>("newton"));
  EXPECT_FALSE(hooke::from_string<hooke::GlobalSolver>("lu"));
  EXPECT_EQ(hooke::choice_names<hooke::GlobalSolver>(), "cholmod, jacobi");
  for (auto bad : {with("none", 0), with("none", 10, 1.5)}) {
    EXPECT_NE(bad.validate().message, "");
    EXPECT_THROW(FastMassSpringStepper(*scene.system, bad), std::invalid_argument);
  }
  FastMassSpringOptions rho;
  rho.chebyshev_rho = 1.0;
  EXPECT_NE(rho.validate().message.find("chebyshev_rho"), std::string::npos);
  FastMassSpringOptions global = with("lbfgs", 10);
  global.global_solver = hooke::GlobalSolver::Jacobi;  // L-BFGS needs the factored matrix
  EXPECT_EQ(global.validate().field, "global_solver");
  EXPECT_NE(global.validate().message.find("global_solver"), std::string::npos);
  EXPECT_THROW(FastMassSpringStepper(*scene.system, global), std::invalid_argument);
}

TEST(FastMassSpring, JacobiGlobalStepLowersTheObjectiveAndNeedsNoFactor) {
  // One Jacobi sweep is a gradient step preconditioned by D = diag(A), and the Hessian of g is
  // at most A (Liu et al. 2013): with the eigenvalues of D^-1 A in (0, 2) every sweep lowers g.
  const Scene scene = hanging_cloth(8, 0.02, 1.0, 100.0);
  const double h = 1e-2;
  const State s0 = moving_state(scene, h, 3);
  FastMassSpringOptions o = with("none", 40);
  o.global_solver = hooke::GlobalSolver::Jacobi;
  std::vector<double> g;
  FastMassSpringStepper* self = nullptr;
  o.on_iteration = [&](int, ConstRef x) { g.push_back(self->objective(s0, h, x)); };
  FastMassSpringStepper fms(*scene.system, o);
  self = &fms;
  State s1;
  ASSERT_EQ(fms.step(s0, h, s1).status, Status::Converged);
  ASSERT_EQ(g.size(), 40u);
  EXPECT_LT(g[0], fms.objective(s0, h, s0.x + h * s0.v));
  int decreases = 0;
  for (size_t k = 1; k < g.size(); ++k) decreases += g[k] < g[k - 1];
  EXPECT_EQ(decreases, 39);
  EXPECT_EQ(fms.factor_nonzeros(), 0.0);
  EXPECT_EQ(fms.factorizations(), 1);  // the one value refresh of the global matrix
}

}  // namespace
}  // namespace hooke

#endif  // HOOKE_WITH_CHOLMOD
