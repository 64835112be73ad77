#pragma once
// Internal to the SUNDIALS backends (cvode_stepper.cpp, ida_stepper.cpp): the plumbing both share.
// Unlike sundials_common.hpp it includes SUNDIALS headers, so it is not installed.
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "hooke/whole_step/sundials_common.hpp"

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

}  // namespace hooke::sundials_detail
