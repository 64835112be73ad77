#include "hooke/forces/hooke_spring.hpp"

#include <algorithm>
#include <limits>

namespace hooke {

namespace {
inline Vec3 spring_vector(ConstRef x, int a, int b) {
  return x.segment<3>(3 * a) - x.segment<3>(3 * b);
}
}  // namespace

void HookeSpring::add_forces(ConstRef x, ConstRef /*v*/, VecRef f) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const Vec3 fa = hooke_spring_kernel::force(spring_vector(x, s.i[n], s.j[n]), s.coeff[n],
                                               s.rest_length[n]);
    f.segment<3>(3 * s.i[n]) += fa;
    f.segment<3>(3 * s.j[n]) -= fa;
  });
}

double HookeSpring::potential_energy(ConstRef x) const {
  const SpringSet& s = m_springs;
  double E = 0.0;
  for (size_t n = 0; n < s.size(); ++n) {
    const double dl = spring_vector(x, s.i[n], s.j[n]).norm() - s.rest_length[n];
    E += 0.5 * s.coeff[n] * dl * dl;
  }
  return E;
}

void HookeSpring::add_jacobians(ConstRef x, ConstRef /*v*/, const JacobianOptions& options,
                                SparseMatrix& K, SparseMatrix& /*D*/) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const Mat3 B = hooke_spring_kernel::dfdx(spring_vector(x, s.i[n], s.j[n]), s.coeff[n],
                                             s.rest_length[n], options.clamp_compressed);
    s.add_spring_block(K, n, B);
  });
}

double HookeSpring::max_strain(ConstRef x) const {
  const SpringSet& s = m_springs;
  double m = -std::numeric_limits<double>::infinity();
  for (size_t n = 0; n < s.size(); ++n) {
    const double L = s.rest_length[n];
    if (L <= 0.0) continue;
    m = std::max(m, (spring_vector(x, s.i[n], s.j[n]).norm() - L) / L);
  }
  return m;
}

double HookeSpring::energy_scale() const {
  const SpringSet& s = m_springs;
  double E = 0.0;
  for (size_t n = 0; n < s.size(); ++n) E += 0.5 * s.coeff[n] * s.rest_length[n] * s.rest_length[n];
  return E;
}

}  // namespace hooke
