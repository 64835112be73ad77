#include "hooke/linear/cholmod/nodal_preconditioner.hpp"

#include <algorithm>
#include <string>

namespace hooke {

namespace {
CholmodOptions metis() {
  CholmodOptions o;
  o.ordering = hooke::CholmodOrdering::Metis;  // nested dissection: the least fill on cloth grids
  return o;
}
}  // namespace

NodalPreconditioner::NodalPreconditioner() : m_chol(metis()) {}
NodalPreconditioner::~NodalPreconditioner() = default;

LinearSummary NodalPreconditioner::analyze(const SparseMatrix& A) {
  LinearSummary s;
  if (A.rows() != A.cols() || A.rows() % 3 != 0) {
    s.status = Status::Fatal;
    s.message = "nodal: A is " + std::to_string(A.rows()) + " x " + std::to_string(A.cols()) +
                "; needs a square matrix of 3 x 3 particle blocks";
    return s;
  }
  const Index n = A.rows() / 3;
  // N's pattern: block (p, q) of A holds an entry on its diagonal (row 3p + c, column 3q + c).
  std::vector<Eigen::Triplet<double, int>> t;
  for (Index j = 0; j < A.cols(); ++j)
    for (SparseMatrix::InnerIterator it(A, j); it; ++it)
      if (it.row() % 3 == j % 3) t.emplace_back(int(it.row() / 3), int(j / 3), 0.0);
  m_N.resize(n, n);
  m_N.setFromTriplets(t.begin(), t.end());  // duplicates (the three coordinates) sum to 0
  m_N.makeCompressed();
  m_from.assign(size_t(m_N.nonZeros()), {-1, -1, -1});
  for (Index j = 0; j < A.cols(); ++j) {
    const Index q = j / 3;
    const int* begin = m_N.innerIndexPtr() + m_N.outerIndexPtr()[q];
    const int* end = m_N.innerIndexPtr() + m_N.outerIndexPtr()[q + 1];
    for (Index k = A.outerIndexPtr()[j]; k < A.outerIndexPtr()[j + 1]; ++k) {
      const Index i = A.innerIndexPtr()[k];
      if (i % 3 != j % 3) continue;
      const int* at = std::lower_bound(begin, end, int(i / 3));
      m_from[size_t(at - m_N.innerIndexPtr())][size_t(j % 3)] = k;
    }
  }
  s = m_chol.analyze(m_N);
  if (s.status == Status::Converged)
    s.message.clear();
  else
    s.message = "nodal: " + s.message;
  return s;
}

LinearSummary NodalPreconditioner::factor(const SparseMatrix& A) {
  const double* a = A.valuePtr();
  double* v = m_N.valuePtr();
  for (size_t e = 0; e < m_from.size(); ++e) {
    double sum = 0.0;
    for (const Index k : m_from[e]) sum += k >= 0 ? a[k] : 0.0;
    v[e] = sum / 3.0;
  }
  LinearSummary s = m_chol.factor(m_N);
  if (s.status != Status::Converged) s.message = "nodal: " + s.message;
  return s;
}

LinearSummary NodalPreconditioner::solve(ConstRef b, VecRef x,
                                         const LinearSolveOptions& /*options*/) {
  HOOKE_ASSERT(b.size() == 3 * m_N.rows() && x.size() == b.size(),
               "nodal: solve sizes " << b.size() << ", " << x.size() << " for n = " << m_N.rows());
  return m_chol.solve_interleaved(b.data(), x.data(), 3);
}

}  // namespace hooke
