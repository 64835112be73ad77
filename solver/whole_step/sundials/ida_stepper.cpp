#include "hooke/whole_step/sundials/ida_stepper.hpp"

#include <ida/ida.h>
#include <ida/ida_ls.h>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "hooke/model/mass_spring_ode.hpp"
#include "hooke/whole_step/sundials/sundials_detail.hpp"

namespace hooke {

OptionError IdaOptions::validate() const {
  if (OptionError err = validate_shared("ida"); !err.ok()) return err;
  if (max_order < 1 || max_order > 5)
    return {"max_order",
            "ida: max_order = " + std::to_string(max_order) + " must be in 1..5 (BDF)"};
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
void free_ida(void* mem) { IDAFree(&mem); }

void check(int flag, const char* call) { sundials_detail::check("ida", flag, call); }
template <class P>
P check_created(P p, const char* call) {
  return sundials_detail::check_created("ida", p, call);
}

}  // namespace

struct IdaStepper::Impl : sundials_detail::StepperState {
  const MassSpringSystem& system;
  IdaOptions options;
  MassSpringOde ode;                          // consistent y' = [P v; P M^-1 f] at (re)starts
  FirstOrderMatrix jac;                       // G = dF/dy + cj dF/dy' (Kind::Dae)
  std::unique_ptr<SchurPreconditioner> prec;  // spgmr only
  Vec f;                                      // 3n force scratch of the residual
  Vec scaled;                                 // 6n scratch of the preconditioner solve
  // SUNDIALS objects, freed in reverse order: the IDA memory first, the context last.
  SunPtr<SUNContext> ctx{nullptr, free_context};
  SunPtr<N_Vector> y{nullptr, free_vector};
  SunPtr<N_Vector> yp{nullptr, free_vector};
  SunPtr<SUNMatrix> A{nullptr, free_matrix};
  SunPtr<SUNLinearSolver> ls{nullptr, free_linear_solver};
  SunPtr<void*> mem{nullptr, free_ida};

  Impl(const MassSpringSystem& sys, IdaOptions opt);
  // The integrator's part of sundials_detail::whole_step.
  void read_counters();
  Eigen::Map<Vec> y_map() { return Eigen::Map<Vec>(N_VGetArrayPointer(y.get()), 2 * n3); }
  int reinit(const State& s0);
  int set_stop_time(double t1) { return IDASetStopTime(mem.get(), t1); }
  int solve(double t1, realtype* t_reached);
  static Status classify(int flag);
  static char* flag_name(int flag) { return IDAGetReturnFlagName(flag); }
  long linearizations() const { return jac.linearizations() + (prec ? prec->linearizations() : 0); }

  /// F = [x' - P v; M v' - P f(x, v)].
  void residual(ConstRef Y, ConstRef YP, VecRef F) {
    system.compute_forces(Y.head(n3), Y.tail(n3), f);
    const Vec& P = jac.free_mask();
    F.head(n3) = YP.head(n3) - P.cwiseProduct(Y.tail(n3));
    F.tail(n3) = system.mass_diagonal().cwiseProduct(YP.tail(n3)) - P.cwiseProduct(f);
  }

  // ---- callbacks (user_data = this); no allocation; exceptions become an unrecoverable flag ----
  static int res(realtype, N_Vector yy, N_Vector ypp, N_Vector rr, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      Eigen::Map<Vec> F = view_mut(rr, 2 * m.n3);
      m.residual(view(yy, 2 * m.n3), view(ypp, 2 * m.n3), F);
      return F.allFinite() ? 0 : 1;  // recoverable: IDA retries with a smaller step
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "residual", e.what());
      return -1;
    }
  }
  static int jacobian(realtype, realtype cj, N_Vector yy, N_Vector, N_Vector, SUNMatrix J,
                      void* data, N_Vector, N_Vector, N_Vector) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> Y = view(yy, 2 * m.n3);
      m.jac.linearize(Y.head(m.n3), Y.tail(m.n3));
      sundials_detail::write_matrix(m.jac, cj, J);
      return 0;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "jacobian", e.what());
      return -1;
    }
  }
  static int jtimes_setup(realtype, N_Vector yy, N_Vector, N_Vector, realtype, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> Y = view(yy, 2 * m.n3);
      m.jac.linearize(Y.head(m.n3), Y.tail(m.n3));
      return 0;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "jtimes_setup", e.what());
      return -1;
    }
  }
  static int jtimes(realtype, N_Vector, N_Vector, N_Vector, N_Vector v, N_Vector Gv, realtype cj,
                    void* data, N_Vector, N_Vector) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      m.jac.multiply(cj, view(v, 2 * m.n3), view_mut(Gv, 2 * m.n3));
      return 0;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "jtimes", e.what());
      return -1;
    }
  }
  static int prec_setup(realtype, N_Vector yy, N_Vector, N_Vector, realtype cj, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> Y = view(yy, 2 * m.n3);
      const LinearSummary s = m.prec->setup(Y.head(m.n3), Y.tail(m.n3), 1.0 / cj, false);
      return s.status == Status::Converged ? 0 : 1;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "prec_setup", e.what());
      return -1;
    }
  }
  /// G = cj diag(I, M) (I - J / cj): z = (I - J / cj)^-1 [r_x / cj; M^-1 r_v / cj].
  static int prec_solve(realtype, N_Vector, N_Vector, N_Vector, N_Vector r, N_Vector z, realtype cj,
                        realtype, void* data) {
    Impl& m = *static_cast<Impl*>(data);
    try {
      const Eigen::Map<const Vec> R = view(r, 2 * m.n3);
      m.scaled.head(m.n3) = R.head(m.n3) / cj;
      m.scaled.tail(m.n3) = R.tail(m.n3).cwiseQuotient(m.system.mass_diagonal()) / cj;
      const LinearSummary s = m.prec->solve(m.scaled, view_mut(z, 2 * m.n3));
      return s.status == Status::Converged ? 0 : 1;
    } catch (const std::exception& e) {
      m.log.record(-1, "hooke", "prec_solve", e.what());
      return -1;
    }
  }
};

IdaStepper::Impl::Impl(const MassSpringSystem& sys, IdaOptions opt)
    : StepperState(sys),
      system(sys),
      options(std::move(opt)),
      ode(sys),
      jac(sys, FirstOrderMatrix::Kind::Dae),
      f(Vec::Zero(sys.dofs())),
      scaled(Vec::Zero(2 * sys.dofs())) {
  sundials_detail::ContextAndVector base("ida", 2 * n3);
  ctx = std::move(base.ctx);
  y = std::move(base.y);
  yp.reset(check_created(N_VNew_Serial(N_VGetLength(y.get()), ctx.get()), "N_VNew_Serial"));
  N_VConst(0.0, yp.get());
  mem.reset(check_created(IDACreate(ctx.get()), "IDACreate"));
  void* ida = mem.get();
  check(IDASetErrHandlerFn(ida, error_handler, &log), "IDASetErrHandlerFn");
  check(IDAInit(ida, res, 0.0, y.get(), yp.get()), "IDAInit");
  check(IDASetUserData(ida, this), "IDASetUserData");
  check(IDASStolerances(ida, options.rtol, options.atol), "IDASStolerances");
  check(IDASetMaxOrd(ida, options.max_order), "IDASetMaxOrd");
  check(IDASetMaxNumSteps(ida, options.max_steps), "IDASetMaxNumSteps");
  if (options.linear_solver != SundialsLinearSolver::Klu)
    prec = make_schur_preconditioner(system, options);
  auto lin = sundials_detail::make_linear_system("ida", options.linear_solver, y.get(),
                                                 jac.nonzeros(), prec != nullptr, ctx.get());
  A = std::move(lin.A);
  ls = std::move(lin.ls);
  check(IDASetLinearSolver(ida, ls.get(), A.get()), "IDASetLinearSolver");
  if (A) {
    check(IDASetJacFn(ida, jacobian), "IDASetJacFn");
  } else {
    check(IDASetJacTimes(ida, jtimes_setup, jtimes), "IDASetJacTimes");
    if (prec) check(IDASetPreconditioner(ida, prec_setup, prec_solve), "IDASetPreconditioner");
  }
}

void IdaStepper::Impl::read_counters() {
  void* ida = mem.get();
  SundialsCounters c;
  IDAGetNumSteps(ida, &c.steps);
  IDAGetNumResEvals(ida, &c.rhs_evals);
  IDAGetNumLinSolvSetups(ida, &c.linear_setups);
  IDAGetNumErrTestFails(ida, &c.error_test_fails);
  IDAGetNonlinSolvStats(ida, &c.nonlinear_iterations, &c.nonlinear_conv_fails);
  IDAGetNumLinIters(ida, &c.linear_iterations);
  counters = before;
  counters.add_totals(c);
  counters.jacobian_evals = linearizations();
  counters.restarts = restarts;
  IDAGetLastStep(ida, &counters.last_step);
  IDAGetCurrentOrder(ida, &counters.order);
}

IdaStepper::IdaStepper(const MassSpringSystem& system, IdaOptions options) {
  if (const OptionError err = options.validate(); !err.ok())
    throw std::invalid_argument(err.message);
  m_impl = std::make_unique<Impl>(system, std::move(options));
}

IdaStepper::~IdaStepper() = default;

const IdaOptions& IdaStepper::options() const { return m_impl->options; }
const IdaCounters& IdaStepper::counters() const { return m_impl->counters; }
std::string IdaStepper::counters_line() const { return m_impl->counters.line(); }

void IdaStepper::residual(ConstRef y, ConstRef yp, VecRef F) {
  const Index N = 2 * m_impl->n3;
  HOOKE_ASSERT(y.size() == N && yp.size() == N && F.size() == N, "ida residual: sizes");
  m_impl->residual(y, yp, F);
}

SparseMatrix IdaStepper::iteration_matrix(ConstRef y, double cj) {
  const Index n3 = m_impl->n3;
  HOOKE_ASSERT(y.size() == 2 * n3, "ida iteration_matrix: y has " << y.size() << " entries");
  m_impl->jac.linearize(y.head(n3), y.tail(n3));
  return m_impl->jac.to_sparse(cj);
}

int IdaStepper::Impl::reinit(const State& s0) {
  Eigen::Map<Vec> Y = y_map();
  Eigen::Map<Vec> YP(N_VGetArrayPointer(yp.get()), 2 * n3);
  Y.head(n3) = s0.x;
  Y.tail(n3) = s0.v;
  ode.rhs(s0.t, Y, YP);  // consistent: F(t0, y0, y'0) = 0 up to round-off
  return IDAReInit(mem.get(), s0.t, y.get(), yp.get());
}

int IdaStepper::Impl::solve(double t1, realtype* t_reached) {
  return IDASolve(mem.get(), t1, t_reached, y.get(), yp.get(), IDA_NORMAL);
}

Status IdaStepper::Impl::classify(int flag) {
  switch (flag) {
    case IDA_TOO_MUCH_WORK:
    case IDA_TOO_MUCH_ACC:
    case IDA_ERR_FAIL:
    case IDA_CONV_FAIL:
      return Status::NotConverged;
    case IDA_LSETUP_FAIL:
    case IDA_LSOLVE_FAIL:
      return Status::BrokeDown;
    default:
      return Status::Fatal;
  }
}

StepSummary IdaStepper::step(const State& s0, double h, State& s1) {
  return sundials_detail::whole_step(*m_impl, "ida", s0, h, s1);
}

}  // namespace hooke
