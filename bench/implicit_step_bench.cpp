// One implicit step (beta = 1, one Newton step: the linearised backward Euler of Baraff and Witkin)
// per linear backend on cloth grids of about 10k, 100k and 1M springs, h = 1/60, linear
// tolerance 1e-6 relative, iterative backends warm-started from the previous step. Iteration caps:
// 20000 for the CG family, 2000 for the stationary methods (Jacobi, Gauss-Seidel), which need far
// more on these matrices; a step that hits its cap is counted in not_conv and its residual shown.
// Each benchmark first takes warm-up steps from rest (3, or 1 at 1M springs) so the cloth moves
// and warm starts mean something, then times further steps of the same run. Counters per step:
// linear iterations, final relative residual, the backend's analyze (one-off), factor and solve
// seconds, and force-and-Jacobian assembly seconds.
//   build/bench/hooke_bench_implicit --benchmark_counters_tabular=true
//   build/bench/hooke_bench_implicit --benchmark_filter='cholmod/1000000'
#include <benchmark/benchmark.h>

#include <memory>

#include "bench/bench_main.hpp"
#include "bench/cloth_fixture.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/simulation.hpp"

namespace {

void BM_ImplicitStep(benchmark::State& state, std::string backend) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0));
  hooke::ImplicitOptions options;
  options.linear_solver = backend;
  options.beta = 1.0;
  options.linear_tolerance = 1e-6;
  const bool stationary = backend == "jacobi" || backend.find("gauss-seidel") != std::string::npos;
  options.max_linear_iterations = stationary ? 2000 : 20000;
  hooke::Simulation sim(*scene.system, hooke::make_stepper("implicit", *scene.system, options),
                        scene.initial);
  const double h = 1.0 / 60.0;
  const int warmup = state.range(0) >= 1000000 ? 1 : 3;
  for (int k = 0; k < warmup; ++k) sim.advance(h);
  const hooke::StepperStats before = sim.stepper().stats();
  long long steps = 0, iterations = 0, not_converged = 0;
  double residual = 0.0;
  for (auto _ : state) {
    const hooke::StepSummary s = sim.advance(h);
    if (s.status == hooke::Status::BrokeDown || s.status == hooke::Status::Fatal) {
      state.SkipWithError(s.message.c_str());
      break;
    }
    not_converged += s.status == hooke::Status::NotConverged;
    iterations += s.iterations;
    residual = s.residual;
    ++steps;
  }
  const hooke::StepperStats after = sim.stepper().stats();
  const double n = double(std::max(1LL, steps));
  state.counters["springs"] = double(scene.edges.size());
  state.counters["lin_iters"] = double(iterations) / n;
  state.counters["not_conv"] = double(not_converged);
  state.counters["residual"] = residual;
  state.counters["analyze_s"] = after.analyze_seconds;
  state.counters["factor_s"] = (after.factor_seconds - before.factor_seconds) / n;
  state.counters["solve_s"] = (after.solve_seconds - before.solve_seconds) / n;
  state.counters["assembly_s"] = (after.assembly_seconds - before.assembly_seconds) / n;
}

// One registration per backend and size; the 1M cases run a single step (they take seconds).
const int registered = [] {
  for (const auto& info : hooke::linear_solvers()) {
    const std::string name = info.name;
    for (long long springs : {10000LL, 100000LL, 1000000LL}) {
      auto* b =
          benchmark::RegisterBenchmark(("ImplicitStep/" + name).c_str(), BM_ImplicitStep, name)
              ->Arg(springs)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
      if (springs >= 1000000) b->Iterations(1);
    }
  }
  return 0;
}();

}  // namespace

HOOKE_BENCHMARK_MAIN();
