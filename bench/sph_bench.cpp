// SPH (solver/sph/): the neighbour search and a weakly compressible step per particle and per
// neighbour pair, on 1 and 2 threads, next to a STREAM-style triad measured in the same process.
//  - Triad/T: a = b + s c on 3 x 2^24 doubles (counter triad_GB/s);
//  - NeighbourSearch/N/T: one update of the lists of a 3D block of N water particles resting in a
//    tank (walls of 2 layers), counters ns_per_particle, ns_per_pair and pairs_per_particle;
//  - WcsphStep/N/T: one WCSPH step of the same (search, densities, forces, update), counters
//    ns_per_particle, ns_per_pair and particle_steps/s. The scaling exponent over N = 10^4 ..
//    10^6 is log(t_1M / t_10k) / log(100) from these rows;
//  - DamBreak2D/T: WCSPH steps of the 2D dam break with 20,000 water particles (a column a wide
//    and 2a high, a / dx = 100, c0 = 10 v_max, CFL 0.4), counter particle_steps/s: the figure to
//    set beside other SPH codes on the same case.
//   build/bench/hooke_bench_sph --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>
#include <memory>

#include "bench/bench_main.hpp"
#include "bench/triad.hpp"
#include "hooke/sph/fluid_system.hpp"
#include "hooke/sph/sampling.hpp"
#include "hooke/sph/wcsph.hpp"

namespace {

using hooke::Vec3;

int threads(benchmark::State& state, int arg) {
  const int t = int(state.range(arg));
  omp_set_num_threads(t);
  return t;
}

void BM_Triad(benchmark::State& state) { hooke::bench::run_triad(state, threads(state, 0)); }

/// Water resting in a 3D tank: a cube of about n particles at spacing 1 cm, walls of 2 layers.
hooke::FluidSystem block_3d(long long n) {
  const double dx = 0.01, side = std::round(std::cbrt(double(n))) * dx;
  hooke::FluidOptions fluid;
  fluid.dimension = 3;
  fluid.spacing = dx;
  fluid.viscosity = 1e-4;
  const auto water = hooke::sample_box(Vec3::Zero(), Vec3::Constant(side), dx, 3);
  const auto tank = hooke::sample_tank(Vec3::Zero(), Vec3(side, 1.5 * side, side), dx, 3, 2);
  return hooke::make_fluid_system(water, tank, fluid, Vec3(0, -9.81, 0));
}

void counters(benchmark::State& state, double seconds, long long calls, long long particles,
              long long pairs, int t) {
  const double per_call = seconds / double(calls);
  state.counters["particles"] = double(particles);
  state.counters["pairs_per_particle"] = double(pairs) / double(particles);
  state.counters["ns_per_particle"] = per_call / double(particles) * 1e9;
  state.counters["ns_per_pair"] = per_call / double(pairs) * 1e9;
  state.counters["particle_steps/s"] = double(particles) / per_call;
  const auto tr = hooke::bench::triad_rates().find(t);
  if (tr != hooke::bench::triad_rates().end()) state.counters["triad_GB/s"] = tr->second;
}

void BM_NeighbourSearch(benchmark::State& state) {
  const int t = threads(state, 1);
  auto scene = block_3d(state.range(0));
  const auto nf = scene.system->fluid()->num_fluid();
  hooke::NeighbourSearch search(scene.system->fluid()->support());
  search.update(scene.state.x, nf);  // warm: buffers sized
  double seconds = 0.0;
  long long calls = 0;
  for (auto _ : state) {
    const double t0 = omp_get_wtime();
    search.update(scene.state.x, nf);
    seconds += omp_get_wtime() - t0;
    ++calls;
  }
  counters(state, seconds, calls, nf, search.total_pairs(), t);
}

/// Times WCSPH steps of `stepper` from `scene`'s state, each of the CFL step (courant 0.4), after
/// a warm-up step; reports the counters with the pairs of the end state's lists.
void time_steps(benchmark::State& state, hooke::WcsphStepper& stepper, hooke::FluidSystem& scene,
                int t) {
  const auto nf = scene.system->fluid()->num_fluid();
  hooke::State next = scene.state;
  stepper.step(scene.state, stepper.cfl_step(scene.state, 0.4), next);  // warm
  double seconds = 0.0;
  long long calls = 0;
  for (auto _ : state) {
    const double h = stepper.cfl_step(scene.state, 0.4);
    const double t0 = omp_get_wtime();
    stepper.step(scene.state, h, next);
    seconds += omp_get_wtime() - t0;
    ++calls;
    std::swap(scene.state, next);
  }
  // The pairs of the fluid particles' lists (a fresh search at the end state, outside the timing).
  hooke::NeighbourSearch search(scene.system->fluid()->support());
  search.update(scene.state.x, nf);
  counters(state, seconds, calls, nf, search.total_pairs(), t);
  state.counters["t_end_s"] = scene.state.t;
}

void BM_WcsphStep(benchmark::State& state) {
  const int t = threads(state, 1);
  auto scene = block_3d(state.range(0));
  hooke::WcsphOptions options;
  options.sound_speed = 10 * std::sqrt(2 * 9.81 * 0.5);
  hooke::WcsphStepper stepper(*scene.system, options);
  time_steps(state, stepper, scene, t);
}

void BM_DamBreak2D(benchmark::State& state) {
  const int t = threads(state, 0);
  const double a = 0.25, dx = a / 100, g = 9.81;
  hooke::FluidOptions fluid;
  fluid.dimension = 2;
  fluid.spacing = dx;
  const double c0 = 10 * std::sqrt(2 * g * 2 * a);
  fluid.viscosity = 0.02 * c0 * dx / 8;  // artificial viscosity alpha = 0.02
  auto scene = hooke::make_fluid_system(
      hooke::sample_box(Vec3::Zero(), Vec3(a, 2 * a, 0), dx, 2),
      hooke::sample_tank(Vec3::Zero(), Vec3(5 * a, 2.5 * a, 0), dx, 2, 2), fluid, Vec3(0, -g, 0));
  hooke::WcsphOptions options;
  options.sound_speed = c0;
  hooke::WcsphStepper stepper(*scene.system, options);
  time_steps(state, stepper, scene, t);
}

}  // namespace

BENCHMARK(BM_Triad)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_NeighbourSearch)
    ->ArgsProduct({{10000, 100000, 1000000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_WcsphStep)
    ->ArgsProduct({{10000, 100000, 1000000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_DamBreak2D)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

HOOKE_BENCHMARK_MAIN();
