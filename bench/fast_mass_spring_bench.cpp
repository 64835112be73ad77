// The local/global solver of Liu et al. 2013 (fast-mass-spring) on the undamped benchmark cloth
// (cloth_fixture.hpp with damping = 0) of about 10k, 100k and 1M springs, h = 1/60:
//  - Setup: the one-off symbolic analysis (stepper construction) and numeric factorization of the
//    n x n matrix M/h^2 + L (counters analyze_s, factor_s, factor_nnz);
//  - Iteration: one plain local/global iteration, i.e. a local step (all spring directions and the
//    right-hand side) plus a global step (forward and back substitution with 3 right-hand sides),
//    timed over steps of 10 iterations after a warm-up step (counters local_ms, global_ms);
//  - Solve3: one CHOLMOD solve (cholmod_l_solve2) with three right-hand sides on the same factor
//    (METIS ordering, as fast-mass-spring uses), for the ratio of an iteration to it (counter
//    iter_over_solve3 on the Iteration case);
//  - Solve3Interleaved: the same solve by hooke's SupernodalSolver (what the global step runs),
//    with its largest difference from CHOLMOD's result (counter rel_diff).
// Prints OPENBLAS_CORETYPE and OPENBLAS_NUM_THREADS, which change the solve times.
//   build/bench/hooke_bench_fast_mass_spring --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <utility>

#include "bench/bench_main.hpp"
#include "bench/cloth_fixture.hpp"
#include "hooke/linear/cholmod/cholmod_solver.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"

namespace {

using hooke::Clock;
using hooke::seconds_since;

constexpr double kH = 1.0 / 60.0;

/// Seconds of one solve_columns with 3 right-hand sides per cloth size, measured by BM_Solve3 and
/// read by BM_Iteration (registered after it) for the ratio.
std::map<long long, double>& solve3_seconds() {
  static std::map<long long, double> m;
  return m;
}

void BM_Setup(benchmark::State& state) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0), "", 0.0);
  hooke::FastMassSpringOptions o;
  o.iterations = 1;
  double analyze = 0.0, factor = 0.0, nnz = 0.0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    hooke::FastMassSpringStepper fms(*scene.system, o);
    const double a = seconds_since(t0);
    hooke::State s1;
    fms.step(scene.initial, kH, s1);
    analyze = a;
    factor = fms.last_factor_seconds();
    nnz = fms.factor_nonzeros();
    state.SetIterationTime(a + factor);
  }
  state.counters["springs"] = double(scene.edges.size());
  state.counters["analyze_s"] = analyze;
  state.counters["factor_s"] = factor;
  state.counters["factor_nnz"] = nnz;
}

void BM_Solve3(benchmark::State& state) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0), "", 0.0);
  hooke::FastMassSpringStepper fms(*scene.system);
  hooke::State s1;
  fms.step(scene.initial, kH, s1);  // fills the global matrix
  hooke::CholmodOptions metis;
  metis.ordering = hooke::CholmodOrdering::Metis;  // as fast-mass-spring factors it
  hooke::CholmodSolver chol(metis);
  chol.analyze(fms.global_matrix());
  chol.factor(fms.global_matrix());
  const Eigen::Index n = fms.global_matrix().rows();
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, 3);
  Eigen::MatrixXd X(n, 3);
  chol.solve_columns(B, X);  // warm-up (workspace)
  double total = 0.0;
  long long count = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    chol.solve_columns(B, X);
    total += seconds_since(t0);
    ++count;
    benchmark::DoNotOptimize(X.data());
  }
  solve3_seconds()[state.range(0)] = total / double(count);
  state.counters["springs"] = double(scene.edges.size());
  state.counters["n"] = double(n);
}

/// The same solve through hooke's own supernodal kernel (CholmodSolver::solve_interleaved), with
/// its largest difference from CHOLMOD's result relative to the largest entry (counter rel_diff).
void BM_Solve3Interleaved(benchmark::State& state) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0), "", 0.0);
  hooke::FastMassSpringStepper fms(*scene.system);
  hooke::State s1;
  fms.step(scene.initial, kH, s1);
  hooke::CholmodOptions metis;
  metis.ordering = hooke::CholmodOrdering::Metis;
  hooke::CholmodSolver chol(metis);
  chol.analyze(fms.global_matrix());
  chol.factor(fms.global_matrix());
  const Eigen::Index n = fms.global_matrix().rows();
  using Rows3 = hooke::FastMassSpringStepper::Rows3;
  const Rows3 B = Rows3::Random(n, 3);
  Rows3 X(n, 3);
  chol.solve_interleaved(B.data(), X.data(), 3);
  Eigen::MatrixXd Bc = B, Xc(n, 3);
  chol.solve_columns(Bc, Xc);
  for (auto _ : state) {
    chol.solve_interleaved(B.data(), X.data(), 3);
    benchmark::DoNotOptimize(X.data());
  }
  state.counters["springs"] = double(scene.edges.size());
  state.counters["rel_diff"] =
      (Xc - Eigen::MatrixXd(X)).cwiseAbs().maxCoeff() / Xc.cwiseAbs().maxCoeff();
}

void BM_Iteration(benchmark::State& state) {
  const hooke::Scene scene = hooke::bench::make_cloth(state.range(0), "", 0.0);
  hooke::FastMassSpringOptions o;
  o.iterations = 10;
  hooke::FastMassSpringStepper fms(*scene.system, o);
  hooke::State s0 = scene.initial, s1;
  fms.step(s0, kH, s1);  // warm-up: factors
  s0 = s1;
  const double local0 = fms.local_seconds(), global0 = fms.global_seconds();
  long long iterations = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    fms.step(s0, kH, s1);
    state.SetIterationTime(seconds_since(t0) / o.iterations);
    iterations += o.iterations;
    std::swap(s0, s1);
  }
  const double it = double(std::max(1LL, iterations));
  const double local = (fms.local_seconds() - local0) / it,
               global = (fms.global_seconds() - global0) / it;
  state.counters["springs"] = double(scene.edges.size());
  state.counters["local_ms"] = 1e3 * local;
  state.counters["global_ms"] = 1e3 * global;
  const auto s3 = solve3_seconds().find(state.range(0));
  if (s3 != solve3_seconds().end())
    state.counters["iter_over_solve3"] = (local + global) / s3->second;
}

const int registered = [] {
  const char* core = std::getenv("OPENBLAS_CORETYPE");
  const char* threads = std::getenv("OPENBLAS_NUM_THREADS");
  benchmark::AddCustomContext("OPENBLAS_CORETYPE", core ? core : "(unset)");
  benchmark::AddCustomContext("OPENBLAS_NUM_THREADS", threads ? threads : "(unset)");
  for (long long springs : {10000LL, 100000LL, 1000000LL}) {
    const bool big = springs >= 1000000;
    auto* s = benchmark::RegisterBenchmark("LocalGlobal/Setup", BM_Setup)
                  ->Arg(springs)
                  ->UseManualTime()
                  ->Unit(benchmark::kMillisecond);
    if (big) s->Iterations(1);
    auto* v = benchmark::RegisterBenchmark("LocalGlobal/Solve3", BM_Solve3)
                  ->Arg(springs)
                  ->UseRealTime()
                  ->Unit(benchmark::kMillisecond);
    if (big) v->Iterations(10);
    auto* w = benchmark::RegisterBenchmark("LocalGlobal/Solve3Interleaved", BM_Solve3Interleaved)
                  ->Arg(springs)
                  ->UseRealTime()
                  ->Unit(benchmark::kMillisecond);
    if (big) w->Iterations(10);
    auto* i = benchmark::RegisterBenchmark("LocalGlobal/Iteration", BM_Iteration)
                  ->Arg(springs)
                  ->UseManualTime()
                  ->Unit(benchmark::kMillisecond);
    if (big) i->Iterations(3);
  }
  return 0;
}();

}  // namespace

HOOKE_BENCHMARK_MAIN();
