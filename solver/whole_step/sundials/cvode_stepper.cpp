#include "hooke/whole_step/sundials/cvode_stepper.hpp"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "hooke/model/mass_spring_ode.hpp"
#include "hooke/whole_step/sundials/sundials_detail.hpp"

namespace hooke {

OptionError CvodeOptions::validate() const {
  if (OptionError err = validate_shared("cvode"); !err.ok()) return err;
  std::ostringstream os;
  const int max_allowed = adams ? 12 : 5;
  if (max_order < 1 || max_order > max_allowed) {
    os << "cvode: max_order = " << max_order << " must be in 1.." << max_allowed << " for "
       << (adams ? "Adams" : "BDF");
    return {"max_order", os.str()};
  }
  const bool fixed_point = nonlinear_solver == CvodeNonlinearSolver::FixedPoint;
  if (fixed_point && !adams)
    return {"nonlinear_solver",
            "cvode: nonlinear_solver = 'fixed-point' needs adams = true (functional iteration on "
            "BDF cannot follow stiff springs); use 'newton'"};
  if (fixed_point && (linear_solver != SundialsLinearSolver::Klu || !preconditioner.empty())) {
    os << "cvode: linear_solver = '" << to_string(linear_solver) << "' / preconditioner = '"
       << preconditioner << "' are unused with nonlinear_solver = 'fixed-point'; leave them at "
       << "their defaults";
    return {"nonlinear_solver", os.str()};
  }
  return {};
}

namespace {

using sundials_detail::error_handler;
using sundials_detail::free_context;
using sundials_detail::free_linear_solver;
using sundials_detail::free_matrix;
using sundials_detail::free_vector;
using sundials_detail::view;
using sundials_detail::view_mut;
void free_nonlinear_solver(SUNNonlinearSolver s) { SUNNonlinSolFree(s); }
void free_cvode(void* mem) { CVodeFree(&mem); }

void check(int flag, const char* call) { sundials_detail::check("cvode", flag, call); }
template <class P>
P check_created(P p, const char* call) {
  return sundials_detail::check_created("cvode", p, call);
}

}  // namespace

struct CvodeStepper::Impl : sundials_detail::StepperState {
  const MassSpringSystem& system;
  CvodeOptions options;
  MassSpringOde ode;     // f(y) = [P v; P M^-1 f(x, v)], shared with the explicit steppers
  FirstOrderMatrix jac;  // J = df/dy (Kind::Ode)
  std::unique_ptr<SchurPreconditioner> prec;  // spgmr only
  // SUNDIALS objects, freed in reverse order: the CVODE memory first, the context last.
  SunPtr<SUNContext> ctx{nullptr, free_context};
  SunPtr<N_Vector> y{nullptr, free_vector};
  SunPtr<SUNMatrix> A{nullptr, free_matrix};
  SunPtr<SUNLinearSolver> ls{nullptr, free_linear_solver};
  SunPtr<SUNNonlinearSolver> nls{nullptr, free_nonlinear_solver};
  SunPtr<void*> mem{nullptr, free_cvode};

  Impl(const MassSpringSystem& sys, CvodeOptions opt);
  Eigen::Map<Vec> y_map() { return Eigen::Map<Vec>(N_VGetArrayPointer(y.get()), 2 * n3); }
  // The integrator's part of sundials_detail::whole_step.
  void read_counters();
  int reinit(const State& s0);
  int set_stop_time(double t1) { return CVodeSetStopTime(mem.get(), t1); }
  int solve(double t1, realtype* t_reached);
  static Status classify(int flag);
  static char* flag_name(int flag) { return CVodeGetReturnFlagName(flag); }
  long linearizations() const { return jac.linearizations() + (prec ? prec->linearizations() : 0); }

  // ---- callbacks (user_data = this); no allocation; exceptions become an unrecoverable flag ----
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      Eigen::Map<Vec> F = view_mut(ydot, 2 * m.n3);
      m.ode.rhs(t, view(y, 2 * m.n3), F);
      return F.allFinite() ? 0 : 1;  // recoverable: CVODE retries with a smaller step
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "rhs", e.what());
      return -1;
    }
  }
  static int jacobian(realtype, N_Vector y, N_Vector, SUNMatrix J, void* data, N_Vector, N_Vector,
                      N_Vector) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> Y = view(y, 2 * m.n3);
      m.jac.linearize(Y.head(m.n3), Y.tail(m.n3));
      sundials_detail::write_matrix(m.jac, 0.0, J);
      return 0;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "jacobian", e.what());
      return -1;
    }
  }
  static int jtimes_setup(realtype, N_Vector y, N_Vector, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> Y = view(y, 2 * m.n3);
      m.jac.linearize(Y.head(m.n3), Y.tail(m.n3));
      return 0;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "jtimes_setup", e.what());
      return -1;
    }
  }
  static int jtimes(N_Vector v, N_Vector Jv, realtype, N_Vector, N_Vector, void* data, N_Vector) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      m.jac.multiply(0.0, view(v, 2 * m.n3), view_mut(Jv, 2 * m.n3));
      return 0;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "jtimes", e.what());
      return -1;
    }
  }
  static int prec_setup(realtype, N_Vector y, N_Vector, booleantype jok, booleantype* jcur,
                        realtype gamma, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> Y = view(y, 2 * m.n3);
      const LinearSummary s = m.prec->setup(Y.head(m.n3), Y.tail(m.n3), gamma, jok != SUNFALSE);
      *jcur = jok ? SUNFALSE : SUNTRUE;
      return s.status == Status::Converged ? 0 : 1;  // recoverable: smaller step, new setup
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "prec_setup", e.what());
      return -1;
    }
  }
  static int prec_solve(realtype, N_Vector, N_Vector, N_Vector r, N_Vector z, realtype, realtype,
                        int, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const LinearSummary s = m.prec->solve(view(r, 2 * m.n3), view_mut(z, 2 * m.n3));
      return s.status == Status::Converged ? 0 : 1;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "prec_solve", e.what());
      return -1;
    }
  }
};

CvodeStepper::Impl::Impl(const MassSpringSystem& sys, CvodeOptions opt)
    : StepperState(sys),
      system(sys),
      options(std::move(opt)),
      ode(sys),
      jac(sys, FirstOrderMatrix::Kind::Ode) {
  sundials_detail::ContextAndVector base("cvode", 2 * n3);
  ctx = std::move(base.ctx);
  y = std::move(base.y);
  mem.reset(
      check_created(CVodeCreate(options.adams ? CV_ADAMS : CV_BDF, ctx.get()), "CVodeCreate"));
  void* cv = mem.get();
  check(CVodeSetErrHandlerFn(cv, error_handler, &log), "CVodeSetErrHandlerFn");
  check(CVodeInit(cv, rhs, 0.0, y.get()), "CVodeInit");
  check(CVodeSetUserData(cv, this), "CVodeSetUserData");
  check(CVodeSStolerances(cv, options.rtol, options.atol), "CVodeSStolerances");
  check(CVodeSetMaxOrd(cv, options.max_order), "CVodeSetMaxOrd");
  check(CVodeSetMaxNumSteps(cv, options.max_steps), "CVodeSetMaxNumSteps");
  if (options.nonlinear_solver == CvodeNonlinearSolver::FixedPoint) {
    nls.reset(
        check_created(SUNNonlinSol_FixedPoint(y.get(), 0, ctx.get()), "SUNNonlinSol_FixedPoint"));
    check(CVodeSetNonlinearSolver(cv, nls.get()), "CVodeSetNonlinearSolver");
  } else {
    if (options.linear_solver != SundialsLinearSolver::Klu)
      prec = make_schur_preconditioner(system, options);
    auto lin = sundials_detail::make_linear_system("cvode", options.linear_solver, y.get(),
                                                   jac.nonzeros(), prec != nullptr, ctx.get());
    A = std::move(lin.A);
    ls = std::move(lin.ls);
    check(CVodeSetLinearSolver(cv, ls.get(), A.get()), "CVodeSetLinearSolver");
    if (A) {
      check(CVodeSetJacFn(cv, jacobian), "CVodeSetJacFn");
    } else {
      check(CVodeSetJacTimes(cv, jtimes_setup, jtimes), "CVodeSetJacTimes");
      if (prec) check(CVodeSetPreconditioner(cv, prec_setup, prec_solve), "CVodeSetPreconditioner");
    }
  }
}

void CvodeStepper::Impl::read_counters() {
  void* cv = mem.get();
  SundialsCounters c;
  CVodeGetNumSteps(cv, &c.steps);
  CVodeGetNumRhsEvals(cv, &c.rhs_evals);
  CVodeGetNumLinSolvSetups(cv, &c.linear_setups);
  CVodeGetNumErrTestFails(cv, &c.error_test_fails);
  CVodeGetNonlinSolvStats(cv, &c.nonlinear_iterations, &c.nonlinear_conv_fails);
  if (ls) CVodeGetNumLinIters(cv, &c.linear_iterations);
  counters = before;
  counters.add_totals(c);
  counters.jacobian_evals = linearizations();
  counters.restarts = restarts;
  CVodeGetLastStep(cv, &counters.last_step);
  CVodeGetCurrentOrder(cv, &counters.order);
}

CvodeStepper::CvodeStepper(const MassSpringSystem& system, CvodeOptions options) {
  if (const OptionError err = options.validate(); !err.ok())
    throw std::invalid_argument(err.message);
  m_impl = std::make_unique<Impl>(system, std::move(options));
}

CvodeStepper::~CvodeStepper() = default;

const CvodeOptions& CvodeStepper::options() const { return m_impl->options; }
const CvodeCounters& CvodeStepper::counters() const { return m_impl->counters; }
std::string CvodeStepper::counters_line() const { return m_impl->counters.line(); }

void CvodeStepper::rhs(ConstRef y, VecRef ydot) {
  HOOKE_ASSERT(y.size() == 2 * m_impl->n3 && ydot.size() == y.size(), "cvode rhs: sizes");
  m_impl->ode.rhs(0.0, y, ydot);
}

SparseMatrix CvodeStepper::jacobian(ConstRef y) {
  const Index n3 = m_impl->n3;
  HOOKE_ASSERT(y.size() == 2 * n3,
               "cvode jacobian: y has " << y.size() << " entries, not " << 2 * n3);
  m_impl->jac.linearize(y.head(n3), y.tail(n3));
  return m_impl->jac.to_sparse(0.0);
}

int CvodeStepper::Impl::reinit(const State& s0) {
  Eigen::Map<Vec> Y = y_map();
  Y.head(n3) = s0.x;
  Y.tail(n3) = s0.v;
  return CVodeReInit(mem.get(), s0.t, y.get());
}

int CvodeStepper::Impl::solve(double t1, realtype* t_reached) {
  return CVode(mem.get(), t1, y.get(), t_reached, CV_NORMAL);
}

Status CvodeStepper::Impl::classify(int flag) {
  switch (flag) {
    case CV_TOO_MUCH_WORK:
    case CV_TOO_MUCH_ACC:
    case CV_ERR_FAILURE:
    case CV_CONV_FAILURE:
      return Status::NotConverged;
    case CV_LSETUP_FAIL:
    case CV_LSOLVE_FAIL:
      return Status::BrokeDown;
    default:
      return Status::Fatal;
  }
}

StepSummary CvodeStepper::step(const State& s0, double h, State& s1) {
  return sundials_detail::whole_step(*m_impl, "cvode", s0, h, s1);
}

}  // namespace hooke
