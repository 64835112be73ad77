#pragma once
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
inline Vec3 force(const Vec3& d, const Vec3& w, double c) {
  const double l = d.norm();
  if (l == 0.0) return Vec3::Zero();
  const Vec3 u = d / l;
  return (-c * u.dot(w)) * u;
}
inline Mat3 dfdv(const Vec3& d, double c) {
  const double l = d.norm();
  if (l == 0.0) return Mat3::Zero();
  const Vec3 u = d / l;
  return -c * (u * u.transpose());
}
inline Mat3 dfdx(const Vec3& d, const Vec3& w, double c) {
  const double l = d.norm();
  if (l == 0.0) return Mat3::Zero();
  const Vec3 u = d / l;
  const Mat3 P = Mat3::Identity() - u * u.transpose();
  return (-c / l) * (u * (P * w).transpose() + u.dot(w) * P);
}
}  // namespace spring_damper_kernel

/// Axial damping along a set of springs (Baraff and Witkin 1998, section 4.2 style damping force
/// along the spring direction).
class SpringDamper final : public Force {
 public:
  /// Adds a damper between particles a != b with coefficient c >= 0 (N s/m).
  void add(int a, int b, double c) { m_springs.add(a, b, c, 0.0); }
  size_t size() const { return m_springs.size(); }

  const char* name() const override { return "spring-damper"; }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  void declare_blocks(BlockPattern& p) const override { m_springs.declare(p); }
  void bind(const BlockPattern& p) override { m_springs.bind(p); }
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;
  bool add_jacobian_product(ConstRef x, ConstRef v, const JacobianOptions& options, ConstRef p,
                            double cv, double cx, VecRef y) const override;

 private:
  SpringSet m_springs;
};

}  // namespace hooke
