#include "hooke/forces/spring_damper.hpp"

namespace hooke {

void SpringDamper::add_forces(ConstRef x, ConstRef v, VecRef f) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const int a = s.i[n], b = s.j[n];
    const Vec3 fa =
        spring_damper_kernel::force(x.segment<3>(3 * a) - x.segment<3>(3 * b),
                                    v.segment<3>(3 * a) - v.segment<3>(3 * b), s.coeff[n]);
    f.segment<3>(3 * a) += fa;
    f.segment<3>(3 * b) -= fa;
  });
}

void SpringDamper::add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options,
                                 SparseMatrix& K, SparseMatrix& D) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const int a = s.i[n], b = s.j[n];
    const Vec3 d = x.segment<3>(3 * a) - x.segment<3>(3 * b);
    const Vec3 w = v.segment<3>(3 * a) - v.segment<3>(3 * b);
    s.add_spring_block(D, n, spring_damper_kernel::dfdv(d, s.coeff[n]));
    if (options.damping_position_terms)
      s.add_spring_block(K, n, spring_damper_kernel::dfdx(d, w, s.coeff[n]));
  });
}

bool SpringDamper::add_jacobian_product(ConstRef x, ConstRef v, const JacobianOptions& options,
                                        ConstRef p, double cv, double cx, VecRef y) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const int a = s.i[n], b = s.j[n];
    const Vec3 d = x.segment<3>(3 * a) - x.segment<3>(3 * b);
    const Vec3 dp = p.segment<3>(3 * a) - p.segment<3>(3 * b);
    const double l2 = d.squaredNorm();
    if (l2 == 0.0) return;  // both blocks are zero at l = 0
    // dfdv dp = -c u (u . dp), without forming the block.
    Vec3 q = (-cv * s.coeff[n] * d.dot(dp) / l2) * d;
    if (options.damping_position_terms) {
      const Vec3 w = v.segment<3>(3 * a) - v.segment<3>(3 * b);
      q += cx * spring_damper_kernel::dfdx_times(d, w, s.coeff[n], dp);
    }
    y.segment<3>(3 * a) += q;
    y.segment<3>(3 * b) -= q;
  });
  return true;
}

}  // namespace hooke
