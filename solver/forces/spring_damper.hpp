#pragma once
#include <cmath>

#include "hooke/forces/force.hpp"
#include "hooke/forces/spring_set.hpp"

namespace hooke {

/// Per-spring kernels of axial (relative-velocity) spring damping with coefficient c (N s/m).
/// With d = x_a - x_b, l = |d|, u = d / l, w = v_a - v_b, P = I - u u^T:
///   force on a   f_a = -c (u . w) u,          f_b = -f_a      (dissipates, no energy)
///   df_a/dv_a    -c u u^T
///   df_a/dx_a    -(c / l) [ u (P w)^T + (u . w) P ]   (not symmetric)
/// and the (a, b) blocks are the negatives. At l = 0 the force and both blocks are zero.
namespace spring_damper_kernel {
// u (u . w) = d (d . w) / l^2: the force and df/dv need no square root and one division.
inline Vec3 force(const Vec3& d, const Vec3& w, double c) {
  const double l2 = d.squaredNorm();
  if (l2 == 0.0) return Vec3::Zero();
  return (-c * d.dot(w) / l2) * d;
}
/// The scalars of both blocks: a = -c / l^2, dw = d . w and e = 2 (d . w) / l^2; all 0 at l = 0,
/// where both blocks vanish.
struct BlockScalars {
  double a = 0.0, dw = 0.0, e = 0.0;
};
inline BlockScalars block_scalars(const Vec3& d, const Vec3& w, double c) {
  const double l2 = d.squaredNorm();
  if (l2 == 0.0) return {};
  const double q = 1.0 / l2, dw = d.dot(w);
  return {-c * q, dw, 2.0 * dw * q};
}
/// a of block_scalars alone (what dfdv needs).
inline double dfdv_scale(const Vec3& d, double c) {
  const double l2 = d.squaredNorm();
  return l2 == 0.0 ? 0.0 : -c * (1.0 / l2);
}
// The blocks entry by entry: an Eigen expression here is evaluated in packets through the stack,
// which stalls on store forwarding.
/// dfdv = a d d^T (exactly symmetric: d_r d_c is one product for (r, c) and (c, r)).
inline Mat3 dfdv_block(const Vec3& d, double a) {
  Mat3 B;
  for (int col = 0; col < 3; ++col)
    for (int r = 0; r < 3; ++r) B(r, col) = a * (d[r] * d[col]);
  return B;
}
/// dfdx = -(c / l) [u (P w)^T + (u . w) P] = a [d w^T - e d d^T + (d . w) I]: no square root.
inline Mat3 dfdx_block(const Vec3& d, const Vec3& w, const BlockScalars& s) {
  Mat3 B;
  for (int col = 0; col < 3; ++col)
    for (int r = 0; r < 3; ++r)
      B(r, col) = s.a * (d[r] * w[col] - s.e * (d[r] * d[col]) + (r == col ? s.dw : 0.0));
  return B;
}
inline Mat3 dfdv(const Vec3& d, double c) { return dfdv_block(d, dfdv_scale(d, c)); }
inline Mat3 dfdx(const Vec3& d, const Vec3& w, double c) {
  return dfdx_block(d, w, block_scalars(d, w, c));
}
/// dfdx(d, w, c) p without forming the block: -(c / l) [u (P w . p) + (u . w) P p].
inline Vec3 dfdx_times(const Vec3& d, const Vec3& w, double c, const Vec3& p) {
  const double l2 = d.squaredNorm();
  if (l2 == 0.0) return Vec3::Zero();
  const double inv_l = 1.0 / std::sqrt(l2);
  const Vec3 u = inv_l * d;
  const double uw = u.dot(w), up = u.dot(p);
  const Vec3 Pw = w - uw * u, Pp = p - up * u;
  return (-c * inv_l) * (Pw.dot(p) * u + uw * Pp);
}
}  // namespace spring_damper_kernel

/// Axial damping along a set of springs (Baraff and Witkin 1998, section 4.2 style damping force
/// along the spring direction).
class SpringDamper final : public Force {
 public:
  /// Adds a damper between particles a != b with coefficient c >= 0 (N s/m).
  void add(int a, int b, double c) { m_springs.add(a, b, c, 0.0); }
  size_t size() const { return m_springs.size(); }
  /// The dampers (coeff = c; rest_length unused).
  const SpringSet& springs() const { return m_springs; }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::Dampers;
    t.springs = &m_springs;
    return t;
  }

  const char* name() const override { return "spring-damper"; }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  void declare_blocks(BlockPattern& p) const override { m_springs.declare(p); }
  void bind(const BlockPattern& p) override { m_springs.bind(p); }
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;
  const SpringSet* jacobian_groups() const override { return &m_springs; }
  void add_jacobians_of_springs(ConstRef x, ConstRef v, const JacobianOptions& options,
                                size_t begin, size_t end, SparseMatrix& K,
                                SparseMatrix& D) const override;
  int per_spring_blocks(ConstRef x, ConstRef v, const JacobianOptions& options, size_t begin,
                        size_t end, bool add_k, bool add_d, double* BK, double* BD) const override;
  bool add_jacobian_product(ConstRef x, ConstRef v, const JacobianOptions& options, ConstRef p,
                            double cv, double cx, VecRef y) const override;

  std::unique_ptr<Force> localize(const LocalIndex& index) const override {
    auto local = std::make_unique<SpringDamper>();
    local->m_springs = m_springs.localize(index);
    return local;
  }

 private:
  SpringSet m_springs;
};

}  // namespace hooke
