#pragma once
#include <vector>

#include "hooke/core.hpp"
#include "hooke/sph/fluid_model.hpp"
#include "hooke/sph/neighbours.hpp"

namespace hooke {

/// IISPH's pressure Poisson equation of one step, assembled as a sparse symmetric positive
/// definite system, so that an exact solution (a direct or Krylov backend of solver/linear/) can
/// be set beside relaxed Jacobi's (iisph.hpp). With q_i = p_i / rho_i^2 and C the 3 nf x nf
/// matrix with (C q)_i = m_i [sum_j m_j (q_i + q_j) gradW_ij + sum_b psi_b q_i gradW_ib] (the
/// pressure force, FluidModel::add_pressure_acceleration = -M^-1 C q), the continuity equation
/// FluidModel::density_change is M^-1 C^T, so IISPH's A p = s reads
///   S q = -M s / h^2,   S = C^T M^-1 C   (symmetric, positive semi-definite).
/// IISPH clamps p >= 0, which makes the problem a linear complementarity problem; here the
/// particles outside `active` are held at p = 0 (the free surface) and the equations of the
/// active ones form the linear system S_AA q_A = (-M s / h^2)_A, positive definite when C_A has
/// full column rank (every active particle has neighbours).
struct PressureSystem {
  std::vector<Index> active;  ///< the fluid particles of the unknowns, in order
  SparseMatrix S;             ///< |active| x |active|, both triangles stored
  Vec rhs;                    ///< |active|
  /// The pressures (Pa, num_fluid entries, 0 off the active set) of a solution q of S q = rhs.
  Vec pressures(ConstRef q, ConstRef rho) const;
};

/// Assembles the system at positions x (3n), masses (n), densities rho and source term
/// s = rho0 - rho* (num_fluid each) of a step of size h, with the neighbours of `search`
/// (updated at x); active: num_fluid flags. Allocates (an analysis tool, not a step).
PressureSystem assemble_pressure_system(const FluidModel& fluid, const NeighbourSearch& search,
                                        ConstRef x, ConstRef masses, ConstRef rho, ConstRef source,
                                        double h, const std::vector<char>& active);

}  // namespace hooke
