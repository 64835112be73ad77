#include "hooke/sph/wcsph.hpp"

#include <cmath>
#include <stdexcept>

namespace hooke {

OptionError WcsphOptions::validate() const {
  if (!(sound_speed > 0.0) || !std::isfinite(sound_speed))
    return option_error("sound_speed", sound_speed, "must be positive (m/s)");
  if (!(gamma >= 1.0) || !std::isfinite(gamma)) return option_error("gamma", gamma, "must be >= 1");
  if (!(max_density_error > 0.0))
    return option_error("max_density_error", max_density_error, "must be positive");
  if (!(courant >= 0.0) || !std::isfinite(courant))
    return option_error("courant", courant, "must be >= 0 (0: no CFL substeps)");
  return {};
}

namespace {
const WcsphOptions& checked(const WcsphOptions& o) {
  if (const OptionError e = o.validate(); !e.ok())
    throw std::invalid_argument("wcsph: " + e.message);
  return o;
}
}  // namespace

WcsphStepper::WcsphStepper(const MassSpringSystem& system, Options options)
    : SphStepper(system, checked(options).courant), m_options(options) {
  m_B = m_fluid.rest_density() * m_options.sound_speed * m_options.sound_speed / m_options.gamma;
}

double WcsphStepper::cfl_step(const State& s, double courant) const {
  return courant * m_fluid.options().spacing / (m_options.sound_speed + max_fluid_speed(s));
}

StepSummary WcsphStepper::substep(const State& s0, double h, State& s1) {
  const auto t0 = Clock::now();
  StepSummary s;
  if (!prepare(s0.x, s)) return s;
  const double inv_rho0 = 1.0 / m_fluid.rest_density(), gamma = m_options.gamma;
  for (Index i = 0; i < m_fluid.num_fluid(); ++i)
    m_p[i] = std::max(0.0, m_B * (std::pow(m_rho[i] * inv_rho0, gamma) - 1.0));
  external_acceleration(s0.x, s0.v);
  m_fluid.add_pressure_acceleration(m_search, s0.x, m_system.masses(), m_rho, m_p, m_a,
                                    m_gradient_scale);
  mask_acceleration();
  finish_step(s0, h, s1, m_options.max_density_error, s);
  s.residual = m_last.max_density_error;
  m_stats.total_seconds += seconds_since(t0);
  return s;
}

}  // namespace hooke
