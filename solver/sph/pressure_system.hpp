#pragma once
#include <vector>

#include "hooke/core.hpp"
#include "hooke/sph/fluid_model.hpp"
#include "hooke/sph/neighbours.hpp"

namespace hooke {

/// IISPH's pressure Poisson equation of one step, assembled as a sparse matrix, so that an exact
/// solution (a direct solver of solver/linear/) can be set beside relaxed Jacobi's (iisph.hpp).
/// With q_i = p_i / rho_i^2, the pressure force of FluidModel::add_pressure_acceleration is
/// -F q, (F q)_i = m_i [sum_j m_j (q_i + q_j) gradW_ij + (q_i + sum_j w_ij rho_j^2 q_j / rho0^2)
/// sum_b psi_b gradW_ib] (the walls at the Shepard average of the pressures around i, weights
/// w_ij = W_ij / sum_k W_ik over i and its fluid neighbours), and the continuity equation
/// FluidModel::density_change is M^-1 E^T, where E is F without the walls' Shepard term (the
/// walls take part as fluid at rest). IISPH's A p = s then reads
///   S q = -M s / h^2,   S = E^T M^-1 F,
/// square and, because the walls push harder than they are pushed into, not symmetric (without
/// walls it is the symmetric positive semi-definite C^T M^-1 C). IISPH clamps p >= 0, which makes
/// the problem a linear complementarity problem; here the particles outside `active` are held at
/// p = 0 (the free surface) and the equations of the active ones form the linear system
/// S_AA q_A = (-M s / h^2)_A, nonsingular when every active particle has neighbours. Solve it
/// with a direct factorisation, or by CHOLMOD through the normal equations S^T S q = S^T b.
struct PressureSystem {
  std::vector<Index> active;  ///< the fluid particles of the unknowns, in order
  SparseMatrix S;             ///< |active| x |active|, not symmetric
  Vec rhs;                    ///< |active|
  /// The pressures (Pa, num_fluid entries, 0 off the active set) of a solution q of S q = rhs.
  Vec pressures(ConstRef q, ConstRef rho) const;
};

/// Assembles the system at positions x (3n), masses (n), densities rho and source term
/// s = rho0 - rho* (num_fluid each) of a step of size h, with the neighbours of `search`
/// (updated at x); active: num_fluid flags; scale: the pressure forces' gradient scale
/// (SphStepper::gradient_scale), which F carries. Allocates (an analysis tool, not a step).
PressureSystem assemble_pressure_system(const FluidModel& fluid, const NeighbourSearch& search,
                                        ConstRef x, ConstRef masses, ConstRef rho, ConstRef source,
                                        double h, const std::vector<char>& active,
                                        double scale = 1.0);

}  // namespace hooke
