#include "hooke/integrators/reduced_matrix.hpp"

#include "hooke/parallel/loops.hpp"

namespace hooke {

ReducedMatrix::ReducedMatrix(const MassSpringSystem& system) {
  const Index N = system.dofs();
  std::vector<int> map(size_t(N), -1);
  for (Index i = 0; i < system.num_particles(); ++i)
    if (!system.pinned()[size_t(i)])
      for (int c = 0; c < 3; ++c) {
        map[size_t(3 * i + c)] = int(m_free.size());
        m_free.push_back(int(3 * i + c));
      }
  const Index nf = Index(m_free.size());
  m_mass.resize(nf);
  for (Index k = 0; k < nf; ++k) m_mass[k] = system.mass_diagonal()[m_free[size_t(k)]];
  // Keep the entries of the full pattern whose row and column are both free; column order and
  // row order within a column are preserved, so A is compressed and sorted.
  const SparseMatrix P = system.pattern().make_matrix();
  std::vector<int> outer(size_t(nf) + 1, 0);
  std::vector<int> inner;
  for (Index cf = 0; cf < nf; ++cf) {
    const int c = m_free[size_t(cf)];
    for (int k = P.outerIndexPtr()[c]; k < P.outerIndexPtr()[c + 1]; ++k) {
      const int r = map[size_t(P.innerIndexPtr()[k])];
      if (r < 0) continue;
      inner.push_back(r);
      m_src.push_back(k);
    }
    outer[size_t(cf) + 1] = int(inner.size());
  }
  m_A.resize(nf, nf);
  m_A.resizeNonZeros(Index(inner.size()));
  std::copy(outer.begin(), outer.end(), m_A.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), m_A.innerIndexPtr());
  std::fill(m_A.valuePtr(), m_A.valuePtr() + inner.size(), 0.0);
  m_diag.assign(size_t(nf), -1);
  for (Index cf = 0; cf < nf; ++cf)
    for (int k = outer[size_t(cf)]; k < outer[size_t(cf) + 1]; ++k)
      if (inner[size_t(k)] == cf) m_diag[size_t(cf)] = k;
}

void ReducedMatrix::assemble(const Jacobians& J, double a, double b) {
  const double* K = J.K.valuePtr();
  const double* D = J.velocity_values();
  double* A = m_A.valuePtr();
  const Index nnz = Index(m_src.size());
  // parallel_for branches instead of using an OpenMP if() clause: a region that runs on one
  // thread still makes libgomp allocate (and free) a team, which the step loop must not do.
  if (D == nullptr)  // no velocity-dependent force: D is not stored
    parallel_for(nnz, 65536, [&](long long k) { A[k] = -b * K[m_src[size_t(k)]]; });
  else
    parallel_for(nnz, 65536,
                 [&](long long k) { A[k] = -a * D[m_src[size_t(k)]] - b * K[m_src[size_t(k)]]; });
  for (size_t i = 0; i < m_diag.size(); ++i) A[m_diag[i]] += m_mass[Index(i)];
}

void ReducedMatrix::gather(ConstRef full, VecRef free) const {
  for (size_t k = 0; k < m_free.size(); ++k) free[Index(k)] = full[m_free[k]];
}

void ReducedMatrix::scatter_add(ConstRef free, VecRef full) const {
  for (size_t k = 0; k < m_free.size(); ++k) full[m_free[k]] += free[Index(k)];
}

}  // namespace hooke
