#pragma once
#include "hooke/model/ode_system.hpp"

namespace hooke {

/// The scalar test equation x' = -rate * x (Dahlquist), exact solution x0 * exp(-rate t).
class DecayOde final : public OdeSystem {
 public:
  explicit DecayOde(double rate) : m_rate(rate) {}
  Index dimension() const override { return 1; }
  void rhs(double, ConstRef X, VecRef dXdt) override { dXdt[0] = -m_rate * X[0]; }
  double rate() const { return m_rate; }

 private:
  double m_rate;
};

/// The circle field (x, y)' = (-y, x): rotation at unit angular speed, partitioned as q = x,
/// p = y; exact solution rotates X0 by angle t.
class CircleOde final : public OdeSystem {
 public:
  Index dimension() const override { return 2; }
  Index position_dimension() const override { return 1; }
  void rhs(double, ConstRef X, VecRef dXdt) override {
    dXdt[0] = -X[1];
    dXdt[1] = X[0];
  }
};

}  // namespace hooke
