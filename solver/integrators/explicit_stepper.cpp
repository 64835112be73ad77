#include "hooke/integrators/explicit_stepper.hpp"

#include <algorithm>

#include "hooke/parallel/loops.hpp"

namespace hooke {

ExplicitRungeKutta::ExplicitRungeKutta(const char* name, std::vector<std::vector<double>> a,
                                       std::vector<double> b, std::vector<double> c,
                                       std::vector<double> b_hat, int estimate_order)
    : m_name(name),
      m_a(std::move(a)),
      m_b(std::move(b)),
      m_c(std::move(c)),
      m_estimate_order(estimate_order) {
  const size_t S = m_b.size();
  HOOKE_ASSERT(S > 0 && m_a.size() == S && m_c.size() == S, "tableau sizes differ");
  for (size_t s = 0; s < S; ++s)
    HOOKE_ASSERT(m_a[s].size() == s, "tableau row " << s << " must have " << s << " entries");
  if (!b_hat.empty()) {
    HOOKE_ASSERT(b_hat.size() == S,
                 "embedded weights: " << b_hat.size() << " for " << S << " stages");
    for (size_t s = 0; s < S; ++s) m_e.push_back(m_b[s] - b_hat[s]);
  }
  HOOKE_ASSERT(
      b_hat.empty() == (estimate_order == 0),
      name << ": an embedded pair needs the order of its estimate, and only a pair has one");
  // First same as last: the last stage is evaluated at X1 (its row is b, b_last = 0, c_last = 1).
  m_fsal = S > 1 && m_b[S - 1] == 0.0 && m_c[S - 1] == 1.0;
  for (size_t j = 0; m_fsal && j + 1 < S; ++j) m_fsal = m_a[S - 1][j] == m_b[j];
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

// Dormand, J. R. and Prince, P. J. (1980), "A family of embedded Runge-Kutta formulae",
// J. Comput. Appl. Math. 6(1), 19-26: the coefficients of their RK5(4)7M.
std::unique_ptr<ExplicitRungeKutta> ExplicitRungeKutta::dopri5() {
  return std::make_unique<ExplicitRungeKutta>(
      "dopri5",
      std::vector<std::vector<double>>{
          {},
          {1.0 / 5.0},
          {3.0 / 40.0, 9.0 / 40.0},
          {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
          {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
          {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0},
          {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0}},
      std::vector<double>{35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
                          11.0 / 84.0, 0.0},
      std::vector<double>{0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0},
      std::vector<double>{5179.0 / 57600.0, 0.0, 7571.0 / 16695.0, 393.0 / 640.0,
                          -92097.0 / 339200.0, 187.0 / 2100.0, 1.0 / 40.0},
      4);
}

// Bogacki, P. and Shampine, L. F. (1989), "A 3(2) pair of Runge-Kutta formulas", Appl. Math.
// Lett. 2(4), 321-325.
std::unique_ptr<ExplicitRungeKutta> ExplicitRungeKutta::bs32() {
  return std::make_unique<ExplicitRungeKutta>(
      "bs32",
      std::vector<std::vector<double>>{
          {}, {1.0 / 2.0}, {0.0, 3.0 / 4.0}, {2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0}},
      std::vector<double>{2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0, 0.0},
      std::vector<double>{0.0, 1.0 / 2.0, 3.0 / 4.0, 1.0},
      std::vector<double>{7.0 / 24.0, 1.0 / 4.0, 1.0 / 3.0, 1.0 / 8.0}, 2);
}

void ExplicitRungeKutta::resize(Index dim) {
  m_k.assign(m_b.size(), Vec::Zero(dim));
  m_stage.setZero(dim);
  m_last_valid = false;
}

void ExplicitRungeKutta::step(OdeSystem& ode, double t, double h, ConstRef X0, VecRef X1) {
  const Index dim = ode.dimension();
  HOOKE_ASSERT(X0.size() == dim && X1.size() == dim, name()
                                                         << ": state sizes " << X0.size() << ", "
                                                         << X1.size() << " for dimension " << dim);
  if (m_stage.size() != dim) resize(dim);
  const size_t S = m_b.size();
  // The first stage is the last step's last one when this step starts where that one ended
  // (same time, same bits: nothing moved the state in between).
  if (m_fsal && m_last_valid && t == m_last_t1 && X0 == m_stage) {
    std::swap(m_k[0], m_k[S - 1]);
  } else {
    ode.rhs(t + m_c[0] * h, X0, m_k[0]);
    ++m_evaluations;
  }
  m_last_valid = false;
  // Stage arguments and the result are sums in a fixed order per entry, formed over blocks in
  // parallel (parallel_ranges: the same bits on any thread count).
  for (size_t s = 1; s < S; ++s) {
    parallel_ranges(dim, [&](long long b, long long e) {
      auto stage = m_stage.segment(b, e - b);
      stage = X0.segment(b, e - b);
      for (size_t j = 0; j < s; ++j)
        if (m_a[s][j] != 0.0) stage.noalias() += (h * m_a[s][j]) * m_k[j].segment(b, e - b);
    });
    ode.rhs(t + m_c[s] * h, m_stage, m_k[s]);
    ++m_evaluations;
  }
  m_last_h = h;
  if (m_fsal) {
    // The last stage's argument is X1, summed in the same order as below would.
    parallel_ranges(
        dim, [&](long long b, long long e) { X1.segment(b, e - b) = m_stage.segment(b, e - b); });
    m_last_t1 = t + m_c[S - 1] * h;
    m_last_valid = true;
    return;
  }
  parallel_ranges(dim, [&](long long b, long long e) {
    auto x1 = X1.segment(b, e - b);
    x1 = X0.segment(b, e - b);
    for (size_t s = 0; s < S; ++s)
      if (m_b[s] != 0.0) x1.noalias() += (h * m_b[s]) * m_k[s].segment(b, e - b);
  });
}

void ExplicitStepper::error_estimate(VecRef) const {
  HOOKE_ASSERT(false, name() << " has no embedded error estimate");
}

void ExplicitRungeKutta::error_estimate(VecRef err) const {
  HOOKE_ASSERT(embedded(), name() << " has no embedded error estimate");
  HOOKE_ASSERT(err.size() == m_stage.size(),
               "error estimate of size " << err.size() << " for " << m_stage.size());
  err.setZero();
  for (size_t s = 0; s < m_e.size(); ++s)
    if (m_e[s] != 0.0) err.noalias() += (m_last_h * m_e[s]) * m_k[s];
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
  // p1 = p0 + h F_p(t, q0, p0). The element-wise updates run over blocks in parallel
  // (parallel_ranges: the same bits on any thread count).
  ode.rhs(t, X0, m_k);
  parallel_ranges(np, [&](long long b, long long e) {
    X1.segment(nq + b, e - b) = X0.segment(nq + b, e - b) + h * m_k.segment(nq + b, e - b);
  });
  if (nq == 0) return;
  // q1 = q0 + h F_q(t, q0, p1)
  parallel_ranges(dim, [&](long long b, long long e) {
    const long long split = std::clamp<long long>(nq, b, e);  // [b, split) positions, the rest p1
    m_mixed.segment(b, split - b) = X0.segment(b, split - b);
    m_mixed.segment(split, e - split) = X1.segment(split, e - split);
  });
  ode.rhs_position(t, m_mixed, X1.head(nq), m_k);
  parallel_ranges(nq, [&](long long b, long long e) {
    X1.segment(b, e - b) = X0.segment(b, e - b) + h * X1.segment(b, e - b);
  });
}

}  // namespace hooke
