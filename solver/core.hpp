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
