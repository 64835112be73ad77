#pragma once
#include <string>
#include <vector>

#include "hooke/forces/element_set.hpp"
#include "hooke/forces/spring_set.hpp"
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// What a whole-step method can take of an element set (forces/element_set.hpp).
enum class ElementNeed {
  None,             ///< no element sets (the method has no path for them yet)
  Energy,           ///< any element set: its energy, gradient and Hessian (vbd)
  Constraint,       ///< element sets of the constraint form k/2 C^2 (xpbd)
  ScalarQuadratic,  ///< element sets of a constant quadratic form (fast-mass-spring)
};

/// The forces of a system as the position-based whole-step methods (fast-mass-spring, xpbd, vbd)
/// see them: Hooke springs (a potential per spring), uniform gravity (constant), linear air drag
/// towards a wind (linear in v) and element sets (a potential per element). Several forces of a
/// kind add up: gravities sum, drags sum their coefficients and average their winds weighted by
/// coefficient.
struct SpringPotentialForces {
  std::vector<const SpringSet*> springs;  ///< the springs of every HookeSpring force
  std::vector<const SpringSet*> dampers;  ///< the dampers of every SpringDamper force (only vbd
                                          ///< takes them; unsupported() refuses them otherwise)
  /// The element sets of every force that has one (Force::terms, ForceForm::Elements), in force
  /// order; only the methods that say so in unsupported() take them.
  std::vector<const ElementSet*> elements;
  /// The Rayleigh damping of element sets (ElementDamping, ForceForm::ElementDampers): the set and
  /// beta (s), in force order; only the methods that take dampers (vbd) take them.
  struct ElementDampers {
    const ElementSet* set;
    double beta;
  };
  std::vector<ElementDampers> element_dampers;
  Vec3 gravity = Vec3::Zero();  ///< total gravity acceleration (m/s^2)
  double drag = 0.0;            ///< total air-drag coefficient c (kg/s per particle)
  Vec3 wind = Vec3::Zero();     ///< c-weighted mean wind velocity (m/s)

  /// Collects the forces of system; it must pass unsupported().
  explicit SpringPotentialForces(const MassSpringSystem& system);
  /// "" if every force of system is one of the three kinds or an element set the method takes
  /// (`elements`), else a message naming the first other force; `method` and `why` are spliced
  /// into it ("xpbd", "... needs each force to be ..."). takes_dampers: the method takes spring
  /// dampers and the element sets' damping too.
  static std::string unsupported(const MassSpringSystem& system, const std::string& method,
                                 const std::string& why, bool takes_dampers = false,
                                 ElementNeed elements = ElementNeed::None);
};

/// Which methods take the element set `set`, for the messages of those that do not: the
/// Force-driven methods and vbd take every set, xpbd and ceres-implicit those with the constraint
/// form, fast-mass-spring those with a constant scalar quadratic form.
std::string element_set_takers(const ElementSet& set);

/// How far s1 (with v1 = (x1 - x0) / h) is from solving the backward-Euler step from s0:
/// max |M (x1 - x0 - h v0) / h^2 - f(x1, v1)| over the free DOFs, relative to the larger of the
/// two terms' maxima (0 for an exact step). `force` is 3n scratch.
double backward_euler_residual(const MassSpringSystem& system, const State& s0, double h,
                               const State& s1, Vec& force);

/// The longest side of the axis-aligned bounding box of the particles at x (3n), or 1 (m) when
/// they all sit at one point: the length the tolerances of the iterative whole-step methods are
/// relative to.
double system_size(ConstRef x);

/// The stopping rule of the iterative whole-step methods (fast-mass-spring, vbd): an iterate x of
/// the step's objective g (grad g = 0 is the backward-Euler step) is accepted once
///
///   e(x) = h^2 max_p |grad_p g(x)|_inf / m_p  <=  tolerance * system_size(x0)
///
/// over the free particles p. The Hessian of g is M/h^2 plus the springs' (and dampers')
/// stiffness, so e is the distance to the exact step that the mass term alone would give: where
/// the stiffness acts like a graph Laplacian (H = M/h^2 + L, L diagonally dominant with
/// non-positive off-diagonal entries) e bounds max |x - x*| exactly, since (M/h^2 + L)^-1 M/h^2
/// is non-negative with unit row sums. On the slow, smooth error modes that stop a linearly
/// converging iteration the bound is tight; on stiff modes it overestimates. Unlike the change per
/// iteration, it does not shrink when the iteration merely contracts slowly.
inline double position_error(const Vec3& gradient, double mass, double h) {
  return h * h * gradient.lpNorm<Eigen::Infinity>() / mass;
}

}  // namespace hooke
