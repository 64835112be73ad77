#pragma once
#include <string>
#include <vector>

#include "hooke/forces/spring_set.hpp"
#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// The forces of a system as the position-based whole-step methods (fast-mass-spring, xpbd) see
/// them: Hooke springs (a potential per spring), uniform gravity (constant) and linear air drag
/// towards a wind (linear in v). Several forces of a kind add up: gravities sum, drags sum their
/// coefficients and average their winds weighted by coefficient.
struct SpringPotentialForces {
  std::vector<const SpringSet*> springs;  ///< the springs of every HookeSpring force
  Vec3 gravity = Vec3::Zero();            ///< total gravity acceleration (m/s^2)
  double drag = 0.0;                      ///< total air-drag coefficient c (kg/s per particle)
  Vec3 wind = Vec3::Zero();               ///< c-weighted mean wind velocity (m/s)

  /// Collects the forces of system; it must pass unsupported().
  explicit SpringPotentialForces(const MassSpringSystem& system);
  /// "" if every force of system is one of the three kinds, else a message naming the first other
  /// force; `method` and `why` are spliced into it ("xpbd", "... needs each force to be ...").
  static std::string unsupported(const MassSpringSystem& system, const std::string& method,
                                 const std::string& why);
};

}  // namespace hooke
