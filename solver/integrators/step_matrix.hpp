#pragma once
#include <vector>

#include "hooke/model/mass_spring_system.hpp"

namespace hooke {

/// The Newton matrix of an implicit step, A = M - a D - b K on all 3n DOFs, formed in place over
/// the values of the system's K: a step stores one 3n x 3n matrix (two with a velocity-dependent
/// force, for D) and no reduced copy or index map, which is what lets the largest cloths fit.
///
/// Pinned particles stay in the system as Dirichlet rows: their rows and columns of A are zero
/// except the diagonal, which holds the mass, and their right-hand side is zero (zero_pinned). A
/// is then block diagonal between free and pinned DOFs, so every backend solves exactly the free
/// block M_ff - a D_ff - b K_ff and returns zero on the pinned DOFs; A stays symmetric positive
/// definite whenever that block is.
class StepMatrix {
 public:
  explicit StepMatrix(const MassSpringSystem& system);
  /// K = df/dx and D = df/dv at (x, v) (MassSpringSystem::assemble_jacobians); jacobians() is
  /// valid from here until form().
  void assemble_jacobians(ConstRef x, ConstRef v, const JacobianOptions& options);
  /// The discrete-gradient step's K and D (MassSpringSystem::assemble_discrete_gradient_jacobians).
  void assemble_discrete_gradient_jacobians(ConstRef x0, ConstRef x1, ConstRef xm, ConstRef vm,
                                            const JacobianOptions& options);
  const Jacobians& jacobians() const { return m_J; }
  /// K itself, between assemble_jacobians() and form(), for a caller that adds a term the
  /// system's forces do not hold (barrier contact: ContactNewtonStepper).
  SparseMatrix& stiffness() { return m_J.K; }
  /// A = M - a D - b K over K's values, then the pinned rows and columns. K is gone until the
  /// next assemble_jacobians().
  void form(double a, double b);
  /// A (after form()): 3n x 3n with the system's block pattern, so its arrays never move.
  const SparseMatrix& matrix() const { return m_J.K; }
  /// r(pinned DOFs) = 0.
  void zero_pinned(VecRef r) const;
  /// A += s M (after form()): a multiple of the mass matrix on the diagonal, the shift that makes
  /// an indefinite Newton matrix positive definite (Nocedal and Wright, section 3.4).
  void add_mass_multiple(double s);

 private:
  const MassSpringSystem& m_system;
  Jacobians m_J;
  std::vector<int> m_diag;            // for each DOF: its diagonal entry
  std::vector<int> m_pinned_entries;  // every entry in a pinned particle's row or column
  std::vector<int> m_pinned_dofs;
};

}  // namespace hooke
