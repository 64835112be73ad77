// Force evaluation and Jacobian assembly (values into the fixed pattern) on cloth grids of about
// 10k, 100k and 1M springs. Counters: springs, and achieved bytes/s of the minimum traffic
// (positions and velocities read, forces written: 3 x 3n doubles; springs' index and parameter
// arrays: 2 ints + 3 doubles each).
#include <benchmark/benchmark.h>

#include "bench/bench_main.hpp"
#include "bench/cloth_fixture.hpp"

namespace {

void set_counters(benchmark::State& state, const hooke::Scene& scene, double bytes_per_iter) {
  state.counters["springs"] = double(scene.edges.size());
  state.counters["particles"] = double(scene.system->num_particles());
  state.counters["bytes/s"] =
      benchmark::Counter(bytes_per_iter, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ComputeForces(benchmark::State& state) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0));
  const auto& sys = *scene.system;
  hooke::Vec f(sys.dofs());
  for (auto _ : state) {
    sys.compute_forces(scene.initial.x, scene.initial.v, f);
    benchmark::DoNotOptimize(f.data());
  }
  set_counters(state, scene, 3.0 * 8 * double(sys.dofs()) + 32.0 * 2 * double(scene.edges.size()));
}

void BM_AssembleJacobians(benchmark::State& state) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0));
  const auto& sys = *scene.system;
  hooke::Jacobians J = sys.make_jacobians();
  for (auto _ : state) {
    sys.assemble_jacobians(scene.initial.x, scene.initial.v, J);
    benchmark::DoNotOptimize(J.K.valuePtr());
  }
  // Charged as a zero-then-add assembly: 4 blocks of 9 doubles per spring into K and D, and both
  // value arrays zeroed (hooke's assembly writes each value once: see roofline_bench.cpp).
  set_counters(state, scene, 2.0 * 8 * double(sys.dofs()) + 2.0 * 2 * 8 * double(J.K.nonZeros()));
}

}  // namespace

BENCHMARK(BM_ComputeForces)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_AssembleJacobians)
    ->Arg(10000)
    ->Arg(100000)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
HOOKE_BENCHMARK_MAIN();
