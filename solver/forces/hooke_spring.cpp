#include "hooke/forces/hooke_spring.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hooke/forces/spring_blocks.hpp"

namespace hooke {

namespace {
inline Vec3 spring_vector(ConstRef x, int a, int b) {
  return x.segment<3>(3 * a) - x.segment<3>(3 * b);
}
}  // namespace

void HookeSpring::add_forces(ConstRef x, ConstRef /*v*/, VecRef f) const {
  const SpringSet& s = m_springs;
  s.for_each_range([&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; b += kSpringBlockChunk)
      spring_blocks::hooke_forces(s, x, b, std::min(end, b + kSpringBlockChunk), f.data());
  });
}

void HookeSpring::add_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef /*xm*/, ConstRef /*vm*/,
                                        VecRef f) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const int a = s.i[n], b = s.j[n];
    const Vec3 fa = hooke_spring_kernel::discrete_gradient(
        spring_vector(x0, a, b), spring_vector(x1, a, b), s.coeff[n], s.rest_length[n]);
    f.segment<3>(3 * a) += fa;
    f.segment<3>(3 * b) -= fa;
  });
}

void HookeSpring::add_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef /*xm*/,
                                                  ConstRef /*vm*/, const JacobianOptions& options,
                                                  SparseMatrix& K, SparseMatrix& /*D*/) const {
  const SpringSet& s = m_springs;
  s.for_each([&](size_t n) {
    const int a = s.i[n], b = s.j[n];
    const Mat3 B = hooke_spring_kernel::discrete_gradient_dfdx(
        spring_vector(x0, a, b), spring_vector(x1, a, b), s.coeff[n], s.rest_length[n],
        options.clamp_compressed);
    s.add_spring_block(K, n, B);
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

namespace {
/// Spring n's df/dx blocks into K.
inline void add_spring_dfdx(const SpringSet& s, size_t n, ConstRef x, bool clamp, SparseMatrix& K) {
  s.add_spring_block(K, n,
                     hooke_spring_kernel::dfdx(spring_vector(x, s.i[n], s.j[n]), s.coeff[n],
                                               s.rest_length[n], clamp));
}
}  // namespace

void HookeSpring::add_jacobians(ConstRef x, ConstRef /*v*/, const JacobianOptions& options,
                                SparseMatrix& K, SparseMatrix& /*D*/) const {
  m_springs.for_each(
      [&](size_t n) { add_spring_dfdx(m_springs, n, x, options.clamp_compressed, K); });
}

void HookeSpring::add_jacobians_of_springs(ConstRef x, ConstRef /*v*/,
                                           const JacobianOptions& options, size_t begin, size_t end,
                                           SparseMatrix& K, SparseMatrix& /*D*/) const {
  for (size_t n = begin; n < end; ++n)
    add_spring_dfdx(m_springs, n, x, options.clamp_compressed, K);
}

int HookeSpring::per_spring_blocks(ConstRef x, ConstRef /*v*/, const JacobianOptions& options,
                                   size_t begin, size_t end, bool add_k, bool /*add_d*/, double* BK,
                                   double* /*BD*/) const {
  spring_blocks::hooke_spring(m_springs, x, options.clamp_compressed, begin, end, add_k, BK);
  return kWroteK;
}

bool HookeSpring::add_jacobian_product(ConstRef x, ConstRef /*v*/, const JacobianOptions& options,
                                       ConstRef p, double /*cv*/, double cx, VecRef y) const {
  // The blocks [[B, -B], [-B, B]] of add_jacobians applied to p: B (p_a - p_b) at a, minus at b.
  // B dp = -k [t dp + (1 - t) u (u . dp)] with t = 1 - L/l (clamped): the block is never formed.
  const SpringSet& s = m_springs;
  const bool clamp = options.clamp_compressed;
  s.for_each([&](size_t n) {
    const int a = s.i[n], b = s.j[n];
    const Vec3 d = spring_vector(x, a, b);
    const Vec3 dp = p.segment<3>(3 * a) - p.segment<3>(3 * b);
    const double l2 = d.squaredNorm(), k = cx * s.coeff[n];
    Vec3 q;
    if (l2 == 0.0) {
      q = -k * dp;  // the surrogate B = -k I of dfdx at l = 0
    } else {
      const double l = std::sqrt(l2);
      double t = 1.0 - s.rest_length[n] / l;
      if (clamp && t < 0.0) t = 0.0;
      q = -k * (t * dp + ((1.0 - t) * d.dot(dp) / l2) * d);
    }
    y.segment<3>(3 * a) += q;
    y.segment<3>(3 * b) -= q;
  });
  return true;
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
