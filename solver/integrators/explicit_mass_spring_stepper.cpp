#include "hooke/integrators/explicit_mass_spring_stepper.hpp"

#include "hooke/integrators/step_controller.hpp"

namespace hooke {

ExplicitMassSpringStepper::ExplicitMassSpringStepper(const MassSpringSystem& system,
                                                     std::unique_ptr<ExplicitStepper> method)
    : m_ode(system), m_method(std::move(method)) {
  m_X0.setZero(m_ode.dimension());
  m_X1.setZero(m_ode.dimension());
  m_method->resize(m_ode.dimension());
  if (m_method->error_estimate_order() > 0) m_err.setZero(m_ode.dimension());
}

StepSummary ExplicitMassSpringStepper::step(const State& s0, double h, State& s1) {
  const Index n3 = m_ode.position_dimension();
  HOOKE_ASSERT(s0.x.size() == n3 && s0.v.size() == n3,
               "state has " << s0.x.size() << " positions for " << n3 << " dofs");
  m_X0.head(n3) = s0.x;
  m_X0.tail(n3) = s0.v;
  m_method->step(m_ode, s0.t, h, m_X0, m_X1);
  s1.x = m_X1.head(n3);
  s1.v = m_X1.tail(n3);
  s1.t = s0.t + h;
  return {};
}

double ExplicitMassSpringStepper::error_norm(double rtol, double atol) {
  HOOKE_ASSERT(m_err.size() == m_X0.size(), name() << " makes no local error estimate");
  m_method->error_estimate(m_err);
  return wrms_norm(m_err, m_X0, m_X1, rtol, atol);
}

}  // namespace hooke
