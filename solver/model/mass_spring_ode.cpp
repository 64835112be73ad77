#include "hooke/model/mass_spring_ode.hpp"

namespace hooke {

MassSpringOde::MassSpringOde(const MassSpringSystem& system)
    : m_system(system), m_f(Vec::Zero(system.dofs())) {
  m_free.resize(system.dofs());
  for (Index i = 0; i < system.num_particles(); ++i)
    m_free.segment<3>(3 * i).setConstant(system.pinned()[i] ? 0.0 : 1.0);
}

void MassSpringOde::rhs(double /*t*/, ConstRef X, VecRef dXdt) {
  const Index n3 = m_system.dofs();
  HOOKE_ASSERT(X.size() == 2 * n3 && dXdt.size() == 2 * n3, "MassSpringOde: size mismatch");
  m_system.compute_forces(X.head(n3), X.tail(n3), m_f);
  dXdt.head(n3) = X.tail(n3).cwiseProduct(m_free);
  dXdt.tail(n3) = m_f.cwiseProduct(m_system.free_inverse_mass());
}

void MassSpringOde::rhs_position(double /*t*/, ConstRef X, VecRef dqdt, VecRef /*scratch*/) {
  const Index n3 = m_system.dofs();
  dqdt = X.tail(n3).cwiseProduct(m_free);
}

}  // namespace hooke
