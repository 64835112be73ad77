// Vertex block descent (method "vbd") and local/global (fast-mass-spring) iterations on the 411 x
// 411 local/global target (target_local_global_411.toml: 842k springs, h = 1/60 s), on 1 and 2
// threads, with and without a busy core, next to a STREAM-style triad measured in the same
// process:
//  - Triad/T: a = b + s c on 3 x 2^24 doubles, T threads (GB/s counter triad_GB/s);
//  - VbdIteration/T/busy: one vbd iteration (a pass over the colours, a 3x3 Newton step and its
//    line search per vertex), timed over steps of 10 iterations after a warm-up step; counters
//    colours, MB (the bytes an iteration must stream at least: the vertex links once, and x, x0,
//    y read and x written), GB/s and of_triad (that rate over the triad's at T threads);
//  - LocalGlobalIteration/T/busy: one plain local/global iteration on the same scene.
// busy = 1 runs a competing process that spins on the last core for the whole case (the shared
// machine our users run on): a two-thread run should then be no slower than a one-thread run.
//   build/bench/hooke_bench_vbd --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bench/bench_main.hpp"
#include "bench/busy_core.hpp"
#include "bench/triad.hpp"
#include "hooke/registry.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"
#include "hooke/whole_step/vbd.hpp"
#include "problems/scene.hpp"

namespace {

using hooke::Clock;
using hooke::seconds_since;

std::map<int, double>& triad() { return hooke::bench::triad_rates(); }

int threads(benchmark::State& state) {
  const int t = int(state.range(0));
  omp_set_num_threads(t);
  return t;
}

const hooke::Scene& scene() {
  static const hooke::Scene s =
      hooke::load_scene(std::string(HOOKE_BENCH_SCENES_DIR) + "/target_local_global_411.toml");
  return s;
}

void BM_Triad(benchmark::State& state) { hooke::bench::run_triad(state, threads(state)); }

/// Times steps of `iterations` iterations of a stepper; returns the seconds per iteration.
template <class Stepper>
double time_iterations(benchmark::State& state, Stepper& stepper, int iterations) {
  const double h = scene().time.dt;
  hooke::State s0 = scene().initial, s1;
  stepper.step(s0, h, s1);  // warm-up (fast-mass-spring: the factorization)
  std::swap(s0, s1);
  double total = 0.0;
  long long count = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    stepper.step(s0, h, s1);
    const double per_iteration = seconds_since(t0) / iterations;
    state.SetIterationTime(per_iteration);
    total += per_iteration;
    ++count;
    std::swap(s0, s1);
  }
  return total / double(std::max(1LL, count));
}

void BM_VbdIteration(benchmark::State& state) {
  const int t = threads(state);
  hooke::VbdOptions o;
  o.iterations = 10;
  hooke::VbdStepper vbd(*scene().system, o);
  double seconds = 0.0;
  {
    hooke::bench::BusyCore busy(state.range(1) != 0);
    seconds = time_iterations(state, vbd, o.iterations);
  }
  // Links: an int and three doubles (32 bytes) per spring end; x read and written, x0 and y read.
  const double links = 2.0 * double(scene().edges.size()), dofs = double(scene().system->dofs());
  const double bytes = 32.0 * links + 4.0 * 8.0 * dofs;
  state.counters["colours"] = vbd.colours();
  state.counters["MB"] = bytes / 1e6;
  state.counters["GB/s"] =
      benchmark::Counter(bytes / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  if (triad().count(t)) {
    state.counters["triad_GB/s"] = triad()[t];
    state.counters["of_triad"] = bytes / seconds / 1e9 / triad()[t];
  }
}

void BM_LocalGlobalIteration(benchmark::State& state) {
  threads(state);
  auto o = scene().integrator.options.as<hooke::FastMassSpringOptions>("fast-mass-spring");
  o.tolerance = 0.0;
  hooke::FastMassSpringStepper fms(*scene().system, o);
  hooke::bench::BusyCore busy(state.range(1) != 0);
  time_iterations(state, fms, o.iterations);
}

}  // namespace

BENCHMARK(BM_Triad)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_VbdIteration)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "busy"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LocalGlobalIteration)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "busy"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

HOOKE_BENCHMARK_MAIN();
