#pragma once
#include <memory>
#include <vector>

#include "hooke/core.hpp"
#include "hooke/model/ode_system.hpp"

namespace hooke {

/// A one-step explicit method for X' = F(t, X). Stage workspace is sized once by resize() (or
/// lazily on the first step of a new dimension) and reused, so steps do not allocate.
class ExplicitStepper {
 public:
  virtual ~ExplicitStepper() = default;
  /// Registry name ("forward-euler", "rk4", ...).
  virtual const char* name() const = 0;
  /// Allocates stage storage for systems of dimension dim.
  virtual void resize(Index dim) = 0;
  /// X1 = one step of size h from (t, X0). X0 and X1 must not alias.
  virtual void step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) = 0;
};

/// An explicit Runge-Kutta method given by its Butcher tableau (a strictly lower triangular,
/// weights b, nodes c): k_s = F(t + c_s h, X0 + h sum_{j<s} a_sj k_j), X1 = X0 + h sum_s b_s k_s.
class ExplicitRungeKutta final : public ExplicitStepper {
 public:
  ExplicitRungeKutta(const char* name, std::vector<std::vector<double>> a, std::vector<double> b,
                     std::vector<double> c);
  /// Forward Euler (1 stage, order 1).
  static std::unique_ptr<ExplicitRungeKutta> forward_euler();
  /// Explicit midpoint (2 stages, order 2).
  static std::unique_ptr<ExplicitRungeKutta> midpoint();
  /// Explicit trapezoid / Heun's method (2 stages, order 2).
  static std::unique_ptr<ExplicitRungeKutta> trapezoid();
  /// Classical fourth-order Runge-Kutta (4 stages, order 4).
  static std::unique_ptr<ExplicitRungeKutta> rk4();

  const char* name() const override { return m_name; }
  void resize(Index dim) override;
  void step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) override;
  int stages() const { return static_cast<int>(m_b.size()); }

 private:
  const char* m_name;
  std::vector<std::vector<double>> m_a;
  std::vector<double> m_b, m_c;
  std::vector<Vec> m_k;  // stage derivatives
  Vec m_stage;           // stage argument
};

/// Symplectic (semi-implicit) Euler for partitioned systems X = [q; p]: p1 = p0 + h F_p(t, q0, p0),
/// then q1 = q0 + h F_q(t, q0, p1). For a mass-spring system (q = x, p = v) this is
/// v1 = v0 + h M^-1 f(x0, v0), x1 = x0 + h v1. For an unpartitioned system it is forward Euler.
class SymplecticEuler final : public ExplicitStepper {
 public:
  const char* name() const override { return "symplectic-euler"; }
  void resize(Index dim) override;
  void step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) override;

 private:
  Vec m_k, m_mixed;
};

}  // namespace hooke
