#include "hooke/whole_step/ida_stepper.hpp"

#include <ida/ida.h>
#include <ida/ida_ls.h>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "hooke/whole_step/sundials_detail.hpp"
#include "hooke/model/mass_spring_ode.hpp"

namespace hooke {

OptionError IdaOptions::validate() const {
  if (OptionError err = validate_shared("ida"); !err.ok()) return err;
  if (max_order < 1 || max_order > 5)
    return {"max_order", "ida: max_order = " + std::to_string(max_order) + " must be in 1..5 (BDF)"};
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

struct IdaStepper::Impl {
  const MassSpringSystem& system;
  IdaOptions options;
  Index n3;
  MassSpringOde ode;                          // consistent y' = [P v; P M^-1 f] at (re)starts
  FirstOrderMatrix jac;                       // G = dF/dy + cj dF/dy' (Kind::Dae)
  std::unique_ptr<SchurPreconditioner> prec;  // spgmr only
  Vec f;                                      // 3n force scratch of the residual
  Vec scaled;                                 // 6n scratch of the preconditioner solve
  SundialsErrorLog log;
  State last;
  bool restart = true;
  long restarts = 0;
  SundialsCounters before, counters;
  // SUNDIALS objects, freed in reverse order: the IDA memory first, the context last.
  SunPtr<SUNContext> ctx{nullptr, free_context};
  SunPtr<N_Vector> y{nullptr, free_vector};
  SunPtr<N_Vector> yp{nullptr, free_vector};
  SunPtr<SUNMatrix> A{nullptr, free_matrix};
  SunPtr<SUNLinearSolver> ls{nullptr, free_linear_solver};
  SunPtr<void*> mem{nullptr, free_ida};

  Impl(const MassSpringSystem& sys, IdaOptions opt);
  void read_counters();
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
    : system(sys),
      options(std::move(opt)),
      n3(sys.dofs()),
      ode(sys),
      jac(sys, FirstOrderMatrix::Kind::Dae),
      f(Vec::Zero(sys.dofs())),
      scaled(Vec::Zero(2 * sys.dofs())),
      last(sys.num_particles()) {
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
    prec =
        make_schur_preconditioner(system, options.preconditioner, options.preconditioner_tolerance);
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

StepSummary IdaStepper::step(const State& s0, double h, State& s1) {
  Impl& m = *m_impl;
  const Index n3 = m.n3;
  HOOKE_ASSERT(s0.x.size() == n3 && s0.v.size() == n3,
               "ida: s0 has " << s0.x.size() << " positions for " << n3 << " dofs");
  HOOKE_ASSERT(&s0 != &s1, "ida: s1 may not alias s0");
  StepSummary out;
  const double t1 = s0.t + h;
  if (!(h > 0.0) || !std::isfinite(h) || !std::isfinite(s0.t) || !(t1 > s0.t)) {
    out.status = Status::Fatal;
    std::ostringstream os;
    os << std::setprecision(10) << "ida: cannot step from t = " << s0.t << " by h = " << h
       << ": h must be positive, finite and above the round-off of t";
    out.message = os.str();
    return out;
  }
  if (!s0.is_finite()) {
    out.status = Status::Fatal;
    out.message = "ida: the start state is not finite";
    return out;
  }
  void* ida = m.mem.get();
  Eigen::Map<Vec> Y(N_VGetArrayPointer(m.y.get()), 2 * n3);
  Eigen::Map<Vec> YP(N_VGetArrayPointer(m.yp.get()), 2 * n3);
  if (m.restart || s0.t != m.last.t || s0.x != m.last.x || s0.v != m.last.v) {
    m.before = m.counters;
    Y.head(n3) = s0.x;
    Y.tail(n3) = s0.v;
    m.ode.rhs(s0.t, Y, YP);  // consistent: F(t0, y0, y'0) = 0 up to round-off
    const int flag = IDAReInit(ida, s0.t, m.y.get(), m.yp.get());
    if (flag < 0) {
      out.status = Status::Fatal;
      out.message = "ida: IDAReInit failed with flag " + std::to_string(flag);
      return out;
    }
    ++m.restarts;
    m.restart = false;
  }
  m.log.clear();
  if (IDASetStopTime(ida, t1) < 0) {
    m.restart = true;
    out.status = Status::Fatal;
    out.message = std::string("ida: IDASetStopTime failed: ") + m.log.text;
    return out;
  }
  const long newton0 = m.counters.nonlinear_iterations;
  const long linear0 = m.counters.linear_iterations;
  realtype t_reached = s0.t;
  const int flag = IDASolve(ida, t1, &t_reached, m.y.get(), m.yp.get(), IDA_NORMAL);
  m.read_counters();
  out.newton_iterations = int(m.counters.nonlinear_iterations - newton0);
  out.iterations = int(m.counters.linear_iterations - linear0);

  s1.x.resize(n3);
  s1.v.resize(n3);
  s1.x = Y.head(n3);
  s1.v = Y.tail(n3);
  s1.t = flag >= 0 ? t1 : t_reached;
  m.last.x = s1.x;
  m.last.v = s1.v;
  m.last.t = s1.t;
  if (flag >= 0 && s1.is_finite()) return out;  // IDA_SUCCESS or IDA_TSTOP_RETURN at t1

  m.restart = true;
  if (flag >= 0) {
    out.status = Status::Fatal;
    out.message =
        "ida: the state became non-finite at t = " + std::to_string(t1) + "; " + m.counters.line();
    return out;
  }
  switch (flag) {
    case IDA_TOO_MUCH_WORK:
    case IDA_TOO_MUCH_ACC:
    case IDA_ERR_FAIL:
    case IDA_CONV_FAIL:
      out.status = Status::NotConverged;
      break;
    case IDA_LSETUP_FAIL:
    case IDA_LSOLVE_FAIL:
      out.status = Status::BrokeDown;
      break;
    default:
      out.status = Status::Fatal;
  }
  char* flag_name = IDAGetReturnFlagName(flag);  // malloc'ed by SUNDIALS
  std::ostringstream os;
  os << std::setprecision(10) << "ida: " << (flag_name ? flag_name : "unknown flag") << " (" << flag
     << ") at t = " << t_reached << " on the step from t = " << s0.t << " to " << t1;
  std::free(flag_name);
  if (m.log.text[0]) os << ": " << m.log.text;
  os << "; " << m.counters.line();
  out.message = os.str();
  return out;
}

}  // namespace hooke
