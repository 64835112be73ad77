#include "hooke/sph/dfsph.hpp"

#include <stdexcept>

namespace hooke {

OptionError DfsphOptions::validate() const {
  if (const OptionError e = IisphOptions::validate(); !e.ok()) return e;
  if (!(divergence_tolerance > 0.0))
    return option_error("divergence_tolerance", divergence_tolerance, "must be positive");
  return {};
}

namespace {
const DfsphOptions& checked(const DfsphOptions& o) {
  if (const OptionError e = o.validate(); !e.ok())
    throw std::invalid_argument("dfsph: " + e.message);
  return o;
}
}  // namespace

DfsphStepper::DfsphStepper(const MassSpringSystem& system, Options options)
    : IisphStepper(system, checked(options)), m_divergence_tolerance(options.divergence_tolerance) {
  const Index nf = m_fluid.num_fluid(), n = system.num_particles();
  m_p_div = Vec::Zero(nf);
  m_a_div = m_v_div = Vec::Zero(3 * n);
}

std::vector<double> DfsphStepper::history() const {
  std::vector<double> h(m_p.data(), m_p.data() + m_p.size());
  h.insert(h.end(), m_p_div.data(), m_p_div.data() + m_p_div.size());
  return h;
}

void DfsphStepper::restore_history(const std::vector<double>& history) {
  const Index nf = m_p.size();
  HOOKE_ASSERT(Index(history.size()) == 2 * nf, "dfsph history of " << history.size()
                                                                    << " pressures for 2 x " << nf
                                                                    << " fluid particles");
  m_p = Eigen::Map<const Vec>(history.data(), nf);
  m_p_div = Eigen::Map<const Vec>(history.data() + nf, nf);
}

StepSummary DfsphStepper::substep(const State& s0, double h, State& s1) {
  const auto t0 = Clock::now();
  StepSummary s;
  if (!prepare(s0.x, s)) return s;
  compute_diagonal(s0.x, h);
  // The divergence solve: cancel the density change the velocities v0 would make in h.
  m_fluid.density_change(m_search, s0.x, m_system.masses(), s0.v, m_div);
  m_source = -h * m_div;
  m_p_div *= 0.5;
  Solve divergence{"divergence", 0, 0.0, m_divergence_tolerance};
  divergence.iterations = pressure_solve(s0.x, h, m_p_div, divergence.tolerance, divergence.error);
  m_divergence_iterations = divergence.iterations;
  m_a_div = m_ap;
  m_v_div = s0.v + h * m_a_div;
  // Then IISPH from the divergence-free velocities (v* = v0 + h (a(p_v) + the rest)).
  external_acceleration(s0.x, m_v_div);
  m_a += m_a_div;
  const Solve density = density_solve(s0, h);
  close_step(s0, h, s1, {density, divergence}, s);
  m_stats.total_seconds += seconds_since(t0);
  return s;
}

}  // namespace hooke
