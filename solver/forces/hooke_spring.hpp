#pragma once
#include <algorithm>
#include <cmath>

#include "hooke/forces/force.hpp"
#include "hooke/forces/spring_set.hpp"

namespace hooke {

/// Per-spring kernels of the linear (Hooke) spring between particles a and b with stiffness k and
/// rest length L. With d = x_a - x_b, l = |d|, u = d / l:
///   force on a      f_a = -k (l - L) u,     f_b = -f_a
///   energy          E = k/2 (l - L)^2
///   df_a/dx_a       B = -k [ u u^T + (1 - L/l) (I - u u^T) ]  (Baraff and Witkin 1998)
/// and df_a/dx_b = -B. When l < L the transverse factor (1 - L/l) is negative (the compressed
/// case): B is then indefinite; clamp_compressed replaces the factor by max(0, 1 - L/l).
/// At l = 0 the direction is undefined: the force is zero and B = -k I (finite surrogate).
namespace hooke_spring_kernel {
inline Vec3 force(const Vec3& d, double k, double L) {
  const double l = d.norm();
  if (l == 0.0) return Vec3::Zero();
  return (-k * (l - L) / l) * d;
}
/// The discrete gradient (Gonzalez 1996) of E = k/2 (l - L)^2 between spring vectors d0 and d1:
/// f_a = -[E(l1) - E(l0)] / [(l1^2 - l0^2) / 2] (d0 + d1) / 2 = -k (1 - 2 L / (l0 + l1)) (d0 + d1)
/// / 2, so that f_a . (d1 - d0) = -(E(l1) - E(l0)) exactly; force(d) when d0 = d1.
inline Vec3 discrete_gradient(const Vec3& d0, const Vec3& d1, double k, double L) {
  const double s = d0.norm() + d1.norm();
  if (s == 0.0) return Vec3::Zero();
  return (-0.5 * k * (1.0 - 2.0 * L / s)) * (d0 + d1);
}
/// A symmetric stand-in for 2 d(discrete_gradient)/d(d1), the Newton matrix of the discrete-
/// gradient step. With q = d0 + d1, s = l0 + l1 and w = q / |q|, it is -k [t (I - w w^T) + a w w^T]
/// with transverse factor t = 1 - 2 L / s and axial factor a = t + 2 L |q|^2 / s^3; the exact
/// derivative, -k [t I + (2 L / s^2) q u1^T] / 2, is not symmetric. Both equal dfdx(d) / 2 when
/// d0 = d1 = d. clamp_compressed clamps t and a at 0 (as dfdx clamps its transverse factor), so
/// the block is then negative semi-definite for every pair.
inline Mat3 discrete_gradient_dfdx(const Vec3& d0, const Vec3& d1, double k, double L,
                                   bool clamp_compressed) {
  const double s = d0.norm() + d1.norm();
  if (s == 0.0) return -k * Mat3::Identity();
  const Vec3 q = d0 + d1;
  const double q2 = q.squaredNorm();
  double t = 1.0 - 2.0 * L / s, a = t + 2.0 * L * q2 / (s * s * s);
  if (clamp_compressed) {
    t = std::max(t, 0.0);
    a = std::max(a, 0.0);
  }
  if (q2 == 0.0) return -k * t * Mat3::Identity();
  return -k * (t * Mat3::Identity() + ((a - t) / q2) * (q * q.transpose()));
}
/// dfdx's block as B = s d d^T - kt I: s = -k (1 - t) / l^2 and kt = k t, with t = 1 - L / l
/// (clamped); s = 0 and kt = k at l = 0, where B = -k I. (-k [u u^T + t (I - u u^T)] with
/// u = d / l.)
inline void dfdx_scalars(const Vec3& d, double k, double L, bool clamp_compressed, double& s,
                         double& kt) {
  const double l2 = d.squaredNorm();
  if (l2 == 0.0) {
    s = 0.0;
    kt = k;
    return;
  }
  const double inv_l = 1.0 / std::sqrt(l2);
  double t = 1.0 - L * inv_l;
  if (clamp_compressed && t < 0.0) t = 0.0;
  s = -k * (1.0 - t) * inv_l * inv_l;
  kt = k * t;
}
/// B from dfdx_scalars. d_r d_c is one product for (r, c) and (c, r), so B is exactly symmetric.
/// Entry by entry: an Eigen expression here is evaluated in packets through the stack, which
/// stalls on store forwarding.
inline Mat3 dfdx_block(const Vec3& d, double s, double kt) {
  Mat3 B;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) B(r, c) = s * (d[r] * d[c]) - (r == c ? kt : 0.0);
  return B;
}
inline Mat3 dfdx(const Vec3& d, double k, double L, bool clamp_compressed) {
  double s, kt;
  dfdx_scalars(d, k, L, clamp_compressed, s, kt);
  return dfdx_block(d, s, kt);
}
}  // namespace hooke_spring_kernel

/// A set of linear springs (elastic part only; axial damping is SpringDamper).
class HookeSpring final : public Force {
 public:
  /// Adds a spring between particles a != b with stiffness k >= 0 (N/m) and rest length L >= 0 (m).
  void add(int a, int b, double k, double L) { m_springs.add(a, b, k, L); }
  size_t size() const { return m_springs.size(); }
  const SpringSet& springs() const { return m_springs; }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::Springs;
    t.springs = &m_springs;
    return t;
  }
  /// Multiplies every stiffness by factor >= 0 (a stiffness continuation between steps; call it
  /// through MassSpringSystem::mutable_force so steppers see the change).
  void scale_stiffness(double factor) {
    HOOKE_ASSERT(factor >= 0.0, "scale_stiffness: factor " << factor << " < 0");
    for (double& k : m_springs.coeff) k *= factor;
  }

  const char* name() const override { return "hooke-spring"; }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  void add_discrete_gradient(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                             VecRef f) const override;
  void add_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                                       const JacobianOptions& options, SparseMatrix& K,
                                       SparseMatrix& D) const override;
  double potential_energy(ConstRef x) const override;
  void declare_blocks(BlockPattern& p) const override { m_springs.declare(p); }
  void bind(const BlockPattern& p) override { m_springs.bind(p); }
  bool has_velocity_jacobian() const override { return false; }
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
  double max_strain(ConstRef x) const override;
  double energy_scale() const override;
  std::unique_ptr<Force> localize(const LocalIndex& index) const override {
    auto local = std::make_unique<HookeSpring>();
    local->m_springs = m_springs.localize(index);
    return local;
  }

 private:
  SpringSet m_springs;
};

}  // namespace hooke
