// One step of a 10k-spring cloth through Simulation, the loop `hooke run` and the Python module
// share: hanging_cloth_16.toml at 42 x 42 particles (10,166 springs), symplectic Euler and the
// linearised backward-Euler step (its default linear solver), with Simulation's swapped state
// buffers (hooke run, and the Python module while no numpy view of the state is alive) and with
// the stable buffers that live views need (one copy of x and v per step). bench/python_overhead.py
// runs this binary and the same steps from Python in one go and prints the ratio.
//   build/bench/hooke_bench_simulation
#include <benchmark/benchmark.h>

#include <string>

#include "bench/bench_main.hpp"
#include "hooke/registry.hpp"
#include "hooke/simulation.hpp"
#include "problems/scene.hpp"

namespace {

/// args: method index (0 symplectic-euler, 1 implicit), stable buffers (0, 1).
void BM_ClothStep(benchmark::State& state) {
  const char* method = state.range(0) == 0 ? "symplectic-euler" : "implicit";
  const hooke::Scene scene = hooke::load_scene(
      std::string(HOOKE_BENCH_SCENES_DIR) + "/hanging_cloth_16.toml",
      {"mesh.nx=42", "mesh.ny=42", std::string("integrator.method=") + method, "time.dt=5e-4"});
  hooke::Simulation sim(*scene.system,
                        hooke::make_stepper(method, *scene.system, scene.integrator.options),
                        scene.initial);
  sim.set_stable_buffers(state.range(1) != 0);
  for (int k = 0; k < 200; ++k) sim.advance(scene.time.dt);  // warm-up, as the Python loop does
  for (auto _ : state) {
    const hooke::StepSummary s = sim.advance(scene.time.dt);
    benchmark::DoNotOptimize(s.status);
  }
  state.counters["springs"] = double(scene.edges.size());
  state.SetLabel(std::string(method) + (state.range(1) ? ", stable buffers" : ", swapped buffers"));
}
BENCHMARK(BM_ClothStep)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace

HOOKE_BENCHMARK_MAIN();
