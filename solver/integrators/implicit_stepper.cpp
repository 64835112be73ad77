#include "hooke/integrators/implicit_stepper.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "hooke/integrators/step_controller.hpp"
#include "hooke/linear/linear_registry.hpp"
#include "hooke/parallel/thread_team.hpp"

namespace hooke {

OptionError ImplicitOptions::validate() const {
  std::ostringstream os;
  std::string field;
  if (!(beta >= 0.0 && beta <= 1.0)) {
    field = "beta";
    os << "beta = " << beta << ": must be in [0, 1]";
  } else if (newton_iterations < 1 || newton_iterations > 100000) {
    field = "newton_iterations";
    os << "newton_iterations = " << newton_iterations << ": must be in [1, 100000]";
  } else if (!(newton_tolerance > 0.0) || !std::isfinite(newton_tolerance)) {
    field = "newton_tolerance";
    os << "newton_tolerance = " << newton_tolerance << ": must be finite and > 0";
  } else if (!(linear_tolerance > 0.0) || !std::isfinite(linear_tolerance)) {
    field = "linear_tolerance";
    os << "linear_tolerance = " << linear_tolerance << ": must be finite and > 0";
  } else if (max_linear_iterations < 1) {
    field = "max_linear_iterations";
    os << "max_linear_iterations = " << max_linear_iterations << ": must be >= 1";
  }
  return {field, os.str()};
}

ImplicitOptions ImplicitOptions::defaults(ImplicitScheme scheme) {
  ImplicitOptions o;
  if (scheme == ImplicitScheme::Midpoint) {
    o.newton_iterations = kMidpointNewtonIterations;
    o.newton_tolerance = kMidpointNewtonTolerance;
  }
  return o;
}

ImplicitStepper::ImplicitStepper(const MassSpringSystem& system, ImplicitScheme scheme,
                                 std::unique_ptr<LinearSolver> solver, ImplicitOptions options)
    : m_system(system),
      m_scheme(scheme),
      m_solver(std::move(solver)),
      m_options(options),
      m_A(system) {
  const OptionError err = m_options.validate();
  HOOKE_ASSERT(err.ok(), "ImplicitOptions: " << err.message);
  HOOKE_ASSERT(m_options.linear_solver.empty() ||
                   canonical_linear_solver(m_options.linear_solver, m_options.preconditioner) ==
                       m_solver->name(),
               "ImplicitOptions::linear_solver / preconditioner are '"
                   << m_options.linear_solver << "' / '" << m_options.preconditioner
                   << "' but the backend given is '" << m_solver->name() << "'");
  m_jac_options.clamp_compressed = m_options.clamp_compressed;
  // Leave the damper's non-symmetric df/dx out of A for every backend: A then stays symmetric
  // (and SPD with the clamp), which CG and Cholesky need and under which Jacobi and Gauss-Seidel
  // are guaranteed to converge (measured: with it, block Jacobi diverged on a damped cloth).
  m_jac_options.damping_position_terms = false;
  const Index N = system.dofs();
  for (Vec* v : {&m_v0, &m_vb, &m_xa, &m_va, &m_xe, &m_v1, &m_xlin, &m_vlin, &m_rhs, &m_tmp, &m_dx,
                 &m_delta})
    v->setZero(N);
  // Only what a scheme and a system use: BDF2's history, and dv where there is a D to apply.
  if (m_scheme == ImplicitScheme::Bdf2)
    for (Point* p : {&m_hist[0], &m_hist[1], &m_last}) {
      p->x.setZero(N);
      p->v.setZero(N);
    }
  if (system.has_velocity_jacobian()) m_dv.setZero(N);
  if (m_scheme == ImplicitScheme::Midpoint && m_options.discrete_gradient) m_x1.setZero(N);
  const LinearSummary a = m_solver->analyze(m_A.matrix());
  if (a.status != Status::Converged) throw SetupError(a.message);
  accumulate(m_totals, a);
}

std::string ImplicitStepper::report() const {
  std::ostringstream os;
  if (m_doubling)
    os << "step doubling (3 steps per step" << (m_solver_half ? ", halves on a second backend" : "")
       << "); ";
  os << m_solver->name() << ": " << m_totals.iterations << " linear iterations, "
     << stats().factorizations << " factorizations; analyze " << m_totals.analyze_seconds
     << " s, factor " << m_totals.factor_seconds << " s, solve " << m_totals.solve_seconds
     << " s; force and Jacobian assembly " << m_assembly_seconds << " s";
  return os.str();
}

std::vector<double> ImplicitStepper::history() const {
  const std::vector<char>& pinned = m_system.pinned();
  std::vector<double> h;
  if (m_scheme == ImplicitScheme::Bdf2) {
    h = {m_has_last ? 1.0 : 0.0, m_last.t, m_last_t1, double(m_last_count), m_hist[0].t};
    for (const Vec* v : {&m_last.x, &m_last.v, &m_hist[0].x, &m_hist[0].v})
      h.insert(h.end(), v->data(), v->data() + v->size());
    if (m_estimating)
      for (const Vec* v : {&m_error.end.x, &m_error.end.v})
        h.insert(h.end(), v->data(), v->data() + v->size());
  }
  // The correction on the free DOFs only.
  for (Index i = 0; i < m_delta.size(); ++i)
    if (!pinned[size_t(i / 3)]) h.push_back(m_delta[i]);
  return h;
}

void ImplicitStepper::restore_history(const std::vector<double>& h) {
  if (h.empty()) {  // none kept (a distributed run's checkpoint): start as a new stepper does
    m_has_last = false;
    m_delta.setZero();
    return;
  }
  const std::vector<char>& pinned = m_system.pinned();
  const size_t N = size_t(m_system.dofs()), nf = N - 3 * size_t(m_system.num_pinned());
  const size_t head = m_scheme == ImplicitScheme::Bdf2 ? 5 + (m_estimating ? 6 : 4) * N : 0;
  HOOKE_ASSERT(h.size() == head + nf, name() << ": history of " << h.size() << " numbers, expected "
                                             << head + nf << " for " << N << " dofs");
  if (m_scheme == ImplicitScheme::Bdf2) {
    HOOKE_ASSERT((h[0] == 0.0 || h[0] == 1.0) && (h[3] == 0.0 || h[3] == 1.0 || h[3] == 2.0),
                 name() << ": history flags " << h[0] << ", " << h[3] << " out of range");
    m_has_last = h[0] != 0.0;
    m_last.t = h[1];
    m_last_t1 = h[2];
    m_last_count = int(h[3]);
    m_hist[0].t = h[4];
    size_t k = 5;
    for (Vec* v :
         {&m_last.x, &m_last.v, &m_hist[0].x, &m_hist[0].v, &m_error.end.x, &m_error.end.v}) {
      if (k == head) break;  // m_error.end only under error control
      *v = Eigen::Map<const Vec>(h.data() + k, Index(N));
      k += N;
    }
  }
  size_t k = head;
  for (Index i = 0; i < m_delta.size(); ++i) m_delta[i] = pinned[size_t(i / 3)] ? 0.0 : h[k++];
}

const char* ImplicitStepper::name() const {
  switch (m_scheme) {
    case ImplicitScheme::Beta:
      return "implicit";
    case ImplicitScheme::Midpoint:
      return "implicit-midpoint";
    case ImplicitScheme::Bdf2:
      return "bdf2";
  }
  return "implicit";
}

ImplicitStepper::OneLeg ImplicitStepper::set_up(const State& s0, double h) {
  m_w = m_scheme == ImplicitScheme::Bdf2 ? bdf2_history(s0, h) : 0.0;
  OneLeg c;
  if (m_scheme == ImplicitScheme::Beta || (m_scheme == ImplicitScheme::Bdf2 && m_w == 0.0)) {
    const double beta = m_scheme == ImplicitScheme::Beta ? m_options.beta : 1.0;
    m_xa = s0.x;
    m_va = (1.0 - beta) * m_v0;
    m_vb = m_v0;
    m_xe = s0.x;
    c = {beta * h, beta, h, h};
  } else if (m_scheme == ImplicitScheme::Midpoint) {
    m_xa = s0.x + (0.25 * h) * m_v0;
    m_va = 0.5 * m_v0;
    m_vb = m_v0;
    m_xe = s0.x + (0.5 * h) * m_v0;
    c = {0.25 * h, 0.5, h, 0.5 * h};
  } else {  // w = 1 gives 4/3, -1/3 and 2/3 to the last bit
    const double w = m_w, a0 = (1.0 + w) * (1.0 + w) / (1.0 + 2.0 * w),
                 a1 = -(w * w) / (1.0 + 2.0 * w), b = (1.0 + w) / (1.0 + 2.0 * w);
    m_xa = a0 * s0.x + a1 * m_hist[0].x;
    m_va.setZero();
    m_vb = a0 * m_v0 + a1 * m_hist[0].v;
    m_xe = m_xa;
    c = {b * h, 1.0, b * h, b * h};
  }
  return c;
}

double ImplicitStepper::bdf2_history(const State& s0, double h) {
  // Steps are matched by time (run loops compute h as differences of step times, and the state a
  // step starts from is the one its caller committed, after constraints).
  const double tol = 1e-12 * std::max({h, std::abs(s0.t), m_last_t1 - m_last.t});
  auto swap_points = [](Point& a, Point& b) {
    std::swap(a.t, b.t);
    a.x.swap(b.x);  // Eigen swaps the buffers: no copy, no allocation
    a.v.swap(b.v);
  };
  // Under error control the history must be a smooth trajectory for the predictor: a start state
  // other than the last step's result (moved by a collider, the strain limit or the user) starts
  // the history anew, as it would otherwise extrapolate the jump. Without error control it goes
  // on through such a state, as BDF2 always has.
  auto moved = [&] {
    const Vec& free = m_system.moving();
    return (s0.x - m_error.end.x).cwiseProduct(free).cwiseAbs().maxCoeff() != 0.0 ||
           (m_v0 - m_error.end.v).cwiseProduct(free).cwiseAbs().maxCoeff() != 0.0;
  };
  int count = 0;  // valid states in m_hist for this step
  if (m_has_last && std::abs(m_last_t1 - s0.t) <= tol &&
      !(m_estimating && moved())) {  // follows the last step
    swap_points(m_hist[1], m_hist[0]);
    swap_points(m_hist[0], m_last);
    count = std::min(m_last_count + 1, 2);
  } else if (m_has_last && std::abs(m_last.t - s0.t) <= tol) {  // retries it
    count = m_last_count;
  }  // else a new start: count = 0
  m_last.t = s0.t;
  m_last.x = s0.x;
  m_last.v = m_v0;
  m_last_t1 = s0.t + h;
  m_last_count = count;
  m_has_last = true;
  // Under error control the estimate needs two states before s0 (see error_estimate_order()).
  if (count < (m_estimating ? 2 : 1)) return 0.0;
  double w = h / (s0.t - m_hist[0].t);
  if (std::abs(w - 1.0) <= 1e-9) w = 1.0;  // constant steps, to round-off in the step times
  return w <= kBdf2MaxRatio * (1.0 + 1e-9) ? w : 0.0;
}

void ImplicitStepper::bdf2_predict(const State& s0, double h) {
  if (m_w == 0.0) {  // backward Euler: explicit Euler, y0 + h y0' (m_rhs is scratch here)
    m_system.compute_forces(s0.x, m_v0, m_rhs);
    m_xp = s0.x + h * m_v0;
    m_vp = m_v0 + h * m_rhs.cwiseQuotient(m_system.mass_diagonal());
    m_milne = -0.5;
  } else {  // the quadratic through y_{n-2}, y_{n-1}, y_n at t + h (Lagrange weights l0, l1, l2)
    const double w = m_w, h1 = s0.t - m_hist[0].t, h2 = m_hist[0].t - m_hist[1].t;
    const double l0 = (h + h1) * (h + h1 + h2) / (h1 * (h1 + h2)),
                 l1 = -h * (h + h1 + h2) / (h1 * h2), l2 = h * (h + h1) / ((h1 + h2) * h2);
    m_xp = l0 * s0.x + l1 * m_hist[0].x + l2 * m_hist[1].x;
    m_vp = l0 * m_v0 + l1 * m_hist[0].v + l2 * m_hist[1].v;
    const double C = -(1.0 + w) * (1.0 + w) * h * h * h / (6.0 * w * (1.0 + 2.0 * w)),
                 P = h * (h + h1) * (h + h1 + h2) / 6.0;
    m_milne = C / (P - C);
  }
  m_A.zero_pinned(m_vp);  // pinned particles stand still (scripted ones: newton() sets theirs)
}

void ImplicitStepper::bdf2_estimate(const State& s0, const State& s1) {
  m_error.err_x = m_milne * (s1.x - m_xp);
  m_error.err_v = m_milne * (s1.v - m_vp);
  // Pinned and scripted particles follow their prescription: no integration error.
  m_A.zero_pinned(m_error.err_x);
  m_A.zero_pinned(m_error.err_v);
  m_error.set_ends(s0, s1);
}

void ImplicitStepper::assemble(const OneLeg& c, ConstRef x0, bool discrete) {
  const auto ta = Clock::now();
  if (discrete) {
    m_x1 = m_xe + c.ex * m_v1;
    m_system.compute_discrete_gradient(x0, m_x1, m_xlin, m_vlin, m_rhs);
    m_A.assemble_discrete_gradient_jacobians(x0, m_x1, m_xlin, m_vlin, m_jac_options);
  } else {
    m_system.compute_forces(m_xlin, m_vlin, m_rhs);
    m_A.assemble_jacobians(m_xlin, m_vlin, m_jac_options);
  }
  const Jacobians& J = m_A.jacobians();
  // rhs = hf (f_lin + K dx + D dv) - M (v1 - vb), with dx, dv the gap between the current
  // iterate's arguments and the linearisation point (nonzero only in the first iteration).
  m_dx = m_xa + c.bx * m_v1 - m_xlin;
  m_tmp.noalias() = J.K * m_dx;
  m_rhs += m_tmp;  // m_rhs holds f_lin (compute_forces above)
  if (J.velocity_values() != nullptr) {
    m_dv = m_va + c.cv * m_v1 - m_vlin;
    m_tmp.noalias() = J.D * m_dv;
    m_rhs += m_tmp;
  }
  m_rhs *= c.hf;
  m_rhs -= m_system.mass_diagonal().cwiseProduct(m_v1 - m_vb);
  m_A.zero_pinned(m_rhs);
  m_A.form(c.hf * c.cv, c.hf * c.bx);  // K's values become A's: K is read above, before this
  m_assembly_seconds += seconds_since(ta);
}

int ImplicitStepper::error_estimate_order() const {
  switch (m_scheme) {
    case ImplicitScheme::Beta:
      return 1;
    case ImplicitScheme::Midpoint:
      return 2;
    case ImplicitScheme::Bdf2:
      return 2;
  }
  return 0;
}

double ImplicitStepper::max_step_ratio() const {
  return m_scheme == ImplicitScheme::Bdf2 ? kBdf2MaxRatio : std::numeric_limits<double>::infinity();
}

void ImplicitStepper::set_error_estimation(bool on) {
  HOOKE_ASSERT(!on || error_estimate_order() > 0, name() << " makes no local error estimate");
  HOOKE_ASSERT(!on || !m_system.distribution(), name()
                                                    << ": error control on a distributed system");
  m_estimating = on;
  m_doubling = on && m_scheme != ImplicitScheme::Bdf2;
  const Index n = m_system.num_particles();
  if (on && !m_error.allocated()) m_error.allocate(n);
  if (on && m_scheme == ImplicitScheme::Bdf2 && m_xp.size() == 0) {
    m_xp.setZero(3 * n);
    m_vp.setZero(3 * n);
  }
  if (m_doubling && m_full.x.size() == 0) {
    for (State* s : {&m_full, &m_half}) *s = State(n);
    if (linear_solver_unknown(m_solver->name()).empty()) {
      m_solver_half = make_linear_solver(m_solver->name(), "",
                                         {m_options.petsc_options, m_system.distribution()});
      const LinearSummary a = m_solver_half->analyze(m_A.matrix());
      if (a.status != Status::Converged) throw SetupError(a.message);
      accumulate(m_totals, a);
    }
  }
}

double ImplicitStepper::error_norm(double rtol, double atol) {
  HOOKE_ASSERT(m_estimating, name() << ": error_norm without set_error_estimation(true)");
  return m_error.norm(rtol, atol);
}

StepSummary ImplicitStepper::step(const State& s0, double h, State& s1) {
  const auto t0 = Clock::now();
  // The step's own parallel loops (assembly, right-hand sides, updates) on the size the linear
  // solver's iterations run at present (CG's AdaptiveTeam), as fast-mass-spring's: with one core
  // busy, a loop on two threads waits for the descheduled one.
  std::optional<TeamStep> team_step;
  if (AdaptiveTeam* team = m_solver->team()) team_step.emplace(*team);
  const StepSummary out = m_doubling ? doubled(s0, h, s1) : newton(s0, h, s1, *m_solver);
  if (m_estimating && m_scheme == ImplicitScheme::Bdf2 && out.status != Status::BrokeDown &&
      out.status != Status::Fatal)
    bdf2_estimate(s0, s1);
  ++m_steps;
  m_newton_iterations += out.newton_iterations;
  m_last_residual = out.residual;
  m_total_seconds += seconds_since(t0);
  return out;
}

StepSummary ImplicitStepper::doubled(const State& s0, double h, State& s1) {
  // Three steps; a failure of any ends the step with its summary (the caller shrinks h).
  LinearSolver& half = m_solver_half ? *m_solver_half : *m_solver;
  StepSummary out;
  add_substep(out, newton(s0, h, m_full, *m_solver));
  if (step_failed(out)) return out;
  add_substep(out, newton(s0, 0.5 * h, m_half, half));
  if (step_failed(out)) return out;
  add_substep(out, newton(m_half, (s0.t + h) - m_half.t, s1, half));
  if (step_failed(out)) return out;
  m_error.extrapolate(s0, m_full, error_estimate_order(), h, s1);
  return out;
}

void ImplicitStepper::start_newton(const State& s0, double h, const OneLeg& c) {
  // Under error control BDF2 starts Newton from its predictor, as BDF codes do: the linearisation
  // error of one Newton step is then O(h^6) instead of O(h^3), below the error the estimate
  // measures. Otherwise the first iteration linearises at the step's start (x0, v0).
  const bool predicted = m_estimating && m_scheme == ImplicitScheme::Bdf2;
  if (predicted) bdf2_predict(s0, h);
  if (predicted)  // the initial guess
    m_v1 = m_vp;
  else
    m_v1 = m_v0;
  // A scripted pin's v1 puts it on its path at t + h: x1 = xe + ex v1 = x_p(t + h). Its rows stay
  // Dirichlet rows (delta = 0); the first linearisation's K dx carries its motion to the free
  // particles' right-hand side.
  const PinMotion& pins = m_system.pin_motion();
  for (size_t k = 0; k < pins.particles().size(); ++k) {
    const Index p = pins.particles()[k];
    m_v1.segment<3>(3 * p) = (pins.position(k, s0.t + h) - m_xe.segment<3>(3 * p)) / c.ex;
  }
  if (predicted) {  // (a conditional expression here would allocate a temporary vector)
    m_xlin = m_xa + c.bx * m_v1;
    m_vlin = m_va + c.cv * m_v1;
  } else {
    m_xlin = s0.x;
    m_vlin = m_v0;
  }
}

StepSummary ImplicitStepper::newton(const State& s0, double h, State& s1, LinearSolver& solver) {
  const Index N = m_system.dofs();
  HOOKE_ASSERT(s0.x.size() == N && s0.v.size() == N, "state size mismatch");
  // Pinned particles never move (their velocity is taken as zero throughout) unless scripted.
  m_v0 = s0.v.cwiseProduct(m_system.moving());
  // One-leg coefficients: M (v1 - vb) = hf f(xa + bx v1, va + cv v1), x1 = xe + ex v1.
  const OneLeg c = set_up(s0, h);

  StepSummary out;
  LinearSolveOptions lin;
  lin.tolerance = m_options.linear_tolerance;
  lin.max_iterations = m_options.max_linear_iterations;
  lin.warm_start = true;
  start_newton(s0, h, c);
  double delta_norm = 0.0;
  int failed_predictions = 0;  // consecutive iterations whose rate cannot reach the tolerance
  bool converged = m_options.newton_iterations == 1;
  for (int k = 0; k < m_options.newton_iterations; ++k) {
    if (k > 0) {
      m_xlin = m_xa + c.bx * m_v1;
      m_vlin = m_va + c.cv * m_v1;
    }
    assemble(c, s0.x, k > 0 && m_x1.size() > 0);
    solver.set_coordinates(m_xlin);
    const LinearSummary fs = solver.factor(m_A.matrix());
    accumulate(m_totals, fs);
    if (fs.status != Status::Converged) {
      out.status = fs.status;
      out.message = fs.message;
      if (fs.not_positive_definite) out.message += not_positive_definite_hint(c);
      out.newton_iterations = k;
      return out;
    }
    const LinearSummary ss = solver.solve(m_rhs, m_delta, lin);
    accumulate(m_totals, ss);
    out.iterations += ss.iterations;
    out.residual = ss.residual;
    out.newton_iterations = k + 1;
    if (ss.status == Status::BrokeDown || ss.status == Status::Fatal) {
      out.status = ss.status;
      out.message = ss.message;
      if (ss.not_positive_definite) out.message += not_positive_definite_hint(c);
      return out;
    }
    if (ss.status == Status::NotConverged) {
      out.status = Status::NotConverged;
      out.message = ss.message;
    }
    // Pinned DOFs are decoupled with a zero right-hand side; zeroing them here keeps a pinned
    // particle exactly still whatever round-off a backend leaves there.
    m_A.zero_pinned(m_delta);
    m_v1 += m_delta;
    if (m_options.newton_iterations > 1) {
      const double previous_norm = delta_norm;
      // Over every process of a distributed system: its ghosts hold their owners' values, so the
      // largest local norm is the whole system's.
      const Distribution* d = m_system.distribution();
      delta_norm = m_delta.lpNorm<Eigen::Infinity>();
      double scale =
          std::max({m_v1.lpNorm<Eigen::Infinity>(), m_v0.lpNorm<Eigen::Infinity>(), 1e-12});
      if (d) {
        delta_norm = d->max(delta_norm);
        scale = d->max(scale);
      }
      const double target = m_options.newton_tolerance * scale;
      if (delta_norm <= target) {
        converged = true;
        break;
      }
      if (const std::string why =
              newton_hopeless(k, delta_norm, previous_norm, scale, failed_predictions);
          !why.empty()) {
        out.status = Status::NotConverged;
        out.message = why;
        break;
      }
    }
  }
  if (!converged && out.status == Status::Converged) {
    std::ostringstream os;
    os << name() << ": Newton did not converge in " << m_options.newton_iterations
       << " iterations: last ||delta v||_inf = " << delta_norm << " (tolerance "
       << m_options.newton_tolerance << " relative)";
    out.status = Status::NotConverged;
    out.message = os.str();
  }
  s1.v = m_v1;
  s1.x = m_xe + c.ex * m_v1;
  s1.t = s0.t + h;
  return out;
}

std::string ImplicitStepper::newton_hopeless(int k, double delta_norm, double previous_norm,
                                             double scale, int& failed_predictions) const {
  // A rate test in the manner of SUNDIALS' nonlinear solvers (cvode's crate): from the third
  // iteration on (the first is the linearisation at the step's start), stop as soon as the
  // measured contraction rate shows that the remaining iterations cannot reach the tolerance, so
  // that a stalled or diverging iteration (a step too large for the problem's nonlinearity) fails
  // fast and the caller can shrink h instead of waiting out the cap. Newton's pre-asymptotic phase
  // can have one or two poor rates before it turns quadratic (measured on a stiff chain with the
  // exact Jacobian: 0.89, then 2e-6), so only three failed predictions in a row stop it.
  // Corrections within 1e4 ulps of the scale are round-off, whose ratios say nothing.
  const int remaining = m_options.newton_iterations - 1 - k;
  if (k < 2 || remaining <= 0 || delta_norm <= 1e4 * std::numeric_limits<double>::epsilon() * scale)
    return "";
  const double target = m_options.newton_tolerance * scale;
  const double rate = delta_norm / previous_norm;
  const bool hopeless =
      rate >= 1.0 || delta_norm * std::pow(rate, remaining) / (1.0 - rate) > target;
  failed_predictions = hopeless ? failed_predictions + 1 : 0;
  if (failed_predictions < 3) return "";
  std::ostringstream os;
  os << name() << ": Newton cannot converge in " << m_options.newton_iterations
     << " iterations: after " << k + 1 << ", ||delta v||_inf = " << delta_norm
     << " contracts at rate " << rate << " per iteration (tolerance " << m_options.newton_tolerance
     << " relative)";
  return os.str();
}

std::string ImplicitStepper::not_positive_definite_hint(const OneLeg& c) const {
  // A = M - a D - b K with a, b >= 0 and M > 0 (MassSpringSystem checks the masses), pinned
  // rows and columns replaced by their masses. The damper's df/dx is left out of K (m_jac_options),
  // so K holds the springs' df/dx only, and D the dampers' and the air drag's df/dv.
  const double a = c.hf * c.cv, b = c.hf * c.bx;
  const SparseMatrix& A = m_A.matrix();
  std::ostringstream os;
  os << "; " << name() << ": A = M - a D - b K with a = " << a << " s, b = " << b << " s^2";
  if (!Eigen::Map<const Vec>(A.valuePtr(), A.nonZeros()).allFinite()) {
    os << " has non-finite entries: non-finite positions or velocities, or an infinite or NaN "
          "stiffness, damping or drag coefficient";
  } else if (!m_options.clamp_compressed) {
    // HookeSpring: a spring compressed below its rest length (l < L) adds the indefinite
    // transverse term -k (1 - L/l) (I - u u^T) to K.
    os << "; with clamp_compressed = false, a compressed spring (shorter than its rest length) "
          "makes K indefinite: set clamp_compressed = true (the default) to clamp that term";
  } else {
    // With the clamp, each spring block of K is -k (u u^T + t (I - u u^T)) with t >= 0, each
    // damper block of D is -c u u^T and the drag's is -c I: all negative semi-definite for
    // k, c >= 0, so that A >= M > 0 in exact arithmetic.
    os << "; with clamp_compressed on, K and D are negative semi-definite when every stiffness, "
          "damping and drag coefficient is >= 0, so A is positive definite in exact arithmetic: "
          "look for a negative coefficient (or a force whose K or D is not negative "
          "semi-definite), or for stiffnesses so large against the masses (b k / m near 1e15 or "
          "beyond) that round-off loses M";
  }
  return os.str();
}

StepperStats ImplicitStepper::stats() const {
  StepperStats s;
  s.steps = m_steps;
  s.iterations = m_newton_iterations;
  s.linear_iterations = m_totals.iterations;
  s.factorizations =
      m_solver->factorizations() + (m_solver_half ? m_solver_half->factorizations() : 0);
  s.last_residual = m_last_residual;
  s.assembly_seconds = m_assembly_seconds;
  s.analyze_seconds = m_totals.analyze_seconds;
  s.factor_seconds = m_totals.factor_seconds;
  s.solve_seconds = m_totals.solve_seconds;
  s.total_seconds = m_total_seconds;
  return s;
}

}  // namespace hooke
