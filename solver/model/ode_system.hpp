#pragma once
#include "hooke/core.hpp"

namespace hooke {

/// A first-order ODE X' = F(t, X). Every explicit stepper works on this interface alone, so the
/// scalar test equation, the circle field and a cloth run through the same code.
///
/// Partitioned systems (X = [q; p] with q' = F_q, p' = F_p, e.g. positions and velocities) report
/// the size of q through position_dimension(); methods that need the split (symplectic Euler)
/// update p first from the old state, then q from (q0, p1). An unpartitioned system returns 0,
/// and such methods then reduce to their explicit base method.
class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  /// Number of unknowns of X.
  virtual Index dimension() const = 0;
  /// Size of the leading "position" block q (0 = not partitioned).
  virtual Index position_dimension() const { return 0; }
  /// Evaluates dXdt = F(t, X). X and dXdt have dimension() entries and do not alias.
  /// Non-const because implementations may use internal scratch; must not allocate.
  virtual void rhs(double t, ConstRef X, VecRef dXdt) = 0;
  /// Evaluates only the position block dq/dt = F_q(t, X) (position_dimension() entries). The
  /// default evaluates the whole rhs into `scratch` (dimension() entries) and copies its head;
  /// partitioned systems whose F_q is cheap (x' = v) override it.
  virtual void rhs_position(double t, ConstRef X, VecRef dqdt, VecRef scratch) {
    rhs(t, X, scratch);
    dqdt = scratch.head(position_dimension());
  }
};

}  // namespace hooke
