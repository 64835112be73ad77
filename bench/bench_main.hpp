// main() of the benchmark binaries: Google Benchmark's BENCHMARK_MAIN, after hooke's OpenMP wait
// policy (solver/thread_policy.hpp), so that benchmarks run the way `hooke` runs.
#pragma once

#include <benchmark/benchmark.h>

#include "hooke/parallel/thread_policy.hpp"

#define HOOKE_BENCHMARK_MAIN()                                          \
  int main(int argc, char** argv) {                                     \
    hooke::adopt_thread_policy(argv);                                   \
    ::benchmark::Initialize(&argc, argv);                               \
    if (::benchmark::ReportUnrecognizedArguments(argc, argv)) return 1; \
    ::benchmark::RunSpecifiedBenchmarks();                              \
    ::benchmark::Shutdown();                                            \
    return 0;                                                           \
  }                                                                     \
  int main(int, char**)
