// Barrier contact's cost (issue 55, acceptance 4): a 256 x 256 cloth (65,536 particles) draped
// over a sphere at h = 10 ms (cloth_on_spinning_sphere.toml: mu 0.4, the sphere spinning at
// 180 deg/s), backward Euler by Newton on the incremental potential with the default linear
// solver. The cloth falls 2 cm onto the sphere; the measured steps start once it lies on it.
// Reports seconds per step, Newton iterations per step, active contacts and the share of the time
// in the contact terms (distances, barrier, friction, CCD), in CCD alone, in the factorizations
// and in the solves.
//   build/bench/hooke_bench_contact --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <string>

#include "bench/bench_main.hpp"
#include "hooke/registry.hpp"
#include "problems/scene.hpp"

namespace {

/// args: cloth side n (n x n particles).
void BM_DrapeOnSphere(benchmark::State& state) {
  const long long n = state.range(0);
  const hooke::Scene scene =
      hooke::load_scene(std::string(HOOKE_BENCH_SCENES_DIR) + "/cloth_on_spinning_sphere.toml",
                        {"mesh.nx=" + std::to_string(n), "mesh.ny=" + std::to_string(n)});
  auto stepper =
      hooke::make_stepper(scene.integrator.method, *scene.system, scene.integrator.options);
  const double h = scene.time.dt;
  hooke::State s = scene.initial, s1;
  auto figure = [&](const char* name) {
    for (const hooke::StepFigure& f : stepper->step_figures(s))
      if (std::string(f.name) == name) return f.value;
    return 0.0;
  };
  // Until the cloth lies on the sphere (it falls 2 cm: about 7 steps).
  for (int k = 0; k < 10 && figure("contacts") == 0.0; ++k) {
    stepper->step(s, h, s1);
    std::swap(s, s1);
  }
  const hooke::StepperStats before = stepper->stats();
  double contacts = 0.0;
  for (auto _ : state) {
    const hooke::StepSummary sum = stepper->step(s, h, s1);
    if (sum.status != hooke::Status::Converged) state.SkipWithError(sum.message.c_str());
    std::swap(s, s1);
    contacts += figure("contacts");
  }
  const hooke::StepperStats after = stepper->stats();
  const double steps = double(after.steps - before.steps);
  const double total = after.total_seconds - before.total_seconds;
  state.counters["particles"] = double(n * n);
  state.counters["s_per_step"] = total / steps;
  state.counters["newton_per_step"] = double(after.iterations - before.iterations) / steps;
  state.counters["contacts"] = contacts / steps;
  state.counters["contact_share"] = (after.contact_seconds - before.contact_seconds) / total;
  state.counters["ccd_share"] = (after.ccd_seconds - before.ccd_seconds) / total;
  state.counters["factor_share"] = (after.factor_seconds - before.factor_seconds) / total;
  state.counters["solve_share"] = (after.solve_seconds - before.solve_seconds) / total;
  state.counters["assembly_share"] = (after.assembly_seconds - before.assembly_seconds) / total;
}
BENCHMARK(BM_DrapeOnSphere)->Arg(64)->Arg(256)->Iterations(3)->Unit(benchmark::kSecond);

}  // namespace

HOOKE_BENCHMARK_MAIN();
