#pragma once
#include <algorithm>

#include "hooke/constraints/constraint.hpp"

namespace hooke {

/// Shared contact response of the colliders: given the outward unit normal nrm at the contact,
/// removes the inward normal velocity (perfectly inelastic contact) and applies Coulomb friction
/// to the tangential velocity, reduced by mu times the removed normal speed (Bridson et al. 2002).
inline void contact_velocity(const Vec3& nrm, double mu, Eigen::Ref<Vec3> v) {
  const double vn = v.dot(nrm);
  if (vn >= 0.0) return;
  Vec3 vt = v - vn * nrm;
  const double vt_norm = vt.norm();
  if (vt_norm > 0.0) vt *= std::max(0.0, 1.0 - mu * (-vn) / vt_norm);
  v = vt;
}

/// The half space {x : n . x >= offset} (a ground plane): particles below it are projected back
/// onto the plane and lose their inward normal velocity (with Coulomb friction mu).
class GroundPlane final : public Constraint {
 public:
  /// normal: any nonzero vector (normalised here); offset in metres; friction mu >= 0.
  GroundPlane(const Vec3& normal, double offset, double friction)
      : m_n(normal.normalized()), m_offset(offset), m_mu(friction) {}
  const char* name() const override { return "ground-plane"; }
  void project(ConstRef x0, double h, const std::vector<char>& pinned, VecRef x1,
               VecRef v1) const override;
  /// Particle by particle: the same plane.
  std::unique_ptr<Constraint> localize(const LocalIndex&) const override {
    return std::make_unique<GroundPlane>(*this);
  }

 private:
  Vec3 m_n;
  double m_offset, m_mu;
};

/// A solid sphere: particles inside are projected to its surface along the radial direction and
/// lose their inward normal velocity (with Coulomb friction mu).
class SphereCollider final : public Constraint {
 public:
  SphereCollider(const Vec3& center, double radius, double friction)
      : m_c(center), m_r(radius), m_mu(friction) {}
  const char* name() const override { return "sphere-collider"; }
  void project(ConstRef x0, double h, const std::vector<char>& pinned, VecRef x1,
               VecRef v1) const override;
  /// Particle by particle: the same sphere.
  std::unique_ptr<Constraint> localize(const LocalIndex&) const override {
    return std::make_unique<SphereCollider>(*this);
  }

 private:
  Vec3 m_c;
  double m_r, m_mu;
};

}  // namespace hooke
