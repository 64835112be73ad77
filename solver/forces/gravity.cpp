#include "hooke/forces/gravity.hpp"

#include "hooke/parallel/loops.hpp"

namespace hooke {

void Gravity::add_forces(ConstRef /*x*/, ConstRef /*v*/, VecRef f) const {
  parallel_for(m_masses.size(), 1 << 15,
               [&](long long i) { f.segment<3>(3 * i) += m_masses[i] * m_g; });
}

double Gravity::potential_energy(ConstRef x) const {
  double E = 0.0;
  for (Index i = 0; i < m_masses.size(); ++i) E -= m_masses[i] * m_g.dot(x.segment<3>(3 * i));
  return E;
}

}  // namespace hooke
