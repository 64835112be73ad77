#pragma once
#include <vector>

#include "hooke/forces/force.hpp"

namespace hooke {

/// Linear air drag relative to a uniform wind: f_i = -c (v_i - w), so D = -c I on every diagonal
/// block and K = 0. With w = 0 it is plain drag; with w != 0 the air pushes the particles towards
/// the wind velocity (the wind force). c in kg/s per particle, w in m/s.
class AirDrag final : public Force {
 public:
  AirDrag(Index num_particles, double c, const Vec3& wind = Vec3::Zero())
      : m_n(num_particles), m_c(c), m_wind(wind) {}

  /// Drag coefficient c (kg/s per particle) and wind velocity w (m/s).
  double coefficient() const { return m_c; }
  const Vec3& wind() const { return m_wind; }
  ForceTerms terms() const override {
    ForceTerms t;
    t.form = ForceForm::Drag;
    t.drag = m_c;
    t.wind = m_wind;
    return t;
  }

  const char* name() const override { return "air-drag"; }
  /// Particle by particle: the same drag over the local particles.
  std::unique_ptr<Force> localize(const LocalIndex& index) const override {
    return std::make_unique<AirDrag>(index.num_local(), m_c, m_wind);
  }
  void add_forces(ConstRef x, ConstRef v, VecRef f) const override;
  void bind(const BlockPattern& p) override;
  void add_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options, SparseMatrix& K,
                     SparseMatrix& D) const override;
  bool add_jacobian_product(ConstRef x, ConstRef v, const JacobianOptions& options, ConstRef p,
                            double cv, double cx, VecRef y) const override;

 private:
  Index m_n;
  double m_c;
  Vec3 m_wind;
  std::vector<BlockSlot> m_diag;
};

}  // namespace hooke
