#include "hooke/forces/spring_damper.hpp"

#include <algorithm>

#include "hooke/forces/spring_blocks.hpp"

namespace hooke {

void SpringDamper::add_forces(ConstRef x, ConstRef v, VecRef f) const {
  const SpringSet& s = m_springs;
  s.for_each_range([&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; b += kSpringBlockChunk)
      spring_blocks::damper_forces(s, x, v, b, std::min(end, b + kSpringBlockChunk), f.data());
  });
}

namespace {
/// Damper n's df/dv blocks into D and, with the position terms, its df/dx blocks into K.
inline void add_damper_jacobians(const SpringSet& s, size_t n, ConstRef x, ConstRef v,
                                 bool position_terms, SparseMatrix& K, SparseMatrix& D) {
  const int a = s.i[n], b = s.j[n];
  const Vec3 d = x.segment<3>(3 * a) - x.segment<3>(3 * b);
  s.add_spring_block(D, n, spring_damper_kernel::dfdv(d, s.coeff[n]));
  if (position_terms) {
    const Vec3 w = v.segment<3>(3 * a) - v.segment<3>(3 * b);
    s.add_spring_block(K, n, spring_damper_kernel::dfdx(d, w, s.coeff[n]));
  }
}
}  // namespace

void SpringDamper::add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options,
                                 SparseMatrix& K, SparseMatrix& D) const {
  m_springs.for_each([&](size_t n) {
    add_damper_jacobians(m_springs, n, x, v, options.damping_position_terms, K, D);
  });
}

void SpringDamper::add_jacobians_of_springs(ConstRef x, ConstRef v, const JacobianOptions& options,
                                            size_t begin, size_t end, SparseMatrix& K,
                                            SparseMatrix& D) const {
  for (size_t n = begin; n < end; ++n)
    add_damper_jacobians(m_springs, n, x, v, options.damping_position_terms, K, D);
}

int SpringDamper::per_spring_blocks(ConstRef x, ConstRef v, const JacobianOptions& options,
                                    size_t begin, size_t end, bool add_k, bool add_d, double* BK,
                                    double* BD) const {
  const bool position_terms = options.damping_position_terms;
  spring_blocks::spring_damper(m_springs, x, v, position_terms, begin, end, add_k, add_d, BK, BD);
  return position_terms ? kWroteK | kWroteD : kWroteD;
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
