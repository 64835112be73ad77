#pragma once
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/ode_system.hpp"

namespace hooke {

/// A mass-spring system seen as the first-order ODE X = [x; v], X' = [v; M^-1 f(x, v)], partitioned
/// with q = x. Pinned particles have zero velocity derivative and zero acceleration; scripted pins
/// move with their velocity and have their prescribed acceleration (PinMotion).
/// Holds a reference to the system, which must outlive it, and its own force scratch.
class MassSpringOde final : public OdeSystem {
 public:
  explicit MassSpringOde(const MassSpringSystem& system);
  Index dimension() const override { return 2 * m_system.dofs(); }
  Index position_dimension() const override { return m_system.dofs(); }
  void rhs(double t, ConstRef X, VecRef dXdt) override;
  void rhs_position(double t, ConstRef X, VecRef dqdt, VecRef scratch) override;
  const MassSpringSystem& system() const { return m_system; }

 private:
  const MassSpringSystem& m_system;
  Vec m_f;  // 3n force scratch
};

}  // namespace hooke
