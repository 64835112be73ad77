#pragma once
#include <vector>

#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// The implicit-step matrix A = M - a D - b K restricted to the free (unpinned) DOFs: pinned
/// particles are removed from the system, not approximated with stiff springs. The pattern and
/// the map from each stored entry of A to its source entry in the system's K and D (which share
/// one pattern) are built once; assemble() then only writes values.
class ReducedMatrix {
 public:
  explicit ReducedMatrix(const MassSpringSystem& system);
  /// A = M_ff - a D_ff - b K_ff with J from system.assemble_jacobians.
  void assemble(const Jacobians& J, double a, double b);
  const SparseMatrix& matrix() const { return m_A; }
  /// Number of free DOFs (rows of A).
  Index free_dofs() const { return Index(m_free.size()); }
  /// free = full restricted to free DOFs.
  void gather(ConstRef full, VecRef free) const;
  /// full(free DOFs) += free; pinned entries untouched.
  void scatter_add(ConstRef free, VecRef full) const;

 private:
  std::vector<int> m_free;  // full DOF index of each free DOF
  std::vector<int> m_src;   // for each stored entry of A: its index in K/D values
  std::vector<int> m_diag;  // for each free DOF: its diagonal entry in A
  Vec m_mass;               // mass of each free DOF
  SparseMatrix m_A;
};

}  // namespace hooke
