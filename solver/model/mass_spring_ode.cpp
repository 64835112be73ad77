#include "hooke/model/mass_spring_ode.hpp"

namespace hooke {

MassSpringOde::MassSpringOde(const MassSpringSystem& system)
    : m_system(system), m_f(Vec::Zero(system.dofs())) {}

void MassSpringOde::rhs(double t, ConstRef X, VecRef dXdt) {
  const Index n3 = m_system.dofs();
  HOOKE_ASSERT(X.size() == 2 * n3 && dXdt.size() == 2 * n3, "MassSpringOde: size mismatch");
  m_system.compute_forces(X.head(n3), X.tail(n3), m_f);
  dXdt.head(n3) = X.tail(n3).cwiseProduct(m_system.moving());
  dXdt.tail(n3) = m_f.cwiseProduct(m_system.free_inverse_mass());
  if (m_system.has_pin_motion()) m_system.pin_motion().accelerate(t, dXdt.tail(n3));
}

void MassSpringOde::rhs_position(double /*t*/, ConstRef X, VecRef dqdt, VecRef /*scratch*/) {
  const Index n3 = m_system.dofs();
  dqdt = X.tail(n3).cwiseProduct(m_system.moving());
}

}  // namespace hooke
