// The two performance targets of issue 7, on their shipped scene files (problems/scenes/), so
// anyone can rerun them:
//  - LocalGlobal411: target_local_global_411.toml, a 411 x 411 cloth with 842k springs solved by
//    fast-mass-spring (Liu et al. 2013). Counters: one-off analysis and factorization, nnz(L), and
//    one local/global iteration split into its local step and its global solve (3 right-hand
//    sides), averaged over steps of 10 iterations after a warm-up step, and team_all, the share of
//    those iterations run on all threads (the adaptive team's choice). The target is 27 ms per
//    iteration (4x a typical public implementation's 107 ms). .../single:1 reads the factor
//    rounded to float (integrator.factor_precision = "single", issue 18).
//  - BackwardEuler256/<linear solver>: target_backward_euler_256.toml, a 256 x 256 cloth (391k
//    springs), one linearised backward-Euler step (beta = 1) per h = 0.01 s at linear tolerance
//    1e-6, averaged over a run of steps from rest (the first, with the first factorization,
//    included: it is what a user pays; first_step_s and later_steps_s split it). The stepper's
//    set-up (the symbolic analysis of the pattern, made when it is constructed) is outside the
//    timed steps and reported as its own figure, setup_s. Counters: PCG iterations,
//    factorizations and their seconds, solve and assembly seconds per step, and team_all, the
//    share of the linear iterations run on all threads (CG's adaptive team). The target is 0.64 s
//    per step (10x a classic Jacobi-PCG's 6.4 s).
//  - BackwardEuler256/Bending/model:{0,...,5}: that step with no, dihedral, quadratic,
//    eigenvalue-projected dihedral, shell or eigenvalue-projected shell bending (issue 54: at
//    most 1.5x the step without it).
// Busy-core mode (issue 18): LocalGlobal411 and BackwardEuler256/pcg-nodal also run as
// .../threads:T/busy:1 with T = 1 and 2 while a competing process spins on the last core
// (bench/busy_core.hpp), one-thread and two-thread cases in one invocation: the two-thread run
// should never be slower. threads:0 is the default thread count, on a quiet machine.
// Prints OPENBLAS_CORETYPE, OPENBLAS_NUM_THREADS, OPENBLAS_THREAD_TIMEOUT, OMP_NUM_THREADS and
// GOMP_SPINCOUNT.
//   build/bench/hooke_bench_targets --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_main.hpp"
#include "bench/busy_core.hpp"
#include "hooke/integrators/implicit_stepper.hpp"
#include "hooke/linear/conjugate_gradient.hpp"
#include "hooke/parallel/loops.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"
#include "problems/scene.hpp"

namespace {

using hooke::Clock;
using hooke::seconds_since;

std::string scene_path(const char* name) {
  return std::string(HOOKE_BENCH_SCENES_DIR) + "/" + name;
}

/// Sets the thread count of a case (state.range(0); 0 keeps the default) for its lifetime.
class CaseThreads {
 public:
  explicit CaseThreads(const benchmark::State& state) : m_previous(omp_get_max_threads()) {
    if (state.range(0) > 0) omp_set_num_threads(int(state.range(0)));
  }
  ~CaseThreads() { omp_set_num_threads(m_previous); }
  CaseThreads(const CaseThreads&) = delete;
  CaseThreads& operator=(const CaseThreads&) = delete;

 private:
  int m_previous;
};

void BM_LocalGlobal411(benchmark::State& state) {
  const CaseThreads threads(state);
  const hooke::bench::BusyCore busy(state.range(1) != 0);
  const hooke::Scene scene = hooke::load_scene(
      scene_path("target_local_global_411.toml"),
      {std::string("integrator.factor_precision=") + (state.range(2) ? "single" : "double")});
  const auto o = scene.integrator.options.as<hooke::FastMassSpringOptions>("fast-mass-spring");
  const double h = scene.time.dt;
  auto t0 = Clock::now();
  hooke::FastMassSpringStepper fms(*scene.system, o);
  const double analyze = seconds_since(t0);
  hooke::State s0 = scene.initial, s1;
  fms.step(s0, h, s1);  // warm-up: factors
  const double factor = fms.last_factor_seconds();
  std::swap(s0, s1);
  const double local0 = fms.local_seconds(), global0 = fms.global_seconds();
  const long long one0 = fms.team().repetitions_one(), all0 = fms.team().repetitions_all();
  long long iterations = 0;
  for (auto _ : state) {
    t0 = Clock::now();
    fms.step(s0, h, s1);
    state.SetIterationTime(seconds_since(t0) / o.iterations);
    iterations += o.iterations;
    std::swap(s0, s1);
  }
  const double it = double(std::max(1LL, iterations));
  state.counters["springs"] = double(scene.edges.size());
  state.counters["analyze_s"] = analyze;
  state.counters["factor_s"] = factor;
  state.counters["factor_nnz"] = fms.factor_nonzeros();
  state.counters["local_ms"] = 1e3 * (fms.local_seconds() - local0) / it;
  state.counters["global_ms"] = 1e3 * (fms.global_seconds() - global0) / it;
  // The share of the timed iterations that the team ran on all threads (solver/thread_team.hpp).
  const double one = double(fms.team().repetitions_one() - one0);
  const double all = double(fms.team().repetitions_all() - all0);
  state.counters["team_all"] = one + all > 0.0 ? all / (one + all) : 0.0;
}

void BM_BackwardEuler256(benchmark::State& state, std::string linear_solver, int steps) {
  const CaseThreads threads(state);
  const hooke::bench::BusyCore busy(state.range(1) != 0);
  const hooke::Scene scene = hooke::load_scene(scene_path("target_backward_euler_256.toml"),
                                               {"integrator.linear_solver=" + linear_solver});
  const double h = scene.time.dt;
  long long iterations = 0, taken = 0;
  double factor = 0.0, solve = 0.0, assembly = 0.0, first = 0.0, later = 0.0, setup = 0.0;
  int factorizations = 0;
  long long team_one = 0, team_all = 0;
  for (auto _ : state) {
    const auto t_setup = Clock::now();
    hooke::Simulation sim(
        *scene.system,
        hooke::make_stepper(scene.integrator.method, *scene.system, scene.integrator.options),
        scene.initial);
    setup += seconds_since(t_setup);
    const auto t0 = Clock::now();
    for (int k = 0; k < steps; ++k) {
      if (k == 1) first += seconds_since(t0);
      const hooke::StepSummary s = sim.advance(h);
      if (s.status != hooke::Status::Converged) {
        state.SkipWithError(s.message.c_str());
        return;
      }
      iterations += s.iterations;
      ++taken;
    }
    const double all = seconds_since(t0);
    later += steps > 1 ? (all - first) / (steps - 1) : 0.0;
    state.SetIterationTime(all / steps);
    const hooke::StepperStats st = sim.stepper().stats();
    factor += st.factor_seconds;
    solve += st.solve_seconds;
    assembly += st.assembly_seconds;
    factorizations += int(st.factorizations);
    const auto* implicit = dynamic_cast<const hooke::ImplicitStepper*>(&sim.stepper());
    if (const hooke::AdaptiveTeam* team = implicit ? implicit->linear_solver().team() : nullptr) {
      team_one += team->repetitions_one();
      team_all += team->repetitions_all();
    }
  }
  const double n = double(std::max(1LL, taken));
  state.counters["springs"] = double(scene.edges.size());
  state.counters["setup_s"] = setup;        // the stepper's construction: symbolic analysis
  state.counters["first_step_s"] = first;   // with the first factorization
  state.counters["later_steps_s"] = later;  // mean of the other steps
  state.counters["lin_iters"] = double(iterations) / n;
  state.counters["factorizations"] = double(factorizations) / n * steps;
  state.counters["factor_s"] = factor / n;
  state.counters["solve_s"] = solve / n;
  state.counters["assembly_s"] = assembly / n;
  // The share of the linear iterations the team ran on all threads (CG: its adaptive team).
  state.counters["team_all"] =
      team_one + team_all > 0 ? double(team_all) / double(team_one + team_all) : 0.0;
}

/// Issue 54, acceptance 4: the same target's step with cloth bending added across its interior
/// edges ([bending] model = none | dihedral | quadratic | dihedral with projection =
/// eigenvalues | shell | shell with projection = eigenvalues, D = 1e-4 N m: a light fabric), on
/// pcg-nodal over 20 steps from rest, so that the cost of the hinge elements (their Hessians, the
/// PSD projection and the denser pattern) reads against the step without them in one run.
void BM_BackwardEuler256Bending(benchmark::State& state) {
  static const char* const kModels[] = {"none",     "dihedral", "quadratic",
                                        "dihedral", "shell",    "shell"};
  const bool eigenvalues = state.range(0) == 3 || state.range(0) == 5;
  const char* model = kModels[state.range(0)];
  std::vector<std::string> sets = {"integrator.linear_solver=pcg-nodal"};
  if (state.range(0) > 0) {
    sets.push_back(std::string("bending.model=") + model);
    sets.push_back("bending.stiffness=1e-4");
  }
  if (eigenvalues) sets.push_back("bending.projection=eigenvalues");
  const hooke::Scene scene = hooke::load_scene(scene_path("target_backward_euler_256.toml"), sets);
  const double h = scene.time.dt;
  const int steps = 20;
  double assembly = 0.0, factor = 0.0, solve = 0.0;
  long long iterations = 0;
  for (auto _ : state) {
    hooke::Simulation sim(
        *scene.system,
        hooke::make_stepper(scene.integrator.method, *scene.system, scene.integrator.options),
        scene.initial);
    const auto t0 = Clock::now();
    for (int k = 0; k < steps; ++k) {
      const hooke::StepSummary s = sim.advance(h);
      if (s.status != hooke::Status::Converged) {
        state.SkipWithError(s.message.c_str());
        return;
      }
      iterations += s.iterations;
    }
    state.SetIterationTime(seconds_since(t0) / steps);
    const hooke::StepperStats st = sim.stepper().stats();
    assembly += st.assembly_seconds / steps;
    factor += st.factor_seconds / steps;
    solve += st.solve_seconds / steps;
  }
  const double runs = double(std::max<int64_t>(1, state.iterations()));
  state.counters["assembly_s"] = assembly / runs;
  state.counters["factor_s"] = factor / runs;
  state.counters["solve_s"] = solve / runs;
  state.counters["lin_iters"] = double(iterations) / (runs * steps);
  state.SetLabel(std::string(model) + (eigenvalues ? ", eigenvalues" : ""));
}

const int registered = [] {
  for (const char* v : {"OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OPENBLAS_THREAD_TIMEOUT",
                        "OMP_NUM_THREADS", "GOMP_SPINCOUNT"}) {
    const char* value = std::getenv(v);
    benchmark::AddCustomContext(v, value ? value : "(unset)");
  }
  benchmark::RegisterBenchmark("Target/LocalGlobal411/Iteration", BM_LocalGlobal411)
      ->Args({0, 0, 0})
      ->Args({1, 0, 0})
      ->Args({2, 0, 0})
      ->Args({1, 0, 1})
      ->Args({2, 0, 1})
      ->Args({1, 1, 0})
      ->Args({2, 1, 0})
      ->Args({1, 1, 1})
      ->Args({2, 1, 1})
      ->ArgNames({"threads", "busy", "single"})
      ->UseManualTime()
      ->Iterations(3)
      ->Unit(benchmark::kMillisecond);
  // Steps per run: pcg-cholmod and pcg-nodal over the scene's 50 (their factorizations are
  // amortised over the run, as a user pays them), cholmod over 3, Jacobi-PCG over 2 (seconds each).
  for (const auto& [solver, steps] : {std::pair<const char*, int>{"pcg-cholmod", 50},
                                      {"pcg-nodal", 50},
                                      {"cholmod", 3},
                                      {"pcg", 2}}) {
    auto* b = benchmark::RegisterBenchmark(
        ("Target/BackwardEuler256/Step/" + std::string(solver)).c_str(), BM_BackwardEuler256,
        std::string(solver), steps);
    b->Args({0, 0});
    if (std::string(solver) == "pcg-nodal") b->Args({1, 1})->Args({2, 1});
    b->ArgNames({"threads", "busy"})->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("Target/BackwardEuler256/Bending", BM_BackwardEuler256Bending)
      ->DenseRange(0, 5)
      ->ArgNames({"model"})
      ->UseManualTime()
      ->Iterations(1)
      ->Unit(benchmark::kMillisecond);
  return 0;
}();

}  // namespace

HOOKE_BENCHMARK_MAIN();
