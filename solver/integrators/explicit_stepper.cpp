#include "hooke/integrators/explicit_stepper.hpp"

namespace hooke {

ExplicitRungeKutta::ExplicitRungeKutta(const char* name, std::vector<std::vector<double>> a,
                                       std::vector<double> b, std::vector<double> c)
    : m_name(name), m_a(std::move(a)), m_b(std::move(b)), m_c(std::move(c)) {
  HOOKE_ASSERT(m_a.size() == m_b.size() && m_c.size() == m_b.size(), "tableau sizes differ");
  for (size_t s = 0; s < m_a.size(); ++s)
    HOOKE_ASSERT(m_a[s].size() == s, "tableau row " << s << " must have " << s << " entries");
}

std::unique_ptr<ExplicitRungeKutta> ExplicitRungeKutta::forward_euler() {
  return std::make_unique<ExplicitRungeKutta>("forward-euler", std::vector<std::vector<double>>{{}},
                                              std::vector<double>{1.0}, std::vector<double>{0.0});
}

std::unique_ptr<ExplicitRungeKutta> ExplicitRungeKutta::midpoint() {
  return std::make_unique<ExplicitRungeKutta>(
      "midpoint", std::vector<std::vector<double>>{{}, {0.5}}, std::vector<double>{0.0, 1.0},
      std::vector<double>{0.0, 0.5});
}

std::unique_ptr<ExplicitRungeKutta> ExplicitRungeKutta::trapezoid() {
  return std::make_unique<ExplicitRungeKutta>(
      "trapezoid", std::vector<std::vector<double>>{{}, {1.0}}, std::vector<double>{0.5, 0.5},
      std::vector<double>{0.0, 1.0});
}

std::unique_ptr<ExplicitRungeKutta> ExplicitRungeKutta::rk4() {
  return std::make_unique<ExplicitRungeKutta>(
      "rk4", std::vector<std::vector<double>>{{}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
      std::vector<double>{1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0},
      std::vector<double>{0.0, 0.5, 0.5, 1.0});
}

void ExplicitRungeKutta::resize(Index dim) {
  m_k.assign(m_b.size(), Vec::Zero(dim));
  m_stage.setZero(dim);
}

void ExplicitRungeKutta::step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) {
  const Index dim = ode.dimension();
  HOOKE_ASSERT(X0.size() == dim && X1.size() == dim, name()
                                                         << ": state sizes " << X0.size() << ", "
                                                         << X1.size() << " for dimension " << dim);
  if (m_stage.size() != dim) resize(dim);
  for (size_t s = 0; s < m_b.size(); ++s) {
    if (s == 0) {
      ode.rhs(t + m_c[0] * h, X0, m_k[0]);
      continue;
    }
    m_stage = X0;
    for (size_t j = 0; j < s; ++j)
      if (m_a[s][j] != 0.0) m_stage.noalias() += (h * m_a[s][j]) * m_k[j];
    ode.rhs(t + m_c[s] * h, m_stage, m_k[s]);
  }
  X1 = X0;
  for (size_t s = 0; s < m_b.size(); ++s)
    if (m_b[s] != 0.0) X1.noalias() += (h * m_b[s]) * m_k[s];
}

void SymplecticEuler::resize(Index dim) {
  m_k.setZero(dim);
  m_mixed.setZero(dim);
}

void SymplecticEuler::step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) {
  const Index dim = ode.dimension();
  const Index nq = ode.position_dimension();
  HOOKE_ASSERT(X0.size() == dim && X1.size() == dim, "symplectic-euler: state size mismatch");
  HOOKE_ASSERT(nq >= 0 && nq <= dim, "position_dimension " << nq << " outside [0, " << dim << "]");
  if (m_k.size() != dim) resize(dim);
  const Index np = dim - nq;
  // p1 = p0 + h F_p(t, q0, p0)
  ode.rhs(t, X0, m_k);
  X1.tail(np) = X0.tail(np) + h * m_k.tail(np);
  if (nq == 0) return;
  // q1 = q0 + h F_q(t, q0, p1)
  m_mixed.head(nq) = X0.head(nq);
  m_mixed.tail(np) = X1.tail(np);
  ode.rhs_position(t, m_mixed, X1.head(nq), m_k);
  X1.head(nq) = X0.head(nq) + h * X1.head(nq);
}

}  // namespace hooke
