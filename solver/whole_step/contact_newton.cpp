#include "hooke/whole_step/contact_newton.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "hooke/forces/force.hpp"

namespace hooke {
namespace {

bool dissipative(ForceForm form) {
  return form == ForceForm::Dampers || form == ForceForm::Drag || form == ForceForm::ElementDampers;
}

/// The magnitude of gravity among the system's forces (m/s^2), for the chosen stiffness.
double gravity_of(const MassSpringSystem& system) {
  Vec3 g = Vec3::Zero();
  for (const auto& f : system.forces())
    if (f->terms().form == ForceForm::Gravity) g += f->terms().acceleration;
  return g.norm();
}

}  // namespace

std::string contact_unsupported(const MassSpringSystem& system) {
  if (system.contact() == nullptr)
    return "the contact step needs a system with [contact] (MassSpringSystem::set_contact)";
  for (const auto& f : system.forces())
    if (f->terms().form == ForceForm::Unknown)
      return std::string(
                 "the contact step poses backward Euler as a minimisation and needs each "
                 "force to be a potential or a damper; '") +
             f->name() + "' is neither";
  return "";
}

ContactNewtonStepper::ContactNewtonStepper(const MassSpringSystem& system,
                                           std::unique_ptr<LinearSolver> solver,
                                           ImplicitOptions options)
    : m_system(system),
      m_solver(std::move(solver)),
      m_options(options),
      m_A(system),
      m_contact(*system.contact(), system.masses(), system.pinned(), system.pattern(),
                gravity_of(system)) {
  const std::string why = contact_unsupported(system);
  HOOKE_ASSERT(why.empty(), why);
  const OptionError err = m_options.validate();
  HOOKE_ASSERT(err.ok(), "ImplicitOptions: " << err.message);
  HOOKE_ASSERT(m_options.beta == 1.0,
               "the contact step is backward Euler (beta = 1), got beta = " << m_options.beta);
  m_jac_options.damping_position_terms = false;
  for (const auto& f : system.forces())
    m_dissipative = m_dissipative || dissipative(f->terms().form);
  const Index N = system.dofs();
  for (Vec* v : {&m_x0, &m_x, &m_xhat, &m_v, &m_f, &m_fd, &m_rhs, &m_dx, &m_trial, &m_tmp})
    v->setZero(N);
  m_force_magnitude.setZero(system.num_particles());
  if (m_contact.self_contact() != nullptr)
    m_grown = std::make_unique<ContactMatrix>(system.pattern());
  const LinearSummary a = m_solver->analyze(newton_matrix());
  if (a.status != Status::Converged) throw SetupError(a.message);
  accumulate(m_totals, a);
}

void ContactNewtonStepper::restore_history(const std::vector<double>& history) {
  if (history.empty()) {
    m_contact.set_kappa(0.0);
    return;
  }
  HOOKE_ASSERT(history.size() == 1 && history[0] >= 0.0,
               name() << ": contact history of " << history.size() << " numbers, expected 1");
  m_contact.set_kappa(history[0]);
}

std::string ContactNewtonStepper::start(const State& s0, double h) {
  m_x0 = s0.x;
  m_x = s0.x;
  const Vec& moving = m_system.moving();
  m_xhat = s0.x + h * s0.v.cwiseProduct(moving);
  const PinMotion& pins = m_system.pin_motion();
  for (size_t k = 0; k < pins.particles().size(); ++k) {
    const Index p = pins.particles()[k];
    m_x.segment<3>(3 * p) = pins.position(k, s0.t + h);
  }
  m_contact.begin_step(s0.t, h, s0.x);
  if (m_grown) {
    // The candidates over the pins' motion to t0 + h, and the grown pattern's unused blocks.
    m_tmp = m_x - m_x0;
    m_contact.prepare_line(m_x0, m_tmp);
    m_contact.self_blocks(m_x, m_pairs);
    if (m_grown->shrink(m_pairs)) {
      const LinearSummary a = m_solver->analyze(m_grown->matrix());
      accumulate(m_totals, a);
      if (a.status != Status::Converged) return a.message;
    }
  }
  const ContactFigures fig = m_contact.figures(m_x);
  m_min_gap = fig.min_gap;
  if (!(fig.min_gap > 0.0)) {
    std::ostringstream os;
    os << name() << ": a contact gap is " << fig.min_gap
       << " m at the step's start with the obstacles where they are at t = " << s0.t + h
       << " s: an obstacle moves into the cloth within one step, or a pinned particle is placed "
          "inside one (lower time.dt)";
    return os.str();
  }
  return "";
}

const SparseMatrix& ContactNewtonStepper::newton_matrix() const {
  return m_grown ? m_grown->matrix() : m_A.matrix();
}

void ContactNewtonStepper::shift_matrix(double s) {
  if (m_grown)
    m_grown->add_diagonal(m_system.mass_diagonal(), s);
  else
    m_A.add_mass_multiple(s);
}

LinearSummary ContactNewtonStepper::assemble(double h) {
  const auto ta = Clock::now();
  m_v = (m_x - m_x0) / h;
  m_system.compute_forces(m_x, m_v, m_f);
  m_A.assemble_jacobians(m_x, m_v, m_jac_options);
  const auto tc = Clock::now();
  m_contact.add_forces(m_x, m_f);
  m_contact.add_hessian(m_x, -1.0, m_A.stiffness(), PsdProjection::None);
  const double contact = seconds_since(tc);
  m_contact_seconds += contact;
  if (m_dissipative) {
    m_fd.setZero();
    for (const auto& f : m_system.forces())
      if (dissipative(f->terms().form)) f->add_forces(m_x, m_v, m_fd);
  }
  m_rhs = h * h * m_f;
  m_rhs -= m_system.mass_diagonal().cwiseProduct(m_x - m_xhat);
  m_A.zero_pinned(m_rhs);
  m_A.form(h, h * h);
  LinearSummary out;
  double self = 0.0;
  if (m_grown) {
    // Self-contact's blocks, the pattern grown (and analyzed) if one is missing, its Hessian.
    const auto ts = Clock::now();
    m_contact.self_blocks(m_x, m_pairs);
    self += seconds_since(ts);
    if (m_grown->grow(m_pairs)) {
      out = m_solver->analyze(m_grown->matrix());
      accumulate(m_totals, out);
    }
    m_grown->copy_from(m_A.matrix());
    const auto th = Clock::now();
    m_contact.add_self_hessian(m_x, h * h, *m_grown, PsdProjection::None);
    self += seconds_since(th);
    m_contact_seconds += self;
  }
  m_assembly_seconds += seconds_since(ta) - contact - self;  // the contact terms count apart
  return out;
}

LinearSummary ContactNewtonStepper::factor_shifted() {
  if (m_shift > 0.0) shift_matrix(m_shift);
  m_solver->set_coordinates(m_x);
  LinearSummary fs = m_solver->factor(newton_matrix());
  accumulate(m_totals, fs);
  for (int j = 0; j < 30 && fs.status != Status::Converged && fs.not_positive_definite; ++j) {
    ++m_shifted_factorizations;
    const double shift = m_shift > 0.0 ? 4.0 * m_shift : kFirstShift;
    shift_matrix(shift - m_shift);  // A already holds m_shift M
    m_shift = shift;
    fs = m_solver->factor(newton_matrix());
    accumulate(m_totals, fs);
  }
  m_shift = m_shift > 4.0 * kFirstShift ? 0.25 * m_shift : 0.0;
  return fs;
}

bool ContactNewtonStepper::line_search(double h, double& fraction) {
  const auto tc = Clock::now();
  m_contact.prepare_line(m_x, m_dx);
  const auto tccd = Clock::now();
  double alpha = m_contact.max_step(m_x, m_dx);
  m_ccd_seconds += seconds_since(tccd);
  m_contact_seconds += seconds_since(tc);
  fraction = alpha;
  // g(x) h^2 in difference form from the iterate m_x: the inertia term exactly, the potentials
  // and the contact energy as differences, the dissipative model by its definition.
  const Vec& mass = m_system.mass_diagonal();
  const Vec& moving = m_system.moving();
  const double e0 = m_system.potential_energy(m_x), c0 = m_contact.energy(m_x);
  const double h2 = h * h;
  // The predicted decrease of h^2 g along dx (A is positive definite, so it is >= 0).
  const double predicted = m_rhs.dot(m_dx);
  const double scale = h2 * (std::abs(e0) + std::abs(c0)) +
                       0.5 * (m_x - m_xhat).cwiseProduct(moving).cwiseAbs2().dot(mass);
  const Jacobians& J = m_A.jacobians();
  for (int k = 0; k < 60; ++k) {
    m_trial = m_x + alpha * m_dx;
    if (alpha * predicted <= 1e-12 * scale) return true;  // below g's round-off: take it
    const auto te = Clock::now();
    const double dc = m_contact.energy(m_trial) - c0;
    m_contact_seconds += seconds_since(te);
    double change = h2 * (m_system.potential_energy(m_trial) - e0 + dc);
    // Inertia: m/2 (|x + a dx - xhat|^2 - |x - xhat|^2) = m a dx . (x - xhat + a dx / 2).
    m_tmp = (m_x - m_xhat + 0.5 * alpha * m_dx).cwiseProduct(moving);
    change += alpha * m_dx.cwiseProduct(mass).dot(m_tmp);
    if (m_dissipative) {
      // -h^2 f_d . (a dx) + h a^2 dx^T (-D) dx / 2.
      change -= h2 * alpha * m_fd.dot(m_dx);
      if (J.velocity_values() != nullptr) {
        m_tmp.noalias() = J.D * m_dx;
        change -= 0.5 * h * alpha * alpha * m_dx.dot(m_tmp);
      }
    }
    if (change <= 0.0) return true;
    alpha *= 0.5;
  }
  return false;
}

StepSummary ContactNewtonStepper::step(const State& s0, double h, State& s1) {
  const auto t_start = Clock::now();
  StepSummary out;
  ++m_steps;
  m_stepped = true;
  m_ccd_fraction = 1.0;
  if (std::string why = start(s0, h); !why.empty()) {
    out.status = Status::BrokeDown;
    out.message = why;
    m_total_seconds += seconds_since(t_start);
    return out;
  }
  LinearSolveOptions lin;
  lin.tolerance = m_options.linear_tolerance;
  lin.max_iterations = m_options.max_linear_iterations;
  lin.warm_start = false;
  const double dhat = m_system.contact()->options().distance;
  const double v0 = s0.v.cwiseProduct(m_system.moving()).lpNorm<Eigen::Infinity>();
  bool converged = false;
  double dx_norm = 0.0;
  // The exact spring Hessian where A is positive definite (Newton converges quadratically);
  // where it is not, A + s M with the smallest s of 1e-3 * 4^j that a factorization accepts
  // (a Hessian modification; the step stays a descent direction), s remembered and quartered at
  // each next iteration. clamp_compressed = true clamps compressed springs instead, always.
  for (int k = 0; k < m_options.newton_iterations; ++k) {
    m_jac_options.clamp_compressed = m_options.clamp_compressed;
    const LinearSummary as = assemble(h);
    const LinearSummary fs = as.status == Status::Converged ? factor_shifted() : as;
    out.newton_iterations = k + 1;
    if (fs.status != Status::Converged) {
      out.status = fs.status;
      out.message = fs.message;
      break;
    }
    m_dx.setZero();
    const LinearSummary ss = m_solver->solve(m_rhs, m_dx, lin);
    accumulate(m_totals, ss);
    out.iterations += ss.iterations;
    out.residual = ss.residual;
    if (ss.status == Status::BrokeDown || ss.status == Status::Fatal) {
      out.status = ss.status;
      out.message = ss.message;
      break;
    }
    m_A.zero_pinned(m_dx);
    dx_norm = m_dx.lpNorm<Eigen::Infinity>();
    const double motion = h * std::max(m_v.lpNorm<Eigen::Infinity>(), v0);
    if (dx_norm <= m_options.newton_tolerance * std::max(motion, dhat)) {
      converged = true;
      break;
    }
    double fraction = 1.0;
    const bool descended = line_search(h, fraction);
    m_ccd_fraction = std::min(m_ccd_fraction, fraction);
    if (!descended) {
      std::ostringstream os;
      os << name() << ": the line search found no decrease of the incremental potential at "
         << "Newton iteration " << k + 1 << " (||dx||_inf = " << dx_norm << " m)";
      out.status = Status::NotConverged;
      out.message = os.str();
      break;
    }
    m_x = m_trial;
    const auto tf = Clock::now();
    m_min_gap = std::min(m_min_gap, m_contact.figures(m_x).min_gap);
    m_contact_seconds += seconds_since(tf);
  }
  m_newton_iterations += out.newton_iterations;
  m_last_newton = out.newton_iterations;
  if (!converged && out.status == Status::Converged) {
    std::ostringstream os;
    os << name() << ": Newton did not converge in " << m_options.newton_iterations
       << " iterations: last ||dx||_inf = " << dx_norm << " m (tolerance "
       << m_options.newton_tolerance << " relative)";
    out.status = Status::NotConverged;
    out.message = os.str();
  }
  s1.x = m_x;
  s1.v = ((m_x - m_x0) / h).cwiseProduct(m_system.moving());
  s1.t = s0.t + h;
  if (!step_failed(out)) m_contact.end_step(m_min_gap);
  m_total_seconds += seconds_since(t_start);
  return out;
}

StepperStats ContactNewtonStepper::stats() const {
  StepperStats s;
  s.steps = m_steps;
  s.iterations = m_newton_iterations;
  s.linear_iterations = m_totals.iterations;
  s.factorizations = m_solver->factorizations();
  s.assembly_seconds = m_assembly_seconds;
  s.analyze_seconds = m_totals.analyze_seconds;
  s.factor_seconds = m_totals.factor_seconds;
  s.solve_seconds = m_totals.solve_seconds;
  s.contact_seconds = m_contact_seconds;
  s.ccd_seconds = m_ccd_seconds;
  if (const SelfContact* sc = m_contact.self_contact())
    s.broad_phase_seconds = sc->broad_phase_seconds();
  if (m_grown) s.contact_pattern_builds = m_grown->rebuilds();
  s.total_seconds = m_total_seconds;
  return s;
}

std::vector<StepFigure> ContactNewtonStepper::step_figures(const State& s) {
  const ContactFigures fig = m_contact.figures(s.x);
  const double min_gap = m_stepped ? m_min_gap : fig.min_gap;
  std::vector<StepFigure> out = {{"newton_iterations", double(m_stepped ? m_last_newton : 0), 17},
                                 {"contacts", double(fig.active), 17},
                                 {"min_gap", min_gap, 9},
                                 {"ccd_fraction", m_stepped ? m_ccd_fraction : 1.0, 6},
                                 {"kappa", m_contact.kappa(), 6}};
  if (m_grown) out.push_back({"self_contacts", double(fig.self_active), 17});
  return out;
}

std::vector<ParticleField> ContactNewtonStepper::output_fields(const State& s) {
  m_force_magnitude.setZero();
  m_contact.add_force_magnitudes(s.x, m_force_magnitude);
  return {{"contact_force", &m_force_magnitude}};
}

}  // namespace hooke
