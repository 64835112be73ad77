#include "bench/implicit_operator.hpp"

#include "hooke/parallel/loops.hpp"

namespace hooke {

ImplicitOperator::ImplicitOperator(const MassSpringSystem& system) : m_sys(system) {
  const Index n = system.num_particles();
  for (Index p = 0; p < n; ++p)
    for (int c = 0; c < 3; ++c)
      (system.pinned()[size_t(p)] ? m_pinned : m_free).push_back(int(3 * p + c));
  m_mass.resize(3 * n);
  for (Index p = 0; p < n; ++p) m_mass.segment<3>(3 * p).setConstant(system.masses()[p]);
  m_P.setZero(3 * n);
  m_Y.setZero(3 * n);
  // Probe every force once with zero vectors: a force without the product says so.
  const Vec zero = Vec::Zero(3 * n);
  for (const auto& f : system.forces())
    m_supported = m_supported && f->add_jacobian_product(zero, zero, {}, zero, 0.0, 0.0, m_Y);
  m_Y.setZero();
}

void ImplicitOperator::set(ConstRef x, ConstRef v, double a, double b,
                           const JacobianOptions& options) {
  HOOKE_ASSERT(x.size() == m_P.size() && v.size() == m_P.size(), "ImplicitOperator: sizes");
  m_x = x.data();
  m_v = v.data();
  m_a = a;
  m_b = b;
  m_options = options;
}

void ImplicitOperator::apply(ConstRef p, VecRef y) {
  HOOKE_ASSERT(m_supported, "ImplicitOperator: a force has no matrix-free Jacobian product");
  HOOKE_ASSERT(m_x, "ImplicitOperator: apply before set");
  HOOKE_ASSERT(p.size() == free_dofs() && y.size() == free_dofs(), "ImplicitOperator: sizes");
  const long long nf = static_cast<long long>(m_free.size());
  const int* free = m_free.data();
  // P = p on the free DOFs (pinned stay 0), Y = M P.
  parallel_for(nf, 1 << 16, [&](long long k) {
    m_P[free[k]] = p[k];
    m_Y[free[k]] = m_mass[free[k]] * p[k];
  });
  for (const int d : m_pinned) m_Y[d] = 0.0;  // rows that are dropped; keep them bounded
  const Index n3 = m_P.size();
  const Eigen::Map<const Vec> x(m_x, n3), v(m_v, n3);
  for (const auto& f : m_sys.forces())
    f->add_jacobian_product(x, v, m_options, m_P, -m_a, -m_b, m_Y);
  parallel_for(nf, 1 << 16, [&](long long k) { y[k] = m_Y[free[k]]; });
}

}  // namespace hooke
