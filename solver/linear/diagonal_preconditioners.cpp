#include "hooke/linear/diagonal_preconditioners.hpp"

#include <cmath>

#include "hooke/linear/iterative_common.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {

using linear_detail::Clock;
using linear_detail::seconds_since;

LinearSummary JacobiPreconditioner::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  m_diag_pos = linear_detail::diagonal_positions(A);
  m_inv_diag.setZero(A.rows());
  LinearSummary s;
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary JacobiPreconditioner::setup(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  for (Index i = 0; i < A.rows(); ++i) {
    const double d = A.valuePtr()[m_diag_pos[size_t(i)]];
    if (!(d > 0.0) || !std::isfinite(d)) {
      s.status = Status::BrokeDown;
      s.not_positive_definite = true;
      s.message = "diagonal entry " + std::to_string(i) + " = " + std::to_string(d) +
                  " is not positive: A is not positive definite";
      return s;
    }
    m_inv_diag[i] = 1.0 / d;
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

Status JacobiPreconditioner::apply(ConstRef r, VecRef z) {
  z = m_inv_diag.cwiseProduct(r);
  return Status::Converged;
}

LinearSummary BlockJacobiPreconditioner::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  m_block_pos = linear_detail::block_diagonal_positions(A);
  LinearSummary s;
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary BlockJacobiPreconditioner::setup(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  const Index bad = linear_detail::invert_diagonal_blocks(A, m_block_pos, true, m_inv_blocks);
  if (bad >= 0) {
    s.status = Status::BrokeDown;
    s.not_positive_definite = true;
    s.message = "diagonal block " + std::to_string(bad) +
                " is not positive definite: A is not positive definite";
    return s;
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

Status BlockJacobiPreconditioner::apply(ConstRef r, VecRef z) {
  const Index nb = r.size() / 3;
  parallel_for(nb, 4096, [&](long long b) {
    z.segment<3>(3 * b) = m_inv_blocks[size_t(b)] * r.segment<3>(3 * b);
  });
  return Status::Converged;
}

}  // namespace hooke
