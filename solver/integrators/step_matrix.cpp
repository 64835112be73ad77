#include "hooke/integrators/step_matrix.hpp"

#include "hooke/parallel/loops.hpp"

namespace hooke {

StepMatrix::StepMatrix(const MassSpringSystem& system)
    : m_system(system), m_J(system.make_jacobians()) {
  const SparseMatrix& K = m_J.K;
  const std::vector<char>& pinned = system.pinned();
  m_diag.assign(size_t(K.cols()), -1);
  for (Index c = 0; c < K.cols(); ++c) {
    const bool pinned_col = pinned[size_t(c / 3)] != 0;
    if (pinned_col) m_pinned_dofs.push_back(int(c));
    for (int k = K.outerIndexPtr()[c]; k < K.outerIndexPtr()[c + 1]; ++k) {
      const int r = K.innerIndexPtr()[k];
      if (r == c) m_diag[size_t(c)] = k;
      if (pinned_col || pinned[size_t(r / 3)]) m_pinned_entries.push_back(k);
    }
  }
  for (const int d : m_diag) HOOKE_ASSERT(d >= 0, "StepMatrix: the pattern lacks a diagonal entry");
}

void StepMatrix::assemble_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options) {
  m_system.assemble_jacobians(x, v, m_J, options);
}

void StepMatrix::assemble_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef xm,
                                                      ConstRef vm, const JacobianOptions& options) {
  m_system.assemble_discrete_gradient_jacobians(x0, x1, xm, vm, m_J, options);
}

void StepMatrix::form(double a, double b) {
  double* A = m_J.K.valuePtr();
  const double* D = m_J.velocity_values();
  const Index nnz = m_J.K.nonZeros();
  // parallel_for branches instead of using an OpenMP if() clause: a region that runs on one
  // thread still makes libgomp allocate (and free) a team, which the step loop must not do.
  if (D == nullptr)  // no velocity-dependent force: D is not stored
    parallel_for(nnz, 65536, [&](long long k) { A[k] *= -b; });
  else
    parallel_for(nnz, 65536, [&](long long k) { A[k] = -a * D[k] - b * A[k]; });
  for (const int k : m_pinned_entries) A[k] = 0.0;
  const Vec& mass = m_system.mass_diagonal();
  for (size_t i = 0; i < m_diag.size(); ++i) A[m_diag[i]] += mass[Index(i)];
}

void StepMatrix::add_mass_multiple(double s) {
  double* A = m_J.K.valuePtr();
  const Vec& mass = m_system.mass_diagonal();
  for (size_t i = 0; i < m_diag.size(); ++i) A[m_diag[i]] += s * mass[Index(i)];
}

void StepMatrix::zero_pinned(VecRef r) const {
  for (const int i : m_pinned_dofs) r[i] = 0.0;
}

}  // namespace hooke
