#include "hooke/sph/sph_stepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace hooke {

std::string sph_unsupported(const MassSpringSystem& system) {
  if (system.fluid() == nullptr)
    return "the system has no fluid: the SPH methods (wcsph, iisph) step fluids only";
  if (system.has_pin_motion()) return "scripted pins are not supported in fluid scenes";
  return "";
}

SphStepper::SphStepper(const MassSpringSystem& system, double courant)
    : m_system(system),
      m_fluid(*[&] {
        if (const std::string why = sph_unsupported(system); !why.empty())
          throw std::invalid_argument(why);
        return system.fluid();
      }()),
      m_courant(courant),
      m_search(m_fluid.support()) {
  HOOKE_ASSERT(courant >= 0.0 && std::isfinite(courant), "CFL number " << courant);
  const Index nf = m_fluid.num_fluid(), n = system.num_particles();
  if (courant > 0.0) m_sub[0] = m_sub[1] = State(n);
  m_rho = Vec::Constant(nf, m_fluid.rest_density());
  m_p = Vec::Zero(nf);
  if (m_fluid.options().gradient_correction) m_moment = Vec::Zero(nf);
  m_a = Vec::Zero(3 * n);
  m_body = Vec::Zero(3 * n);
  m_force = Vec::Zero(3 * n);
  m_moving = system.moving();
}

StepSummary SphStepper::step(const State& s0, double h, State& s1) {
  if (m_courant == 0.0) {
    StepSummary s = substep(s0, h, s1);
    m_last.substeps = 1;
    return s;
  }
  // Substeps until t0 + h, each of the remaining time over the fewest pieces the CFL step at its
  // start allows; a substep count beyond kMaxSubsteps means the speeds have run away.
  constexpr long long kMaxSubsteps = 1000000;
  StepSummary total;
  FluidStepStats agg;
  const State* from = &s0;
  double done = 0.0;
  for (int k = 0;; ++k) {
    const double remaining = h - done;
    const double limit = cfl_limit(*from);
    const double pieces = std::ceil(remaining / limit * (1.0 - 1e-12));
    if (!(pieces < double(kMaxSubsteps))) {
      std::ostringstream os;
      os << "CFL: the CFL step " << limit << " s would split the remaining " << remaining
         << " s into more than " << kMaxSubsteps << " substeps (largest speed "
         << max_fluid_speed(*from) << " m/s); the fluid has exploded";
      total.status = Status::Fatal;
      total.message = os.str();
      return total;
    }
    const bool last = pieces <= 1.0;
    const double hs = last ? remaining : remaining / pieces;
    State& to = last ? s1 : m_sub[k & 1];
    const StepSummary s = substep(*from, hs, to);
    total.iterations += s.iterations;
    total.residual = std::max(total.residual, s.residual);
    agg.max_density_error = std::max(agg.max_density_error, m_last.max_density_error);
    agg.mean_density_error = std::max(agg.mean_density_error, m_last.mean_density_error);
    agg.pressure_iterations += m_last.pressure_iterations;
    agg.pressure_residual = std::max(agg.pressure_residual, m_last.pressure_residual);
    agg.max_speed = m_last.max_speed;
    agg.lost = m_last.lost;
    ++agg.substeps;
    if (s.status == Status::Fatal) {
      m_last = agg;
      total.status = s.status;
      total.message = s.message;
      return total;
    }
    if (s.status != Status::Converged && total.status == Status::Converged) {
      total.status = s.status;  // NotConverged: the run decides (run.allow_not_converged)
      total.message = s.message;
    }
    if (last) break;
    done += hs;
    from = &to;
  }
  s1.t = s0.t + h;
  m_last = agg;
  return total;
}

double SphStepper::max_fluid_speed(const State& s) const {
  double max_speed2 = 0.0;
  for (Index i = 0; i < m_fluid.num_fluid(); ++i)
    if (!lost(s.x, i)) max_speed2 = std::max(max_speed2, s.v.segment<3>(3 * i).squaredNorm());
  return std::sqrt(max_speed2);
}

bool SphStepper::lost(ConstRef x, Index i) const {
  const Index nf = m_fluid.num_fluid(), n = x.size() / 3;
  if (n == nf) return false;
  if (!m_domain_known) {
    // The boundary particles never move: their box, from any state, once.
    const auto P =
        Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>>(x.data() + 3 * nf, 3, n - nf);
    m_domain_lower = P.rowwise().minCoeff().array() - m_fluid.support();
    m_domain_upper = P.rowwise().maxCoeff().array() + m_fluid.support();
    m_domain_known = true;
  }
  const Vec3 xi = x.segment<3>(3 * i);
  // Open at the top (+y): spray above the walls comes back.
  return xi.x() < m_domain_lower.x() || xi.x() > m_domain_upper.x() ||
         xi.y() < m_domain_lower.y() || xi.z() < m_domain_lower.z() || xi.z() > m_domain_upper.z();
}

std::string SphStepper::report() const {
  std::ostringstream os;
  os << format_stats(m_stats) << "; last step: max density error " << m_last.max_density_error
     << ", mean " << m_last.mean_density_error;
  if (m_last.lost > 0)
    os << "; " << m_last.lost << " fluid particles lost (left the walls' domain)";
  return os.str();
}

void SphStepper::output_densities(const State& s) {
  // The next step updates the search at the same positions again: an update depends on the
  // positions only, so this one leaves the steps unchanged.
  m_output_rho.resize(m_fluid.num_fluid());
  if (m_search.update(s.x, m_fluid.num_fluid()) == Status::Converged)
    m_fluid.compute_density(m_search, s.x, m_system.masses(), m_output_rho);
  else
    m_output_rho.setConstant(std::numeric_limits<double>::quiet_NaN());
}

std::vector<StepFigure> SphStepper::step_figures(const State& s) {
  FluidStepStats st = m_last;
  if (m_stats.steps == 0) {  // the initial state's densities
    output_densities(s);
    st = {};
    std::tie(st.max_density_error, st.mean_density_error) =
        density_errors(m_output_rho, m_fluid.rest_density());
  }
  double front = -std::numeric_limits<double>::infinity();
  for (Index i = 0; i < m_fluid.num_fluid(); ++i) front = std::max(front, s.x[3 * i]);
  return {{"max_density_error", st.max_density_error, 6},
          {"mean_density_error", st.mean_density_error, 6},
          {"pressure_iterations", double(st.pressure_iterations), 17},
          {"substeps", double(st.substeps), 17},
          {"front", front, 17},
          {"lost", double(st.lost), 17}};
}

std::vector<ParticleField> SphStepper::output_fields(const State& s) {
  output_densities(s);
  return {{"density", &m_output_rho}, {"pressure", &m_p}};
}

bool SphStepper::prepare(ConstRef x, StepSummary& s) {
  if (m_search.update(x, m_fluid.num_fluid()) != Status::Converged) {
    s.status = Status::Fatal;
    s.message = "CFL: the neighbour search failed: " + m_search.error() +
                "; the fluid has exploded (reduce dt below the CFL step)";
    return false;
  }
  if (m_fluid.options().gradient_correction) {
    m_fluid.compute_density(m_search, x, m_system.masses(), m_rho, m_moment);
    m_gradient_scale = 1.0 / FluidModel::mean_gradient_moment(m_moment);
  } else {
    m_fluid.compute_density(m_search, x, m_system.masses(), m_rho);
  }
  const auto [max_error, mean_error] = density_errors(m_rho, m_fluid.rest_density());
  m_last = {};
  m_last.max_density_error = max_error;
  m_last.mean_density_error = mean_error;
  for (Index i = 0; i < m_fluid.num_fluid(); ++i) {
    const bool gone = lost(x, i);
    m_moving.segment<3>(3 * i).setConstant(gone ? 0.0 : m_system.moving()[3 * i]);
    m_last.lost += gone ? 1 : 0;
  }
  return true;
}

void SphStepper::mask_acceleration() { m_a.array() *= m_moving.array(); }

void SphStepper::external_acceleration(ConstRef x, ConstRef v) {
  m_system.compute_forces(x, v, m_force);
  m_body = m_system.free_inverse_mass().cwiseProduct(m_force).cwiseProduct(m_moving);
  m_a = m_body;
  m_fluid.add_viscous_acceleration(m_search, x, v, m_system.masses(), m_rho, m_a);
  m_fluid.add_wall_support(m_search, x, m_rho, m_body, m_a, m_gradient_scale);
  mask_acceleration();
}

void SphStepper::finish_step(const State& s0, double h, State& s1, double max_density_error,
                             StepSummary& s) {
  // Lost particles stop where they are (m_moving); the others move by symplectic Euler.
  s1.v = (s0.v + h * m_a).cwiseProduct(m_moving);
  s1.x = s0.x + h * s1.v;
  s1.t = s0.t + h;
  // Every fluid particle's speed, one that left the domain in this very step included: an
  // explosion that throws the fluid out of the tank still fails the checks below.
  double max_speed2 = 0.0;
  for (Index i = 0; i < m_fluid.num_fluid(); ++i)
    max_speed2 = std::max(max_speed2, s1.v.segment<3>(3 * i).squaredNorm());
  m_last.max_speed = std::sqrt(max_speed2);
  ++m_stats.steps;
  m_stats.last_residual = m_last.max_density_error;
  if (!(m_last.max_density_error <= max_density_error)) {
    std::ostringstream os;
    os << "density: the largest density error " << m_last.max_density_error * 100
       << "% exceeds max_density_error " << max_density_error * 100
       << "%; the fluid is compressed beyond the method's limit (reduce dt)";
    s.status = Status::Fatal;
    s.message = os.str();
  } else if (!(h * m_last.max_speed <= m_fluid.support())) {
    std::ostringstream os;
    os << "CFL: a particle moved " << h * m_last.max_speed << " m in one step at "
       << m_last.max_speed << " m/s, more than the kernel support " << m_fluid.support()
       << " m; the fluid has exploded (reduce dt below the CFL step)";
    s.status = Status::Fatal;
    s.message = os.str();
  }
}

}  // namespace hooke
