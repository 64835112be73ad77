#pragma once
#include <memory>
#include <vector>

#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/state.hpp"
#include "hooke/sph/fluid_model.hpp"

namespace hooke {

/// A finalized fluid system and its state at rest.
struct FluidSystem {
  std::unique_ptr<MassSpringSystem> system;
  State state;
};

/// The system of a fluid: the fluid particles (each of mass rho0 dx^d) first, then the boundary
/// particles (pinned, with the same mass for output only; their mass in the SPH sums is
/// FluidModel::boundary_psi), uniform gravity g (m/s^2) when it is not zero, and the fluid model.
/// Velocities start at zero. Throws InternalError for invalid options or no fluid particle.
FluidSystem make_fluid_system(const std::vector<Vec3>& fluid, const std::vector<Vec3>& boundary,
                              const FluidOptions& options, const Vec3& gravity);

}  // namespace hooke
