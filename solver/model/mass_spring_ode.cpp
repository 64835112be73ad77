#include "hooke/model/mass_spring_ode.hpp"

#include "hooke/parallel/loops.hpp"

namespace hooke {

MassSpringOde::MassSpringOde(const MassSpringSystem& system)
    : m_system(system), m_f(Vec::Zero(system.dofs())) {}

void MassSpringOde::rhs(double t, ConstRef X, VecRef dXdt) {
  const Index n3 = m_system.dofs();
  HOOKE_ASSERT(X.size() == 2 * n3 && dXdt.size() == 2 * n3, "MassSpringOde: size mismatch");
  m_system.compute_forces(X.head(n3), X.tail(n3), m_f);
  const Vec &moving = m_system.moving(), &inv_mass = m_system.free_inverse_mass();
  parallel_ranges(n3, [&](long long b, long long e) {
    dXdt.segment(b, e - b) = X.segment(n3 + b, e - b).cwiseProduct(moving.segment(b, e - b));
    dXdt.segment(n3 + b, e - b) = m_f.segment(b, e - b).cwiseProduct(inv_mass.segment(b, e - b));
  });
  if (m_system.has_pin_motion()) m_system.pin_motion().accelerate(t, dXdt.tail(n3));
}

void MassSpringOde::rhs_position(double /*t*/, ConstRef X, VecRef dqdt, VecRef /*scratch*/) {
  const Index n3 = m_system.dofs();
  const Vec& moving = m_system.moving();
  parallel_ranges(n3, [&](long long b, long long e) {
    dqdt.segment(b, e - b) = X.segment(n3 + b, e - b).cwiseProduct(moving.segment(b, e - b));
  });
}

}  // namespace hooke
