#pragma once
// Internal to the SUNDIALS backends (cvode_stepper.cpp, ida_stepper.cpp): the plumbing both share.
// Unlike sundials_common.hpp it includes SUNDIALS headers, so it is not installed.
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cstdint>
#include <cstdlib>
#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "hooke/whole_step/sundials/sundials_common.hpp"

namespace hooke::sundials_detail {

static_assert(std::is_same_v<sunindextype, std::int64_t>,
              "FirstOrderMatrix stores 64-bit indices: SUNDIALS must be built with them");
static_assert(std::is_same_v<realtype, double>, "SUNDIALS must be built in double precision");

inline void free_context(SUNContext c) { SUNContext_Free(&c); }
inline void free_vector(N_Vector v) { N_VDestroy(v); }
inline void free_matrix(SUNMatrix A) { SUNMatDestroy(A); }
inline void free_linear_solver(SUNLinearSolver s) { SUNLinSolFree(s); }

/// Throws std::runtime_error("<module>: <call> failed with flag F") for a negative SUNDIALS flag.
inline void check(const char* module, int flag, const char* call) {
  if (flag < 0)
    throw std::runtime_error(std::string(module) + ": " + call + " failed with flag " +
                             std::to_string(flag));
}

/// Returns p, or throws std::runtime_error("<module>: <call> returned NULL").
template <class P>
P check_created(const char* module, P p, const char* call) {
  if (p == nullptr) throw std::runtime_error(std::string(module) + ": " + call + " returned NULL");
  return p;
}

/// Views of a serial N_Vector's data (no copy).
inline Eigen::Map<const Vec> view(N_Vector v, Index size) {
  return Eigen::Map<const Vec>(N_VGetArrayPointer(v), size);
}
inline Eigen::Map<Vec> view_mut(N_Vector v, Index size) {
  return Eigen::Map<Vec>(N_VGetArrayPointer(v), size);
}

/// Writes m's current values, as dF/dy + c dF/dy' (c = 0 for CVODE's J), into the SUNDIALS CSC
/// matrix J. SUNDIALS zeroes the whole structure (SUNMatZero) before calling the Jacobian
/// function, so the pattern is copied in each time.
inline void write_matrix(const FirstOrderMatrix& m, double c, SUNMatrix J) {
  HOOKE_ASSERT(SUNSparseMatrix_NNZ(J) >= m.nonzeros() && SUNSparseMatrix_Columns(J) == m.size(),
               "SUNDIALS matrix too small for the first-order pattern");
  m.write(c, SUNSparseMatrix_IndexPointers(J), SUNSparseMatrix_IndexValues(J),
          SUNSparseMatrix_Data(J));
}

/// The context and state vector every integrator needs, created in that order.
struct ContextAndVector {
  SunPtr<SUNContext> ctx{nullptr, free_context};
  SunPtr<N_Vector> y{nullptr, free_vector};
  ContextAndVector(const char* module, Index size) {
    SUNContext c = nullptr;
    check(module, SUNContext_Create(nullptr, &c), "SUNContext_Create");
    ctx.reset(check_created(module, c, "SUNContext_Create"));
    y.reset(check_created(module, N_VNew_Serial(sunindextype(size), ctx.get()), "N_VNew_Serial"));
    N_VConst(0.0, y.get());
  }
};

/// The Newton linear solver of either integrator: KLU on a sparse matrix with the first-order
/// pattern's size, or matrix-free SPGMR, left-preconditioned when a Schur preconditioner exists.
/// The caller attaches it (CVodeSetLinearSolver / IDASetLinearSolver with A, which is null for
/// SPGMR) and sets its Jacobian or Jv and preconditioner callbacks.
struct LinearSystem {
  SunPtr<SUNMatrix> A{nullptr, free_matrix};
  SunPtr<SUNLinearSolver> ls{nullptr, free_linear_solver};
  bool klu() const { return A != nullptr; }
};
inline LinearSystem make_linear_system(const char* module, SundialsLinearSolver linear_solver,
                                       N_Vector y, Index nonzeros, bool preconditioned,
                                       SUNContext ctx) {
  LinearSystem s;
  if (linear_solver == SundialsLinearSolver::Klu) {
    const sunindextype N = N_VGetLength(y);
    s.A.reset(check_created(module, SUNSparseMatrix(N, N, sunindextype(nonzeros), CSC_MAT, ctx),
                            "SUNSparseMatrix"));
    s.ls.reset(check_created(module, SUNLinSol_KLU(y, s.A.get(), ctx), "SUNLinSol_KLU"));
  } else {
    s.ls.reset(check_created(
        module, SUNLinSol_SPGMR(y, preconditioned ? SUN_PREC_LEFT : SUN_PREC_NONE, 0, ctx),
        "SUNLinSol_SPGMR"));
  }
  return s;
}

inline void error_handler(int code, const char* module, const char* function, char* msg,
                          void* data) {
  static_cast<SundialsErrorLog*>(data)->record(code, module, function, msg);
}

/// What CvodeStepper::Impl and IdaStepper::Impl share beyond their SUNDIALS objects: the state
/// the last step returned (CVODE and IDA continue their history only from exactly that state), the
/// restart flag and count, the counters and the error log.
struct StepperState {
  explicit StepperState(const MassSpringSystem& sys) : n3(sys.dofs()), last(sys.num_particles()) {}
  Index n3;
  State last;           // the state step() returned last
  bool restart = true;  // re-initialise at the next step whatever s0 is
  long restarts = 0;
  SundialsCounters before;  // totals of the runs before the current (re)initialisation
  SundialsCounters counters;
  SundialsErrorLog log;
};

/// One whole step of CVODE or IDA from s0 to s0.t + h in NORMAL mode with the stop time at t1,
/// with the checks, restarts, counters and outcome mapping both share. Impl derives from
/// StepperState and provides, for its integrator:
///   int reinit(const State& s0)          loads s0 into y (and y') and re-initialises; a flag
///   int set_stop_time(double t1)         ...SetStopTime
///   int solve(double t1, realtype* t)   CVode / IDASolve in NORMAL mode; a flag
///   void read_counters()                 counters = before + the integrator's own
///   Status classify(int flag)            NotConverged / BrokeDown / Fatal for a negative flag
///   char* flag_name(int flag)            ...GetReturnFlagName (malloc'ed)
///   Eigen::Map<Vec> y_map()              y = [x; v]
/// `module` ("cvode", "ida") starts every message.
template <class Impl>
StepSummary whole_step(Impl& m, const char* module, const State& s0, double h, State& s1) {
  const Index n3 = m.n3;
  HOOKE_ASSERT(s0.x.size() == n3 && s0.v.size() == n3,
               module << ": s0 has " << s0.x.size() << " positions for " << n3 << " dofs");
  HOOKE_ASSERT(&s0 != &s1, module << ": s1 may not alias s0");
  StepSummary out;
  const double t1 = s0.t + h;
  auto fatal = [&](const std::string& message) {
    out.status = Status::Fatal;
    out.message = std::string(module) + ": " + message;
    return out;
  };
  if (!(h > 0.0) || !std::isfinite(h) || !std::isfinite(s0.t) || !(t1 > s0.t)) {
    std::ostringstream os;
    os << std::setprecision(10) << "cannot step from t = " << s0.t << " by h = " << h
       << ": h must be positive, finite and above the round-off of t";
    return fatal(os.str());
  }
  if (!s0.is_finite()) return fatal("the start state is not finite");
  // Continue the integrator's history only from exactly the state it returned last.
  if (m.restart || s0.t != m.last.t || s0.x != m.last.x || s0.v != m.last.v) {
    m.before = m.counters;
    if (const int flag = m.reinit(s0); flag < 0)
      return fatal("re-initialisation failed with flag " + std::to_string(flag));
    ++m.restarts;
    m.restart = false;
  }
  m.log.clear();
  if (m.set_stop_time(t1) < 0) {
    m.restart = true;
    return fatal(std::string("setting the stop time failed: ") + m.log.text);
  }
  const long newton0 = m.counters.nonlinear_iterations;
  const long linear0 = m.counters.linear_iterations;
  realtype t_reached = s0.t;
  const int flag = m.solve(t1, &t_reached);
  m.read_counters();
  out.newton_iterations = int(m.counters.nonlinear_iterations - newton0);
  out.iterations = int(m.counters.linear_iterations - linear0);

  const Eigen::Map<Vec> Y = m.y_map();
  s1.x = Y.head(n3);
  s1.v = Y.tail(n3);
  s1.t = flag >= 0 ? t1 : t_reached;
  m.last.x = s1.x;
  m.last.v = s1.v;
  m.last.t = s1.t;
  if (flag >= 0 && s1.is_finite()) return out;  // SUCCESS or TSTOP_RETURN at t1

  m.restart = true;
  if (flag >= 0)
    return fatal("the state became non-finite at t = " + std::to_string(t1) + "; " +
                 m.counters.line());
  out.status = m.classify(flag);
  char* name = m.flag_name(flag);  // malloc'ed by SUNDIALS
  std::ostringstream os;
  os << std::setprecision(10) << module << ": " << (name ? name : "unknown flag") << " (" << flag
     << ") at t = " << t_reached << " on the step from t = " << s0.t << " to " << t1;
  std::free(name);
  if (m.log.text[0]) os << ": " << m.log.text;
  os << "; " << m.counters.line();
  out.message = os.str();
  return out;
}

}  // namespace hooke::sundials_detail
