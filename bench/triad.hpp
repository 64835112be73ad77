// The STREAM-style triad a = b + s c on 3 x 2^24 doubles (384 MB; 24 bytes and 2 flops per
// element), measured in the same process as the kernels it is set beside: the benchmarks report
// their bandwidth as a fraction of it.
#pragma once

#include <benchmark/benchmark.h>
#include <omp.h>

#include <map>
#include <vector>

namespace hooke::bench {

/// Triad GB/s per thread count, filled by run_triad (register the triad cases first).
inline std::map<int, double>& triad_rates() {
  static std::map<int, double> rates;
  return rates;
}

/// One triad pass a = b + 3 c over the arrays' n entries, on the current OpenMP thread count.
inline void triad_pass(std::vector<double>& a, const std::vector<double>& b,
                       const std::vector<double>& c) {
  const long long n = static_cast<long long>(a.size());
#pragma omp parallel for schedule(static)
  for (long long i = 0; i < n; ++i) a[size_t(i)] = b[size_t(i)] + 3.0 * c[size_t(i)];
  benchmark::DoNotOptimize(a.data());
}

/// Times the triad on the current OpenMP thread count in `state`'s loop, stores its GB/s under
/// `threads` and reports it as the counter triad_GB/s.
inline void run_triad(benchmark::State& state, int threads) {
  const long long n = 1LL << 24;
  std::vector<double> a(size_t(n), 0.0), b(size_t(n), 1.0), c(size_t(n), 2.0);
  double seconds = 0.0;
  long long calls = 0;
  for (auto _ : state) {
    const double t0 = omp_get_wtime();
    triad_pass(a, b, c);
    seconds += omp_get_wtime() - t0;
    ++calls;
  }
  triad_rates()[threads] = 24.0 * double(n) * double(calls) / seconds / 1e9;
  state.counters["triad_GB/s"] = triad_rates()[threads];
}

/// The triad's GB/s on `threads` threads over `calls` calls, outside any benchmark's loop: for a
/// kernel's fraction of the bandwidth the machine gave just before and after it (the other tenant
/// of these machines moves the triad between 27 and 41 GB/s on one thread within minutes). Its
/// three arrays are allocated and first touched on the first call, kept for the process.
inline double measure_triad(int threads, int calls) {
  const long long n = 1LL << 24;
  static std::vector<double> a, b, c;
  if (a.empty()) {
    a.assign(size_t(n), 0.0);
    b.assign(size_t(n), 1.0);
    c.assign(size_t(n), 2.0);
  }
  const int previous = omp_get_max_threads();
  omp_set_num_threads(threads);
  const double t0 = omp_get_wtime();
  for (int k = 0; k < calls; ++k) triad_pass(a, b, c);
  const double seconds = omp_get_wtime() - t0;
  omp_set_num_threads(previous);
  return 24.0 * double(n) * double(calls) / seconds / 1e9;
}

}  // namespace hooke::bench
