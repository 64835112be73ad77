#include "hooke/sph/iisph.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "hooke/parallel/loops.hpp"

namespace hooke {

namespace {
constexpr long long kParallelParticles = 1024;
}  // namespace

OptionError IisphOptions::validate() const {
  if (!(tolerance > 0.0)) return option_error("tolerance", tolerance, "must be positive");
  if (min_iterations < 1) return option_error("min_iterations", min_iterations, "must be >= 1");
  if (max_iterations < min_iterations)
    return option_error("max_iterations", max_iterations,
                        "must be >= min_iterations (" + std::to_string(min_iterations) + ")");
  if (!(omega > 0.0 && omega <= 1.0)) return option_error("omega", omega, "must be in (0, 1]");
  if (!(max_density_error > 0.0))
    return option_error("max_density_error", max_density_error, "must be positive");
  if (!(courant >= 0.0) || !std::isfinite(courant))
    return option_error("courant", courant, "must be >= 0 (0: no CFL substeps)");
  return {};
}

namespace {
const IisphOptions& checked(const IisphOptions& o) {
  if (const OptionError e = o.validate(); !e.ok())
    throw std::invalid_argument("iisph: " + e.message);
  return o;
}
}  // namespace

IisphStepper::IisphStepper(const MassSpringSystem& system, Options options)
    : SphStepper(system, checked(options).courant), m_options(options) {
  const Index nf = m_fluid.num_fluid(), n = system.num_particles();
  m_v_adv = Vec::Zero(3 * n);
  m_ap = Vec::Zero(3 * n);
  m_source = m_diag = m_Ap = m_div = m_shepard = Vec::Zero(nf);
  m_d = m_wall_grad = Vec::Zero(3 * nf);
}

double IisphStepper::cfl_step(const State& s, double courant, double max_step) const {
  const double vmax = max_fluid_speed(s);
  return vmax > 0.0 ? std::min(max_step, courant * m_fluid.options().spacing / vmax) : max_step;
}

std::vector<double> IisphStepper::history() const {
  return std::vector<double>(m_p.data(), m_p.data() + m_p.size());
}

void IisphStepper::restore_history(const std::vector<double>& history) {
  HOOKE_ASSERT(Index(history.size()) == m_p.size(), "iisph history of "
                                                        << history.size() << " pressures for "
                                                        << m_p.size() << " fluid particles");
  m_p = Eigen::Map<const Vec>(history.data(), Index(history.size()));
}

void IisphStepper::compute_diagonal(ConstRef x, double h) {
  const Index nf = m_fluid.num_fluid();
  const Vec& masses = m_system.masses();
  const Vec& psi = m_fluid.boundary_psi();
  const double inv_rho0_2 = 1.0 / (m_fluid.rest_density() * m_fluid.rest_density());
  m_fluid.with_kernel([&](const auto& kernel) {
    // The walls push on i with p_i / rho_i^2 + p~_i / rho0^2 (FluidModel::
    // add_pressure_acceleration), p~_i = sum_j W_ij p_j / sum_j W_ij the Shepard average of the
    // pressures around i: per particle, the Shepard sum and beta_i = sum_b psi_b gradW_ib.
    parallel_for(nf, kParallelParticles, [&](long long i) {
      const Vec3 xi = x.segment<3>(3 * i);
      Vec3 fluid_grad = Vec3::Zero(), wall_grad = Vec3::Zero();
      double sum_w = kernel.W0();
      for (const int* it = m_search.begin(i); it != m_search.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - x.segment<3>(3 * j);
        const double r = xij.norm();
        if (j < nf) {
          fluid_grad += masses[j] * kernel.gradW(xij, r);
          sum_w += kernel.W(r);
        } else {
          wall_grad += psi[j - nf] * kernel.gradW(xij, r);
        }
      }
      const double inv_rho2 = 1.0 / (m_rho[i] * m_rho[i]);
      m_shepard[i] = sum_w;
      m_wall_grad.segment<3>(3 * i) = wall_grad;
      // d_ii: the pressure acceleration of particle i per unit of its own pressure.
      m_d.segment<3>(3 * i) =
          -inv_rho2 * fluid_grad - (inv_rho2 + kernel.W0() / sum_w * inv_rho0_2) * wall_grad;
    });
    // a_ii = h^2 [sum_j m_j (d_ii - d_ji) . gradW_ij + sum_b psi_b d_ii . gradW_ib], d_ji the
    // acceleration of j per unit pressure at i: m_i / rho_i^2 gradW_ij from the pair, and
    // -(W_ij / sum_k W_jk) / rho0^2 beta_j from the walls' pressure j sees.
    parallel_for(nf, kParallelParticles, [&](long long i) {
      const Vec3 xi = x.segment<3>(3 * i), d = m_d.segment<3>(3 * i);
      const double inv_rho2 = 1.0 / (m_rho[i] * m_rho[i]);
      double aii = 0.0;
      for (const int* it = m_search.begin(i); it != m_search.end(i); ++it) {
        const Index j = *it;
        const Vec3 xij = xi - x.segment<3>(3 * j);
        const double r = xij.norm();
        const Vec3 g = kernel.gradW(xij, r);
        if (j < nf) {
          const Vec3 dji = masses[i] * inv_rho2 * g -
                           kernel.W(r) / m_shepard[j] * inv_rho0_2 * m_wall_grad.segment<3>(3 * j);
          aii += masses[j] * (d - dji).dot(g);
        } else {
          aii += psi[j - nf] * d.dot(g);
        }
      }
      m_diag[i] = h * h * m_gradient_scale * aii;  // every d is a pressure acceleration
    });
    return 0;
  });
}

void IisphStepper::apply(ConstRef x, double h, ConstRef p) {
  m_ap.setZero();
  m_fluid.add_pressure_acceleration(m_search, x, m_system.masses(), m_rho, p, m_ap,
                                    m_gradient_scale);
  m_ap.array() *= m_moving.array();
  m_fluid.density_change(m_search, x, m_system.masses(), m_ap, m_div);
  m_Ap = h * h * m_div;
}

int IisphStepper::pressure_solve(ConstRef x, double h, Vec& p, double tolerance, double& error) {
  const Index nf = m_fluid.num_fluid();
  const double rho0 = m_fluid.rest_density(), omega = m_options.omega;
  int iterations = 0;
  while (true) {
    apply(x, h, p);
    // The residual of the complementarity problem, with (A p - s)_i = rho_i(p) - rho0: a particle
    // under pressure must reach rho0 (either sign counts), a particle at p = 0 may expand but not
    // be compressed. Counting compression alone would let the solve stop with pressures far from
    // the solution wherever they are too high (tests/sph/pressure_system_test.cpp).
    double sum = 0.0;
    for (Index i = 0; i < nf; ++i) {
      const double r = m_Ap[i] - m_source[i];
      sum += p[i] > 0.0 ? std::abs(r) : std::max(r, 0.0);
    }
    error = sum / (double(nf) * rho0);
    if (iterations >= m_options.min_iterations &&
        (error <= tolerance || iterations >= m_options.max_iterations))
      return iterations;
    for (Index i = 0; i < nf; ++i)
      p[i] = m_diag[i] != 0.0 ? std::max(0.0, p[i] + omega * (m_source[i] - m_Ap[i]) / m_diag[i])
                              : 0.0;
    ++iterations;
  }
}

IisphStepper::Solve IisphStepper::density_solve(const State& s0, double h) {
  m_v_adv = s0.v + h * m_a;
  m_fluid.density_change(m_search, s0.x, m_system.masses(), m_v_adv, m_div);
  m_source = (m_fluid.rest_density() - m_rho.array() - h * m_div.array()).matrix();
  m_p *= 0.5;  // warm start (Ihmsen et al. 2014, sec. 3.3)
  Solve solve{"density", 0, 0.0, m_options.tolerance};
  solve.iterations = pressure_solve(s0.x, h, m_p, solve.tolerance, solve.error);
  m_a += m_ap;
  return solve;
}

void IisphStepper::close_step(const State& s0, double h, State& s1,
                              std::initializer_list<Solve> solves, StepSummary& s) {
  finish_step(s0, h, s1, m_options.max_density_error, s);
  int iterations = 0;
  for (const Solve& solve : solves) {
    iterations += solve.iterations;
    if (s.status == Status::Converged && solve.error > solve.tolerance) {
      std::ostringstream os;
      os << name() << ": the " << solve.what << " solve stopped at max_iterations "
         << m_options.max_iterations << " with a mean " << solve.what << " error " << solve.error
         << " > tolerance " << solve.tolerance;
      s.status = Status::NotConverged;
      s.message = os.str();
    }
    if (solve.what == std::string("density")) m_last.pressure_residual = s.residual = solve.error;
  }
  m_last.pressure_iterations = iterations;
  m_stats.iterations += iterations;
  s.iterations = iterations;
}

StepSummary IisphStepper::substep(const State& s0, double h, State& s1) {
  const auto t0 = Clock::now();
  StepSummary s;
  if (!prepare(s0.x, s)) return s;
  compute_diagonal(s0.x, h);
  external_acceleration(s0.x, s0.v);
  close_step(s0, h, s1, {density_solve(s0, h)}, s);
  m_stats.total_seconds += seconds_since(t0);
  return s;
}

}  // namespace hooke
