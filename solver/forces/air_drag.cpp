#include "hooke/forces/air_drag.hpp"

#include "hooke/parallel/loops.hpp"

namespace hooke {

void AirDrag::add_forces(ConstRef /*x*/, ConstRef v, VecRef f) const {
  parallel_for(m_n, 1 << 15,
               [&](long long i) { f.segment<3>(3 * i) -= m_c * (v.segment<3>(3 * i) - m_wind); });
}

void AirDrag::bind(const BlockPattern& p) {
  m_diag.resize(static_cast<size_t>(m_n));
  for (Index i = 0; i < m_n; ++i) m_diag[i] = p.slot(int(i), int(i));
}

void AirDrag::add_jacobians(ConstRef, ConstRef, const JacobianOptions&, SparseMatrix&,
                            SparseMatrix& D) const {
  const Mat3 B = -m_c * Mat3::Identity();
  for (Index i = 0; i < m_n; ++i) add_block(D, m_diag[i], B);
}

bool AirDrag::add_jacobian_product(ConstRef, ConstRef, const JacobianOptions&, ConstRef p,
                                   double cv, double, VecRef y) const {
  y.head(3 * m_n) -= (cv * m_c) * p.head(3 * m_n);  // df/dv = -c I
  return true;
}

}  // namespace hooke
