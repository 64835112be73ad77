#pragma once
#include "hooke/forces/force.hpp"

namespace hooke {

/// Uniform gravity f_i = m_i g with energy -sum_i m_i g . x_i; K = D = 0.
class Gravity final : public Force {
 public:
  /// masses: n vector (kg); g: acceleration (m/s^2).
  Gravity(Vec masses, const Vec3& g) : m_masses(std::move(masses)), m_g(g) {}
  const Vec3& acceleration() const { return m_g; }

  const char* name() const override { return "gravity"; }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::Gravity;
    t.acceleration = m_g;
    return t;
  }
  /// Particle by particle: the local particles' masses, the same g.
  std::unique_ptr<Force> localize(const LocalIndex& index) const override {
    Vec masses(index.num_local());
    for (Index l = 0; l < index.num_local(); ++l) masses[l] = m_masses[index.global[size_t(l)]];
    return std::make_unique<Gravity>(std::move(masses), m_g);
  }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  double potential_energy(ConstRef x) const override;
  bool has_velocity_jacobian() const override { return false; }
  void add_jacobians(ConstRef, ConstRef, const JacobianOptions&, SparseMatrix&,
                     SparseMatrix&) const override {}
  /// Constant force: no Jacobian, nothing to add.
  bool add_jacobian_product(ConstRef, ConstRef, const JacobianOptions&, ConstRef, double, double,
                            VecRef) const override {
    return true;
  }

 private:
  Vec m_masses;
  Vec3 m_g;
};

}  // namespace hooke
