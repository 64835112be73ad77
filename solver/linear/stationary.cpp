#include "hooke/linear/stationary.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hooke/parallel/loops.hpp"

namespace hooke {

using linear_detail::Clock;
using linear_detail::seconds_since;

LinearSummary StationarySolver::solve(ConstRef b, VecRef x, const LinearSolveOptions& options) {
  const auto t0 = Clock::now();
  LinearSummary s;
  const double bnorm = linear_detail::begin_solve(name(), m_A, b, x, options, t0, s);
  if (bnorm == 0.0) return s;
  m_r.noalias() = (*m_A) * x;
  m_r = b - m_r;
  const double r0 = m_r.norm() / bnorm;
  double res = r0;
  int it = 0;
  while (res > options.tolerance && it < options.max_iterations) {
    sweep(b, x);
    ++it;
    m_r.noalias() = (*m_A) * x;
    m_r = b - m_r;
    res = m_r.norm() / bnorm;
    if (!std::isfinite(res) || res > 1e6 * std::max(r0, 1.0)) break;
  }
  s.iterations = it;
  s.residual = res;
  s.solve_seconds = seconds_since(t0);
  if (!(res <= options.tolerance)) {
    std::ostringstream os;
    os << name() << ": relative residual " << res << " after " << it << " iterations (tolerance "
       << options.tolerance << ", initial " << r0 << ")";
    const bool diverged = !std::isfinite(res) || res > 1e6 * std::max(r0, 1.0);
    if (diverged)
      os << ": the iteration diverges (its iteration matrix has spectral radius > 1 for this A)";
    s.status = diverged ? Status::BrokeDown : Status::NotConverged;
    s.message = os.str();
  }
  return s;
}

// ---- Jacobi ----

LinearSummary JacobiSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  HOOKE_ASSERT(A.rows() % 3 == 0, "jacobi (3x3 block) needs a 3n x 3n matrix");
  m_block_pos = linear_detail::block_diagonal_positions(A);
  m_r.setZero(A.rows());
  LinearSummary s;
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary JacobiSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  m_A = &A;
  const Index bad = linear_detail::invert_diagonal_blocks(A, m_block_pos, false, m_inv_blocks);
  if (bad >= 0) {
    s.status = Status::BrokeDown;
    s.message = "jacobi: diagonal block " + std::to_string(bad) + " is singular";
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

void JacobiSolver::sweep(ConstRef /*b*/, VecRef x) {
  // m_r holds b - A x from the residual check of the previous iteration.
  const Index nb = x.size() / 3;
  parallel_for(nb, 4096, [&](long long i) {
    x.segment<3>(3 * i) += m_inv_blocks[size_t(i)] * m_r.segment<3>(3 * i);
  });
}

// ---- Gauss-Seidel ----

LinearSummary GaussSeidelSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  m_csr.build(A);
  m_diag_pos = linear_detail::diagonal_positions(A);
  m_r.setZero(A.rows());
  LinearSummary s;
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary GaussSeidelSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  m_A = &A;
  m_csr.refresh(A);
  for (size_t r = 0; r < m_diag_pos.size(); ++r) {
    const double d = A.valuePtr()[m_diag_pos[r]];
    if (d == 0.0 || !std::isfinite(d)) {
      s.status = Status::BrokeDown;
      s.message = "gauss-seidel: diagonal entry " + std::to_string(r) + " is " + std::to_string(d);
      return s;
    }
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

void GaussSeidelSolver::sweep(ConstRef b, VecRef x) {
  const Index n = x.size();
  for (Index r = 0; r < n; ++r) {
    double sum = b[r];
    for (int k = m_csr.row_start[size_t(r)]; k < m_csr.row_start[size_t(r) + 1]; ++k)
      sum -= m_csr.value[size_t(k)] * x[m_csr.col[size_t(k)]];
    const double d = m_A->valuePtr()[m_diag_pos[size_t(r)]];
    x[r] += sum / d;  // sum included the diagonal term d * x_r
  }
}

// ---- Multicolour block Gauss-Seidel ----

LinearSummary ColoredGaussSeidelSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  HOOKE_ASSERT(A.rows() % 3 == 0, "colored-gauss-seidel needs a 3n x 3n matrix");
  m_csr.build(A);
  m_block_pos = linear_detail::block_diagonal_positions(A);
  const int nb = int(A.rows() / 3);
  // Greedy colouring of the block graph in natural order.
  std::vector<int> color(size_t(nb), -1);
  std::vector<int> mark;
  int ncolors = 0;
  for (int i = 0; i < nb; ++i) {
    mark.assign(size_t(ncolors) + 1, 0);
    for (int r = 3 * i; r < 3 * i + 3; ++r)
      for (int k = m_csr.row_start[size_t(r)]; k < m_csr.row_start[size_t(r) + 1]; ++k) {
        const int j = m_csr.col[size_t(k)] / 3;
        if (j != i && color[size_t(j)] >= 0) mark[size_t(color[size_t(j)])] = 1;
      }
    int c = 0;
    while (mark[size_t(c)]) ++c;
    color[size_t(i)] = c;
    ncolors = std::max(ncolors, c + 1);
  }
  m_color_start.assign(size_t(ncolors) + 1, 0);
  for (int i = 0; i < nb; ++i) m_color_start[size_t(color[size_t(i)]) + 1]++;
  for (int c = 0; c < ncolors; ++c) m_color_start[size_t(c) + 1] += m_color_start[size_t(c)];
  m_order.resize(size_t(nb));
  std::vector<int> next(m_color_start.begin(), m_color_start.end() - 1);
  for (int i = 0; i < nb; ++i) m_order[size_t(next[size_t(color[size_t(i)])]++)] = i;
  m_r.setZero(A.rows());
  LinearSummary s;
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary ColoredGaussSeidelSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  m_A = &A;
  m_csr.refresh(A);
  const Index bad = linear_detail::invert_diagonal_blocks(A, m_block_pos, false, m_inv_blocks);
  if (bad >= 0) {
    s.status = Status::BrokeDown;
    s.message = "colored-gauss-seidel: diagonal block " + std::to_string(bad) + " is singular";
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

void ColoredGaussSeidelSolver::sweep(ConstRef b, VecRef x) {
  // One parallel region per sweep with a barrier per colour (not a fork per colour); small
  // systems run serially, where thread synchronisation would cost more than the work.
  const int ncolors = int(m_color_start.size()) - 1;
  const bool parallel = run_parallel(static_cast<long long>(m_order.size()), 4096);
  auto block_row = [&](int k) {
    const int i = m_order[size_t(k)];
    Vec3 r;
    for (int a = 0; a < 3; ++a) {
      const int row = 3 * i + a;
      double sum = b[row];
      for (int q = m_csr.row_start[size_t(row)]; q < m_csr.row_start[size_t(row) + 1]; ++q)
        sum -= m_csr.value[size_t(q)] * x[m_csr.col[size_t(q)]];
      r[a] = sum;  // includes the diagonal block's own contribution
    }
    x.segment<3>(3 * i) += m_inv_blocks[size_t(i)] * r;
  };
  if (parallel) {
#pragma omp parallel
    for (int c = 0; c < ncolors; ++c) {
      const int begin = m_color_start[size_t(c)], end = m_color_start[size_t(c) + 1];
#pragma omp for schedule(static)
      for (int k = begin; k < end; ++k) block_row(k);
    }
  } else {
    for (int k = 0; k < int(m_order.size()); ++k) block_row(k);  // colours in order
  }
}

}  // namespace hooke
