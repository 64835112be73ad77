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
inline Mat3 dfdv(const Vec3& d, double c) {
  const double l2 = d.squaredNorm();
  if (l2 == 0.0) return Mat3::Zero();
  return (-c / l2) * (d * d.transpose());
}
inline Mat3 dfdx(const Vec3& d, const Vec3& w, double c) {
  const double l = d.norm();
  if (l == 0.0) return Mat3::Zero();
  const Vec3 u = (1.0 / l) * d;
  const Mat3 P = Mat3::Identity() - u * u.transpose();
  return (-c / l) * (u * (P * w).transpose() + u.dot(w) * P);
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

  const char* name() const override { return "spring-damper"; }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  void declare_blocks(BlockPattern& p) const override { m_springs.declare(p); }
  void bind(const BlockPattern& p) override { m_springs.bind(p); }
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;
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
