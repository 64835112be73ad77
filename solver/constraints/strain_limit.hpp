#pragma once
#include "hooke/constraints/constraint.hpp"
#include "hooke/forces/spring_set.hpp"

namespace hooke {

/// Provot's strain limiting (Provot 1995, "Deformation constraints in a mass-spring model to
/// describe rigid cloth behavior"): after a step, every spring longer than (1 + max_strain) L is
/// shortened to that length by moving its endpoints towards each other along the spring, half each
/// (all of it on the free end when the other is pinned). Gauss-Seidel passes repeat up to
/// `passes` times or until no spring exceeds the bound. The position change dx is also applied to
/// the velocity as dx / h, so that x1 - x0 = h v1 still holds for the corrected particles.
class StrainLimit final : public Constraint {
 public:
  /// max_strain > 0 (0.1 = 10%); passes >= 1.
  StrainLimit(double max_strain, int passes) : m_max_strain(max_strain), m_passes(passes) {}
  /// Adds a limited spring between a and b with rest length L > 0.
  void add(int a, int b, double L) { m_springs.add(a, b, 0.0, L); }
  size_t size() const { return m_springs.size(); }
  double max_strain() const { return m_max_strain; }
  int passes() const { return m_passes; }
  /// Largest relative elongation (l - L) / L over the limited springs at x (-infinity if none):
  /// above max_strain() when the passes ran out before every spring met the bound.
  double worst_strain(ConstRef x) const;

  const char* name() const override { return "strain-limit"; }
  void project(ConstRef x0, double h, const std::vector<char>& pinned, VecRef x1,
               VecRef v1) const override;

 private:
  SpringSet m_springs;
  double m_max_strain;
  int m_passes;
};

}  // namespace hooke
