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
  /// Order q of the embedded local error estimate (error O(h^(q+1))); 0: the method has none.
  virtual int error_estimate_order() const { return 0; }
  /// err = the local error estimate of the last step (methods with error_estimate_order() > 0).
  virtual void error_estimate(VecRef err) const;
};

/// An explicit Runge-Kutta method given by its Butcher tableau (a strictly lower triangular,
/// weights b, nodes c): k_s = F(t + c_s h, X0 + h sum_{j<s} a_sj k_j), X1 = X0 + h sum_s b_s k_s.
///
/// An embedded pair also has weights b_hat of a lower order q: X1 - X1_hat = h sum_s (b_s -
/// b_hat_s) k_s estimates the local error of the order-q solution (the step keeps the higher-order
/// X1: local extrapolation, as in Dormand and Prince). When the last stage is evaluated at X1
/// itself (first same as last: its row of a is b and c = 1), the next step reuses it as its first
/// stage, provided that step starts from exactly that state and time (a constraint that moved a
/// particle in between makes it evaluate the stage again).
class ExplicitRungeKutta final : public ExplicitStepper {
 public:
  ExplicitRungeKutta(const char* name, std::vector<std::vector<double>> a, std::vector<double> b,
                     std::vector<double> c, std::vector<double> b_hat = {}, int estimate_order = 0);
  /// Forward Euler (1 stage, order 1).
  static std::unique_ptr<ExplicitRungeKutta> forward_euler();
  /// Explicit midpoint (2 stages, order 2).
  static std::unique_ptr<ExplicitRungeKutta> midpoint();
  /// Explicit trapezoid / Heun's method (2 stages, order 2).
  static std::unique_ptr<ExplicitRungeKutta> trapezoid();
  /// Classical fourth-order Runge-Kutta (4 stages, order 4).
  static std::unique_ptr<ExplicitRungeKutta> rk4();
  /// Dormand-Prince 5(4) (Dormand and Prince 1980; the pair of MATLAB's ode45 and scipy's RK45):
  /// 7 stages, 6 per step with the first-same-as-last reuse; order 5, error estimate of order 4.
  static std::unique_ptr<ExplicitRungeKutta> dopri5();
  /// Bogacki-Shampine 3(2) (1989; MATLAB's ode23, scipy's RK23): 4 stages, 3 per step with the
  /// reuse; order 3, error estimate of order 2.
  static std::unique_ptr<ExplicitRungeKutta> bs32();

  const char* name() const override { return m_name; }
  void resize(Index dim) override;
  void step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) override;
  int stages() const { return static_cast<int>(m_b.size()); }
  /// True for an embedded pair (error_estimate() is available).
  bool embedded() const { return !m_e.empty(); }
  int error_estimate_order() const override { return m_estimate_order; }
  /// True when the last stage is the next step's first (see the class comment).
  bool first_same_as_last() const { return m_fsal; }
  /// Right-hand-side evaluations so far (what a reused first stage saves).
  long long evaluations() const { return m_evaluations; }
  /// err = X1 - X1_hat of the last step (its h): the local error estimate of the embedded
  /// lower-order solution. Embedded pairs only; err has the system's dimension.
  void error_estimate(VecRef err) const override;

 private:
  const char* m_name;
  std::vector<std::vector<double>> m_a;
  std::vector<double> m_b, m_c;
  std::vector<double> m_e;  // b - b_hat (empty: no embedded pair)
  int m_estimate_order = 0;
  bool m_fsal = false;
  std::vector<Vec> m_k;  // stage derivatives
  Vec m_stage;           // stage argument; after a first-same-as-last step, X1 itself
  // The last step of a first-same-as-last method: its h, and whether m_k.back() holds F at
  // (m_last_t1, m_stage), the next step's first stage if it starts there.
  double m_last_h = 0.0, m_last_t1 = 0.0;
  bool m_last_valid = false;
  long long m_evaluations = 0;
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
