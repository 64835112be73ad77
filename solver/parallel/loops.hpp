#pragma once
/// The OpenMP loops of hooke: whether a loop runs in parallel, and the loop shapes whose results
/// do not depend on the thread count (per item, per piece of a sparse product, per block of a
/// vector).
#include <Eigen/Core>
#include <algorithm>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace hooke {

/// The threads a parallel region started now would have (1 without OpenMP).
inline int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}
/// The calling thread's number in its OpenMP team (0 outside a parallel region).
inline int thread_number() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/// True if a loop over `work` items should run in an OpenMP parallel region: large enough
/// (work >= threshold) to pay for the threads, and more than one thread available. Loops branch on
/// this instead of using an OpenMP if() clause, because a region that runs on one thread still
/// makes libgomp allocate and free a thread team, which the step loop must not do.
inline bool run_parallel(long long work, long long threshold) {
#ifdef _OPENMP
  return work >= threshold && omp_get_max_threads() > 1;
#else
  (void)work;
  (void)threshold;
  return false;
#endif
}

/// Calls body(i) for i in [0, n): in an OpenMP loop when run_parallel(n, threshold), else
/// serially. For per-particle loops whose iterations write disjoint entries, so the result does
/// not depend on the thread count. The loop is cut into 64 chunks handed out one at a time: with a
/// static split, a thread whose core another process holds made every such loop wait for its
/// half.
template <typename Body>
inline void parallel_for(long long n, long long threshold, Body&& body) {
  if (run_parallel(n, threshold)) {
    const long long chunk = std::max(1LL, (n + 63) / 64);
#pragma omp parallel for schedule(dynamic, chunk)
    for (long long i = 0; i < n; ++i) body(i);
  } else {
    for (long long i = 0; i < n; ++i) body(i);
  }
}

/// Calls body(begin, end) over [0, n) cut into 64 pieces handed out one at a time to the threads
/// when run_parallel(work, threshold), else once for all of [0, n). For loops whose cost is not n
/// (the rows of a sparse product: work is its stored entries) and whose pieces write disjoint
/// entries, each computed the same way by whichever thread: the result does not depend on the
/// thread count, and a thread whose core another process shares takes fewer pieces.
template <typename Body>
inline void parallel_pieces(long long n, long long work, long long threshold, Body&& body) {
  if (run_parallel(work, threshold)) {
#pragma omp parallel for schedule(dynamic, 1)
    for (long long p = 0; p < 64; ++p) body(n * p / 64, n * (p + 1) / 64);
  } else {
    body(0LL, n);
  }
}

/// Calls body(begin, end) over [0, n) cut into blocks of kRangeBlock entries: blocks handed out
/// one at a time to the threads when run_parallel(n, kRangeThreshold), else one call for all of
/// [0, n). For element-wise vector work (copies, axpys, scalings of state vectors): each entry is
/// computed the same way whoever computes it, so the result does not depend on the thread count,
/// and a thread whose core another process shares takes fewer blocks.
inline constexpr long long kRangeBlock = 1 << 15, kRangeThreshold = 1 << 17;
template <typename Body>
inline void parallel_ranges(long long n, Body&& body) {
  if (run_parallel(n, kRangeThreshold)) {
    const long long blocks = (n + kRangeBlock - 1) / kRangeBlock;
#pragma omp parallel for schedule(dynamic, 1)
    for (long long b = 0; b < blocks; ++b)
      body(b * kRangeBlock, std::min(n, (b + 1) * kRangeBlock));
  } else {
    body(0LL, n);
  }
}

/// dst = src (resized), over blocks in parallel for long vectors.
inline void parallel_copy(const Eigen::Ref<const Eigen::VectorXd>& src, Eigen::VectorXd& dst) {
  dst.resize(src.size());
  parallel_ranges(src.size(), [&](long long b, long long e) {
    std::copy(src.data() + b, src.data() + e, dst.data() + b);
  });
}

/// True if every entry of a is finite; over blocks in parallel for long vectors.
inline bool all_finite(const Eigen::Ref<const Eigen::VectorXd>& a) {
  const long long n = a.size();
  if (!run_parallel(n, kRangeThreshold)) return a.allFinite();
  const long long blocks = (n + kRangeBlock - 1) / kRangeBlock;
  bool finite = true;
#pragma omp parallel for schedule(dynamic, 1) reduction(&& : finite)
  for (long long b = 0; b < blocks; ++b) {
    const long long b0 = b * kRangeBlock;
    finite = finite && a.segment(b0, std::min(n, b0 + kRangeBlock) - b0).allFinite();
  }
  return finite;
}

}  // namespace hooke
