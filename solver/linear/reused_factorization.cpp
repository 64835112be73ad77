#include "hooke/linear/cholmod/reused_factorization.hpp"

#include "hooke/linear/iterative_common.hpp"

namespace hooke {

using linear_detail::Clock;
using linear_detail::seconds_since;

ReusedFactorization::ReusedFactorization(std::unique_ptr<LinearSolver> direct)
    : m_direct(std::move(direct)) {}

LinearSummary ReusedFactorization::analyze(const SparseMatrix& A) {
  LinearSummary s = m_direct->analyze(A);
  const double c = m_direct->factor_cost_in_solves();
  m_factor_cost = c > 0.0 ? c : 50.0;
  m_fresh = false;
  m_factorizations = 0;
  return s;
}

LinearSummary ReusedFactorization::refresh() {
  HOOKE_ASSERT(m_A, "ReusedFactorization: refresh before setup");
  const auto t0 = Clock::now();
  LinearSummary s = m_direct->factor(*m_A);
  s.factor_seconds = seconds_since(t0);
  if (s.status == Status::Converged) {
    m_fresh = true;
    ++m_factorizations;
    m_cost_since = m_factor_cost;
    m_steps_since = 0;
  }
  return s;
}

LinearSummary ReusedFactorization::setup(const SparseMatrix& A) {
  m_A = &A;
  m_fresh = false;
  // Renewal rule: refactor once the last step cost more than the average per step since the last
  // factorization (so the average stops falling), or if there is none yet.
  const bool renew = m_factorizations == 0 ||
                     (m_steps_since > 0 && m_last_iterations > m_cost_since / m_steps_since);
  return renew ? refresh() : LinearSummary{};
}

Status ReusedFactorization::apply(ConstRef r, VecRef z) { return m_direct->solve(r, z, {}).status; }

void ReusedFactorization::solved(int iterations) {
  m_last_iterations = iterations;
  m_cost_since += iterations;
  ++m_steps_since;
}

}  // namespace hooke
