#pragma once
/// Project-wide aliases, the internal assertion macro and the outcome status of every solve.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <sstream>
#include <stdexcept>
#include <string>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace hooke {

using Index = Eigen::Index;
using Vec = Eigen::VectorXd;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
/// Read-only vector argument (any contiguous double vector, including segments of a larger one).
using ConstRef = Eigen::Ref<const Eigen::VectorXd>;
/// Writable vector argument; the caller owns the storage and its size is fixed.
using VecRef = Eigen::Ref<Eigen::VectorXd>;
/// Compressed-column sparse matrix used for K = df/dx and D = df/dv (3n x 3n).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// The clock of every timing in hooke (wall time, monotonic).
using Clock = std::chrono::steady_clock;
/// Seconds of wall time since t0.
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Thrown by HOOKE_ASSERT: a broken invariant or a size mismatch, i.e. a programmer error.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

/// Thrown when a method or backend name is not in its registry table; the message lists the
/// available names, or names the build option / Debian package of a backend this build lacks.
class UnknownName : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Thrown when a stepper cannot be set up for a system, e.g. because the sparse factorization it
/// needs would exceed the memory budget (memory_budget()); the message says why, with the numbers.
/// Front ends report it as an input error of the scene's integrator settings.
class SetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Outcome of a numerical solve (linear solve, nonlinear step, whole step). Recoverable cases
/// (NotConverged) let the caller shrink h or report; BrokeDown means the method met something it
/// cannot handle (e.g. CG on an indefinite matrix); Fatal means the result must not be used.
enum class Status { Converged, NotConverged, BrokeDown, Fatal };

/// Lowercase name of a status for logs and messages.
inline const char* to_string(Status s) {
  switch (s) {
    case Status::Converged:
      return "converged";
    case Status::NotConverged:
      return "not-converged";
    case Status::BrokeDown:
      return "broke-down";
    case Status::Fatal:
      return "fatal";
  }
  return "unknown";
}

/// The memory budget (bytes) that solvers check before a large allocation they can estimate in
/// advance, such as a sparse Cholesky factor after its symbolic analysis; 0 (the default) means
/// no budget. The scene loader sets it to its own budget (problems/scene.hpp), so a scene whose
/// factorization would not fit is refused with the estimate instead of being killed.
inline double& memory_budget_slot() {
  static double budget = 0.0;
  return budget;
}
inline double memory_budget() { return memory_budget_slot(); }
inline void set_memory_budget(double bytes) { memory_budget_slot() = bytes; }

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

/// Checks a programmer-level precondition (sizes, invariants) and throws hooke::InternalError with
/// the condition, location and message. Always active: only used at API boundaries, never per
/// spring, so its cost is negligible.
#define HOOKE_ASSERT(cond, msg)                                      \
  do {                                                               \
    if (!(cond)) {                                                   \
      std::ostringstream hooke_assert_os_;                           \
      hooke_assert_os_ << __FILE__ << ":" << __LINE__                \
                       << ": assertion '" #cond "' failed: " << msg; \
      throw ::hooke::InternalError(hooke_assert_os_.str());          \
    }                                                                \
  } while (false)
